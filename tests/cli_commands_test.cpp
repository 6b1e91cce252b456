// The r1 command end to end: hash, info, convert, export --ply (R1-HASH-010, R1-IN-006, R1-IN-060,
// R1-RND-095).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;
using r1::test::run_cli;

fs::path good(const std::string& name) { return r1::test::source_dir() / "tests/good_input" / name; }

nlohmann::json info_json(const std::vector<std::string>& extra) {
  std::vector<std::string> args = {"info", "--json"};
  args.insert(args.end(), extra.begin(), extra.end());
  const auto r = run_cli(args);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return nlohmann::json::parse(r.out);
}

TEST(CliHash, PlainAndTreeVectorsFromStdinAndFile) {
  const auto v = nlohmann::json::parse(r1::test::read_file(r1::test::source_dir() / "tests/data/hemera_vectors.json"));
  const std::string hello = "hello";
  auto r = run_cli({"hash", "-"}, &hello);
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(r.out, v["hash"]["hello"].get<std::string>() + "\n");
  r = run_cli({"hash", "--tree", "-"}, &hello);
  EXPECT_EQ(r.out, v["tree"]["hello"].get<std::string>() + "\n");
  r1::test::TempDir d;
  r1::test::write_file(d / "zeros", std::string(4096, '\0'));
  r = run_cli({"hash", "--tree", (d / "zeros").string()});
  EXPECT_EQ(r.out, v["tree"]["4k_zeros"].get<std::string>() + "\n");
  r1::test::write_file(d / "empty", "");
  r = run_cli({"hash", (d / "empty").string(), (d / "zeros").string()});
  EXPECT_EQ(r.out.substr(0, 64), v["hash"]["empty"].get<std::string>());
  EXPECT_NE(r.out.find("  " + (d / "zeros").string() + "\n"), std::string::npos);
}

TEST(CliInfo, EdgeListWithCrlfBomHeaderAndSelfLoop) {
  const auto j = info_json({good("crlf_bom_header.tsv").string()});
  EXPECT_EQ(j["particles"], 3);  // "alpha beta", gamma, delta
  EXPECT_EQ(j["links"], 4);
  EXPECT_EQ(j["self_loops_dropped"], 1);
  EXPECT_EQ(j["components"], 1);
  EXPECT_EQ(j["largest_component"], 3);
  EXPECT_EQ(j["anchor"], 3);
  EXPECT_EQ(j["digest"].get<std::string>().size(), 64u);
  EXPECT_EQ(j["degree"]["min"], 2);
  EXPECT_EQ(j["degree"]["max"], 2);
}

TEST(CliInfo, QuotedCsvAndSymmetricMatrixMarket) {
  auto j = info_json({good("quoted.csv").string()});
  EXPECT_EQ(j["particles"], 5);
  EXPECT_EQ(j["links"], 3);
  EXPECT_EQ(j["components"], 2);
  j = info_json({good("symmetric.mtx").string()});
  // 1-1 is a self-loop kept once, 3-2 is an explicit zero, three off-diagonal entries give 6 links.
  EXPECT_EQ(j["particles"], 4);
  EXPECT_EQ(j["links"], 7);
  EXPECT_EQ(j["self_loops_dropped"], 1);
  EXPECT_EQ(j["pairs"], 3);
  EXPECT_EQ(j["components"], 1);
}

TEST(CliConvert, EdgeListToGraphKeepsTheDigest) {
  r1::test::TempDir d;
  const auto r = run_cli({"convert", good("crlf_bom_header.tsv").string(), (d / "x.graph").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto a = info_json({good("crlf_bom_header.tsv").string()});
  const auto b = info_json({(d / "x.graph").string()});
  EXPECT_EQ(a["digest"], b["digest"]);
  EXPECT_EQ(a["particles"], b["particles"]);
  EXPECT_EQ(b["titles"], 0);
  // Converting the .graph again gives the same bytes, and so does a .tsv round trip.
  ASSERT_EQ(run_cli({"convert", (d / "x.graph").string(), (d / "y.graph").string()}).exit_code, 0);
  EXPECT_EQ(r1::test::read_file(d / "x.graph"), r1::test::read_file(d / "y.graph"));
  ASSERT_EQ(run_cli({"convert", good("crlf_bom_header.tsv").string(), (d / "x.tsv").string()}).exit_code, 0);
  EXPECT_EQ(info_json({(d / "x.tsv").string()})["digest"], a["digest"]);
}

TEST(CliConvert, GraphRoundTripIsByteIdentical) {
  r1::test::TempDir d;
  const auto src = good("extension_section.graph");
  const auto r = run_cli({"convert", src.string(), (d / "copy.graph").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r1::test::read_file(src), r1::test::read_file(d / "copy.graph"));
}

TEST(CliConvert, TitlesSideFileIsEmbedded) {
  r1::test::TempDir d;
  r1::test::write_file(d / "titles.tsv", "gamma\tThe Gamma\nnobody\tignored\n");
  ASSERT_EQ(run_cli({"convert", good("crlf_bom_header.tsv").string(), (d / "t.graph").string(), "--titles",
                     (d / "titles.tsv").string()})
                .exit_code,
            0);
  EXPECT_EQ(info_json({(d / "t.graph").string()})["titles"], 1);
  EXPECT_NE(r1::test::read_file(d / "t.graph").find("The Gamma"), std::string::npos);
}

TEST(CliConvert, GraphWithoutNamesCannotBecomeAnEdgeList) {
  r1::test::TempDir d;
  const auto r = run_cli({"convert", good("extension_section.graph").string(), (d / "x.tsv").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("no names"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(d / "x.tsv"));
}

TEST(CliExport, PlyIsWrittenAtomically) {
  r1::test::TempDir d;
  ASSERT_EQ(run_cli({"gen", "grid", "--dims", "6x5", "-o", (d / "g.graph").string()}).exit_code, 0);
  ASSERT_EQ(run_cli({"epoch", (d / "g.graph").string(), "-q", "-o", (d / "e").string()}).exit_code, 0);
  auto r = run_cli({"export", (d / "e").string(), "--ply", (d / "e.ply").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string ply = r1::test::read_file(d / "e.ply");
  EXPECT_EQ(ply.substr(0, 4), "ply\n");
  EXPECT_NE(ply.find("element vertex 30\n"), std::string::npos);
  // Both outputs at once give the same .ply; neither is an input error (exit 2).
  r = run_cli({"export", (d / "e").string(), "--tsv", (d / "e.tsv").string(), "--ply", (d / "f.ply").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r1::test::read_file(d / "f.ply"), ply);
  EXPECT_TRUE(fs::exists(d / "e.tsv"));
  EXPECT_EQ(run_cli({"export", (d / "e").string()}).exit_code, 2);
  // A target whose directory does not exist: exit 3 (output refused), nothing written.
  r1::test::write_file(d / "plain", "");
  const fs::path bad = d / "plain" / "x.ply";
  r = run_cli({"export", (d / "e").string(), "--ply", bad.string()});
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
  EXPECT_FALSE(fs::exists(bad));
}

}  // namespace
