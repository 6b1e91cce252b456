// Suites whose graphs are snapshot files (spec/conformance.md R1-CONF-006, 007, 043, 044): a
// golden set of one's own graph is written, copied and checked; a changed, missing, malformed or
// escaping file is a one-line input error naming the suite file, the line and the graph entry,
// before anything is computed or written.
#include <gtest/gtest.h>

#include <algorithm>
#include <nlohmann/json.hpp>

#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;
using r1::test::run_cli;

// The 16 views of the small suite, taken from its file so this suite stays valid when they change.
std::string small_views() {
  const std::string small = r1::test::read_file(r1::test::source_dir() / "spec/suites/small.toml");
  const auto at = small.find("[[view]]");
  EXPECT_NE(at, std::string::npos);
  return small.substr(at);
}

// A suite of two graphs: `file_line` (a snapshot graph, [[graph]] on line 6) and a generator's.
std::string suite_text(const std::string& file_line) {
  return "# a suite of one's own graph\n"
         "name = \"mine\"\n"
         "width = 48\n"
         "height = 27\n"
         "\n"
         "[[graph]]\n"
         "name = \"friends\"\n" +
         file_line +
         "\n"
         "titles = \"graphs/friends.titles.tsv\"\n"
         "\n"
         "[[graph]]\n"
         "name = \"ring\"\n"
         "gen = \"ring --n 16\"\n\n" +
         small_views();
}

constexpr const char* kEdges =
    "# friends\nalice\tbob\nbob\tcarol\ncarol\talice\ncarol\tdave\ndave\terin\nerin\tfrank\nfrank\tdave\nalice\tdave\t2\n";

// DIR/my.toml with its graph files under DIR/graphs/.
fs::path make_suite(const fs::path& dir, const std::string& file_line = "file = \"graphs/friends.tsv\"") {
  fs::create_directories(dir / "graphs");
  r1::test::write_file(dir / "graphs/friends.tsv", kEdges);
  r1::test::write_file(dir / "graphs/friends.titles.tsv", "alice\tAlice A.\n");
  r1::test::write_file(dir / "my.toml", suite_text(file_line));
  return dir / "my.toml";
}

std::size_t lines(const std::string& s) { return static_cast<std::size_t>(std::count(s.begin(), s.end(), '\n')); }

// R1-CONF-043: the set holds the file at its suite path, the manifest its path, byte digest and
// snapshot digest (the digest `r1 info` gives), and the set checks clean.
TEST(CliGoldenFiles, ASnapshotGraphMakesAGoldenSetThatChecks) {
  r1::test::TempDir d;
  const fs::path suite = make_suite(d.path());
  const fs::path g = d / "golden";
  const auto w = run_cli({"golden", "--suite", suite.string(), "-o", g.string()});
  ASSERT_EQ(w.exit_code, 0) << w.out << w.err;
  EXPECT_EQ(r1::test::read_file(g / "graphs/friends.tsv"), kEdges);
  EXPECT_EQ(r1::test::read_file(g / "graphs/friends.titles.tsv"), "alice\tAlice A.\n");
  EXPECT_EQ(r1::test::read_file(g / "suite.toml"), r1::test::read_file(suite));
  const auto m = nlohmann::json::parse(r1::test::read_file(g / "manifest.json"));
  const auto& friends = m.at("graphs").at(0);
  const auto info = run_cli({"info", "--json", (d / "graphs/friends.tsv").string()});
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_EQ(friends.at("snapshot_digest"), nlohmann::json::parse(info.out).at("digest"));
  EXPECT_EQ(friends.at("snapshot_file").at("file"), "graphs/friends.tsv");
  const auto hash = run_cli({"hash", (d / "graphs/friends.tsv").string()});
  EXPECT_EQ(friends.at("snapshot_file").at("digest").get<std::string>(), hash.out.substr(0, 64));
  EXPECT_EQ(friends.at("titles_file").at("file"), "graphs/friends.titles.tsv");
  EXPECT_FALSE(friends.contains("gen"));
  EXPECT_EQ(m.at("graphs").at(1).at("gen"), "ring --n 16");
  EXPECT_FALSE(m.at("graphs").at(1).contains("snapshot_file"));
  EXPECT_EQ(friends.at("particles"), 6);

  // The set is self-contained: moved elsewhere, without the original, it still checks.
  fs::rename(g, d / "moved");
  fs::remove_all(d / "graphs");
  const auto c = run_cli({"golden", "--check", (d / "moved").string()});
  EXPECT_EQ(c.exit_code, 0) << c.out << c.err;
  EXPECT_NE(c.out.find("2 of 2 graphs reproduce"), std::string::npos) << c.out;
  const auto conform = run_cli({"conform", "--backend", "reference", "--golden", (d / "moved").string(), "--checks",
                                "topo,pos,pix", "-o", (d / "c.toml").string()});
  EXPECT_EQ(conform.exit_code, 0) << conform.out << conform.err;
}

// R1-CONF-044: one byte of the copy changed is caught by its digest before any epoch runs; with the
// manifest's byte digest forged to match, the snapshot digest still catches it.
TEST(CliGoldenFiles, AnEditedSnapshotCopyFailsOnItsDigest) {
  r1::test::TempDir d;
  const fs::path g = d / "golden";
  ASSERT_EQ(run_cli({"golden", "--suite", make_suite(d.path()).string(), "-o", g.string()}).exit_code, 0);
  std::string edges = kEdges;
  edges[edges.find("frank")] = 'F';  // a particle renamed: another snapshot
  r1::test::write_file(g / "graphs/friends.tsv", edges);
  auto r = run_cli({"golden", "--check", g.string()});
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.err.find((g / "suite.toml").string() + ":6: graph 'friends': graphs/friends.tsv: digest does not match the manifest"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  EXPECT_EQ(r.out.find("particles"), std::string::npos) << "computed before checking:\n" << r.out;

  std::string manifest = r1::test::read_file(g / "manifest.json");
  const std::string old_digest = nlohmann::json::parse(manifest)["graphs"][0]["snapshot_file"]["digest"];
  const auto hash = run_cli({"hash", (g / "graphs/friends.tsv").string()});
  manifest.replace(manifest.find(old_digest), 64, hash.out.substr(0, 64));
  r1::test::write_file(g / "manifest.json", manifest);
  r = run_cli({"golden", "--check", g.string()});
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.err.find("graph 'friends': graphs/friends.tsv: snapshot digest"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("does not match the manifest's"), std::string::npos) << r.err;
  EXPECT_EQ(lines(r.err), 1u) << r.err;

  // A side file is held to its digest too: titles change the labels drawn.
  ASSERT_EQ(run_cli({"golden", "--suite", (d / "my.toml").string(), "-o", g.string()}).exit_code, 0);
  r1::test::write_file(g / "graphs/friends.titles.tsv", "alice\tAlice B.\n");
  r = run_cli({"golden", "--check", g.string()});
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.err.find("graph 'friends': graphs/friends.titles.tsv: digest does not match the manifest"), std::string::npos)
      << r.err;
}

// A missing file: one line naming the suite file, line and entry; nothing written, for golden -o,
// golden --check and conform alike.
TEST(CliGoldenFiles, AMissingSnapshotFileIsAOneLineError) {
  r1::test::TempDir d;
  const fs::path suite = make_suite(d.path());
  const fs::path g = d / "golden";
  ASSERT_EQ(run_cli({"golden", "--suite", suite.string(), "-o", g.string()}).exit_code, 0);
  fs::remove(g / "graphs/friends.tsv");
  auto r = run_cli({"golden", "--check", g.string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find((g / "suite.toml").string() + ":6: graph 'friends': file: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("graphs/friends.tsv: cannot open"), std::string::npos) << r.err;
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  r = run_cli({"conform", "--backend", "reference", "--golden", g.string(), "-o", (d / "c.toml").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("graph 'friends': file: "), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(d / "c.toml"));

  fs::remove(d / "graphs/friends.tsv");
  r = run_cli({"golden", "--suite", suite.string(), "-o", (d / "other").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(suite.string() + ":6: graph 'friends': file: "), std::string::npos) << r.err;
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  EXPECT_FALSE(fs::exists(d / "other"));
}

// A malformed file is the reader's own error (file and line), placed at the suite entry.
TEST(CliGoldenFiles, AMalformedSnapshotFileNamesTheEntryAndTheLine) {
  r1::test::TempDir d;
  const fs::path suite = make_suite(d.path());
  r1::test::write_file(d / "graphs/friends.tsv", "alice\tbob\nbob\tcarol\tmany\n");
  const auto r = run_cli({"conform", "--backend", "reference", "--suite", suite.string(), "-o", (d / "c.toml").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(suite.string() + ":6: graph 'friends': "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("friends.tsv:2: "), std::string::npos) << r.err;
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  EXPECT_FALSE(fs::exists(d / "c.toml"));
}

// R1-CONF-007: a path that leaves the suite's directory (absolute, '..') is refused even when the
// file is there, since a golden set could not hold it at that path; so are '.', empty names and
// backslashes, and the names of the set's own files.
TEST(CliGoldenFiles, APathOutsideTheSuiteDirectoryIsRefused) {
  r1::test::TempDir d;
  const fs::path inner = d / "suite";
  make_suite(inner);
  r1::test::write_file(d / "friends.tsv", kEdges);  // reachable by "../friends.tsv", refused all the same
  for (const std::string& path : {std::string("../friends.tsv"), (d / "friends.tsv").string(),
                                  std::string("graphs/../graphs/friends.tsv"), std::string("./graphs/friends.tsv"),
                                  std::string("graphs//friends.tsv"), std::string("graphs\\\\friends.tsv")}) {
    r1::test::write_file(inner / "my.toml", suite_text("file = \"" + path + "\""));
    const auto r = run_cli({"golden", "--suite", (inner / "my.toml").string(), "-o", (d / "out").string()});
    EXPECT_EQ(r.exit_code, 2) << path << r.out;
    EXPECT_NE(r.err.find(":6: graph 'friends': file: '"), std::string::npos) << path << r.err;
    EXPECT_NE(r.err.find("R1-CONF-007"), std::string::npos) << path << r.err;
    EXPECT_FALSE(fs::exists(d / "out")) << path;
  }
  r1::test::write_file(inner / "manifest.json", kEdges);
  r1::test::write_file(inner / "my.toml", suite_text("file = \"manifest.json\""));
  auto r = run_cli({"golden", "--suite", (inner / "my.toml").string(), "-o", (d / "out").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("'manifest.json' is the name of a golden set's own file"), std::string::npos) << r.err;
  // The rule is the path's, not the file's: the same graph below the directory is accepted.
  r1::test::write_file(inner / "my.toml", suite_text("file = \"graphs/friends.tsv\""));
  r = run_cli({"golden", "--suite", (inner / "my.toml").string(), "-o", (d / "out").string()});
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

// An entry is a generator or a file, not both, and a file graph's keys are strings.
TEST(CliGoldenFiles, AnEntryIsAGeneratorOrAFile) {
  r1::test::TempDir d;
  const fs::path suite = make_suite(d.path(), "file = \"graphs/friends.tsv\"\ngen = \"ring --n 8\"");
  auto r = run_cli({"golden", "--suite", suite.string(), "-o", (d / "out").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(":6: graph 'friends': expected exactly one of gen"), std::string::npos) << r.err;
  make_suite(d.path(), "file = \"graphs/friends.tsv\"\nformat = \"xls\"");
  r = run_cli({"golden", "--suite", suite.string(), "-o", (d / "out").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("format: 'xls' is not one of graph, tsv, csv, mtx"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(d / "out"));
}

}  // namespace
