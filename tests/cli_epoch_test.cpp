// `r1 epoch` and `r1 export` end to end: reproducible directories, the TSV table, small and
// disconnected graphs, bad options and inputs (R1-EPO-010..020, R1-ERR-001..003).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <algorithm>
#include <cstring>
#include <sstream>

#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;
using r1::test::run_cli;

// A generated snapshot in `dir`; returns its path.
fs::path gen(const fs::path& dir, const std::vector<std::string>& kind_and_options) {
  std::vector<std::string> args = {"gen"};
  args.insert(args.end(), kind_and_options.begin(), kind_and_options.end());
  const fs::path out = dir / "g.graph";
  args.push_back("-o");
  args.push_back(out.string());
  const auto r = run_cli(args);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return out;
}

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> v;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) v.push_back(l);
  return v;
}

// Asserts the failure contract: exit `code` (2 bad input, 3 output refused), one line on stderr starting "r1: " and holding
// `fragment`, nothing on stdout.
void expect_one_line_error(const r1::test::CliResult& r, const std::string& fragment, int code = 2) {
  EXPECT_EQ(r.exit_code, code) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
  ASSERT_FALSE(r.err.empty());
  EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << "more than one line: " << r.err;
  EXPECT_EQ(r.err.rfind("r1: ", 0), 0u) << r.err;
  EXPECT_NE(r.err.find(fragment), std::string::npos) << "expected '" << fragment << "' in: " << r.err;
}

TEST(CliEpoch, TwoRunsWithoutTimingsAreByteIdentical) {
  r1::test::TempDir d;
  const auto g = gen(d.path(), {"sbm", "--sizes", "120,80,50", "--p-in", "0.2", "--p-out", "0.01"});
  for (const char* name : {"a", "b"}) {
    const auto r = run_cli({"epoch", g.string(), "--no-timings", "-o", (d / name).string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("particles          250"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("clusters           level 0: "), std::string::npos) << r.out;
  }
  std::size_t files = 0;
  for (const auto& e : fs::directory_iterator(d / "a")) {
    ++files;
    const auto other = d / "b" / e.path().filename();
    EXPECT_EQ(r1::test::read_file(e.path()), r1::test::read_file(other)) << e.path().filename();
  }
  EXPECT_EQ(files, 23u);  // R1-EPO-011: 22 files (betweenness.f64 with role shapes, heat.q32, image.i128, records.chunks, files.chunks) + manifest.json
  const auto m = nlohmann::json::parse(r1::test::read_file(d / "a/manifest.json"));
  EXPECT_EQ(m["eigenvalues"].size(), 6u);
  EXPECT_EQ(m["residuals"].size(), 6u);
  for (const auto& res : m["residuals"]) EXPECT_LE(res.get<double>(), 1e-8);
  EXPECT_FALSE(m.contains("timings_s"));
  EXPECT_GT(m["scale"].get<double>(), 0);
}

TEST(CliEpoch, ExportWritesOneRowPerParticleWithTheDocumentedHeader) {
  r1::test::TempDir d;
  const auto g = gen(d.path(), {"grid", "--dims", "9x7"});
  ASSERT_EQ(run_cli({"epoch", g.string(), "-q", "-o", (d / "e").string()}).exit_code, 0);
  const auto r = run_cli({"export", (d / "e").string(), "--tsv", (d / "e.tsv").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto rows = lines(r1::test::read_file(d / "e.tsv"));
  ASSERT_EQ(rows.size(), 1u + 63u);
  EXPECT_EQ(rows[0],
            "particle\ttitle\tx\ty\tz\tu5\tu6\tfocus\tradius\tluminosity\thue\tsaturation\trole\tcluster0\tcluster1\tcluster2\tcluster3");
  for (std::size_t i = 1; i < rows.size(); ++i) {
    EXPECT_EQ(std::count(rows[i].begin(), rows[i].end(), '\t'), 16) << rows[i];
    EXPECT_EQ(rows[i].find('\t'), 64u) << rows[i];
  }
  // `--tsv -` prints the same table.
  const auto out = run_cli({"export", (d / "e").string(), "--tsv", "-"});
  ASSERT_EQ(out.exit_code, 0) << out.err;
  EXPECT_EQ(out.out, r1::test::read_file(d / "e.tsv"));
}

// R1-NRF-030: `r1 epoch` trains the neural field by default (here with fewer steps), lists it in
// the manifest and reads it back for `r1 render --field neural`; --no-field leaves it out.
TEST(CliEpoch, TrainsTheNeuralFieldUnlessTold) {
  r1::test::TempDir d;
  const auto g = gen(d.path(), {"grid", "--dims", "9x7"});
  const auto r = run_cli({"epoch", g.string(), "--field-steps", "4", "-o", (d / "e").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("field "), std::string::npos) << "the field's stage time: " << r.out;
  ASSERT_TRUE(std::filesystem::exists(d / "e" / "field.nrf"));
  const auto m = nlohmann::json::parse(r1::test::read_file(d / "e" / "manifest.json"));
  EXPECT_TRUE(m["files"].contains("field.nrf"));
  const auto far = run_cli({"render", (d / "e").string(), "--distance", "2000000", "--size", "64x36", "--field", "neural", "-o",
                            (d / "far.png").string()});
  ASSERT_EQ(far.exit_code, 0) << far.err;
  EXPECT_NE(far.out.find("field: neural"), std::string::npos) << far.out;
  ASSERT_EQ(run_cli({"epoch", g.string(), "--no-field", "-q", "-o", (d / "plain").string()}).exit_code, 0);
  EXPECT_FALSE(std::filesystem::exists(d / "plain" / "field.nrf"));
  EXPECT_FALSE(nlohmann::json::parse(r1::test::read_file(d / "plain" / "manifest.json"))["files"].contains("field.nrf"));
}

TEST(CliEpoch, TinyAndDisconnectedGraphs) {
  r1::test::TempDir d;
  // Three particles: only two non-trivial eigenvectors exist; the missing coordinates are 0.
  r1::test::write_file(d / "tiny.tsv", "a\tb\nb\tc\n");
  auto r = run_cli({"epoch", (d / "tiny.tsv").string(), "-o", (d / "tiny").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // Two components: rho = auto regularises (R-1.0 3.1, decision 4).
  r1::test::write_file(d / "two.tsv", "a\tb\nb\tc\nc\ta\nx\ty\ny\tz\nz\tx\nz\tw\n");
  r = run_cli({"epoch", (d / "two.tsv").string(), "-o", (d / "two").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("2 components"), std::string::npos) << r.out;
  const auto m = nlohmann::json::parse(r1::test::read_file(d / "two/manifest.json"));
  EXPECT_GT(m["rho"].get<double>(), 0);
}

TEST(CliEpoch, BadOptionsAreOneLineErrorsAndWriteNothing) {
  r1::test::TempDir d;
  const auto g = gen(d.path(), {"ring", "--n", "40"});
  const std::string out = (d / "never").string();
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"--lambda-d", "0.9"}, "lambda"},
      {{"--domain", "fp32"}, "--domain 'fp32'"},
      {{"--tau", "nan"}, "--tau 'nan'"},
      {{"--teleport", "-0.5"}, "teleport"},
      {{"--rho", "-1"}, "--rho '-1'"},
      {{"--anchor", (d / "missing.anchor").string()}, "missing.anchor"},
      {{"--overlay", "rainbow"}, "rainbow"},
      {{"--overlay", "custom"}, "overlay"},
      {{"--bogus"}, "--bogus"},
  };
  for (const auto& [extra, fragment] : cases) {
    SCOPED_TRACE(extra.front());
    std::vector<std::string> args = {"epoch", g.string(), "-o", out};
    args.insert(args.end(), extra.begin(), extra.end());
    expect_one_line_error(run_cli(args), fragment);
    EXPECT_FALSE(fs::exists(out));
  }
  // A directory that is not an epoch is never replaced; a plain file neither.
  fs::create_directory(d / "mine");
  r1::test::write_file(d / "mine/keep.txt", "precious");
  expect_one_line_error(run_cli({"epoch", g.string(), "-o", (d / "mine").string()}), "not an r1 output directory", 3);
  EXPECT_EQ(r1::test::read_file(d / "mine/keep.txt"), "precious");
  // A malformed snapshot: the reader's error, and no output directory.
  r1::test::write_file(d / "bad.tsv", "a\tb\t-3\n");
  expect_one_line_error(run_cli({"epoch", (d / "bad.tsv").string(), "-o", out}), "bad.tsv");
  EXPECT_FALSE(fs::exists(out));
}

TEST(CliEpoch, ExportRefusesADamagedEpoch) {
  r1::test::TempDir d;
  const auto g = gen(d.path(), {"path", "--n", "30"});
  ASSERT_EQ(run_cli({"epoch", g.string(), "-q", "-o", (d / "e").string()}).exit_code, 0);
  std::string pos = r1::test::read_file(d / "e/positions.q32");
  pos[5] = static_cast<char>(pos[5] ^ 1);
  r1::test::write_file(d / "e/positions.q32", pos);
  expect_one_line_error(run_cli({"export", (d / "e").string(), "--tsv", (d / "x.tsv").string()}), "positions.q32");
  EXPECT_FALSE(fs::exists(d / "x.tsv"));
}

TEST(CliEpoch, AnchorAlignsALaterEpoch) {
  r1::test::TempDir d;
  const auto g = gen(d.path(), {"sbm", "--sizes", "90,60,40", "--p-in", "0.25", "--p-out", "0.01"});
  ASSERT_EQ(run_cli({"epoch", g.string(), "-q", "-o", (d / "e0").string()}).exit_code, 0);
  const auto r = run_cli({"epoch", g.string(), "--anchor", (d / "e0/anchor.bin").string(), "-o", (d / "e1").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("aligned to the anchor"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("190 anchor particles matched"), std::string::npos) << r.out;
  // The same snapshot aligned to its own anchor lands on the same positions (Q32 rounding aside:
  // the rotation is the identity to ~1e-16, so each coordinate moves by at most one raw unit).
  const std::string a = r1::test::read_file(d / "e0/positions.q32"), b = r1::test::read_file(d / "e1/positions.q32");
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i + 8 <= a.size(); i += 8) {
    std::int64_t x = 0, y = 0;
    std::memcpy(&x, a.data() + i, 8);
    std::memcpy(&y, b.data() + i, 8);
    EXPECT_LE(std::abs(x - y), 1) << i / 8;
  }
}

}  // namespace
