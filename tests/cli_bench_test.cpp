// r1 bench through the command line (spec/bench.md R1-BEN-001..050): a backend that gives the
// reference's bytes agrees and exits 0, the null backend disagrees and exits 4 with the table
// still printed, bench.json holds what the spec lists and is consistent with itself, the chart is
// a PNG, and bad inputs are one-line errors that leave no output directory.
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using r1::test::run_cli;

// Small frames keep the runs quick; the size is not what these tests are about.
constexpr const char* kSize = "160x90";

json read_json(const fs::path& p) { return json::parse(r1::test::read_file(p)); }

const json& run_of(const json& report, const std::string& input, const std::string& backend) {
  for (const auto& r : report.at("runs"))
    if (r.at("input") == input && r.at("backend") == backend) return r;
  ADD_FAILURE() << "no run " << input << " / " << backend;
  static const json none;
  return none;
}

std::size_t lines(const std::string& s) { return static_cast<std::size_t>(std::count(s.begin(), s.end(), '\n')); }

// R1-BEN-010, 011, 030..034: cpu computes the reference's bits, so every file but the
// timings is identical, the frames are the same pixels, the verdict is AGREE and the exit 0. The
// report's numbers hang together: epoch = the sum of the timed members, speedup = reference time
// over backend time, one scaling point per input.
TEST(CliBench, ParallelAgreesWithTheReferenceOnTwoGeneratedGraphs) {
  r1::test::TempDir dir;
  const fs::path out = dir / "bench";
  const auto r =
      run_cli({"bench", "--gen", "ba:150,ba:300", "--backend", "cpu", "--size", kSize, "-o", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("bench: AGREE"), std::string::npos) << r.out;
  // The table: a header and one row per (input, backend), then the speedup table.
  EXPECT_NE(r.out.find("spectral"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("bytes identical"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("speedup against the reference"), std::string::npos) << r.out;
  // One progress line per run on standard error (and one per generated input).
  EXPECT_NE(r.err.find("bench: [4/4]"), std::string::npos) << r.err;

  const json j = read_json(out / "bench.json");
  EXPECT_EQ(j.at("format"), "r1-bench");
  EXPECT_EQ(j.at("version"), 1);
  EXPECT_TRUE(j.at("agree").get<bool>());
  ASSERT_EQ(j.at("backends").size(), 2u);
  EXPECT_EQ(j.at("backends")[0].at("name"), "reference");  // always first
  EXPECT_EQ(j.at("backends")[1].at("epoch_check"), "bytes");
  ASSERT_EQ(j.at("inputs").size(), 2u);
  EXPECT_EQ(j.at("inputs")[0].at("particles"), 150);
  EXPECT_EQ(j.at("inputs")[1].at("particles"), 300);
  EXPECT_TRUE(fs::is_regular_file(out / j.at("inputs")[0].at("path").get<std::string>()));
  ASSERT_EQ(j.at("runs").size(), 4u);
  for (const auto& run : j.at("runs")) {
    const auto& t = run.at("times_s");
    double sum = 0;
    for (const auto& [k, v] : t.items())
      if (k != "epoch" && k != "render") sum += v.get<double>();
    for (const char* stage : {"read", "digest", "spectral", "focus", "frame", "encoding", "hierarchy", "render"})
      EXPECT_GE(t.at(stage).get<double>(), 0) << stage;
    EXPECT_NEAR(t.at("epoch").get<double>(), sum, 1e-12 * std::max(1.0, sum));
    EXPECT_GT(run.at("epoch_run").at("peak_rss_mib").get<double>(), 1);
    EXPECT_GT(run.at("render_run").at("peak_rss_mib").get<double>(), 1);
    EXPECT_TRUE(fs::is_regular_file(out / run.at("render_run").at("png").get<std::string>()));
    EXPECT_TRUE(run.at("agrees").get<bool>());
  }
  for (const char* input : {"ba-150", "ba-300"}) {
    const json& ref = run_of(j, input, "reference");
    const json& par = run_of(j, input, "cpu");
    EXPECT_EQ(par.at("epoch_agreement").at("method"), "bytes");
    EXPECT_TRUE(par.at("epoch_agreement").at("differing_files").empty());
    EXPECT_EQ(par.at("frame_agreement").at("mean_de2000").get<double>(), 0.0);
    for (const char* stage : {"spectral", "focus", "epoch", "render"}) {
      const double want = ref.at("times_s").at(stage).get<double>() / par.at("times_s").at(stage).get<double>();
      EXPECT_NEAR(par.at("speedup").at(stage).get<double>(), want, 1e-9 * want) << stage;
    }
  }
  ASSERT_EQ(j.at("scaling").size(), 2u);
  for (const auto& s : j.at("scaling")) {
    EXPECT_EQ(s.at("points").size(), 2u);
    EXPECT_TRUE(s.at("exponent").is_number());
  }
  // The chart is a PNG OpenImageIO reads back.
  auto in = OIIO::ImageInput::open((out / "bench.png").string());
  ASSERT_TRUE(in);
  EXPECT_GT(in->spec().width, 400);
  EXPECT_GT(in->spec().height, 200);
  in->close();
  // Nothing else of the run is left: no temporaries beside the output, no epoch directories in it.
  EXPECT_FALSE(fs::exists(out / "work"));
  for (const auto& e : fs::directory_iterator(dir.path())) EXPECT_EQ(e.path().filename(), "bench") << e.path();
}

// R1-BEN-011, 050: null's epochs are well-formed and wrong, so they differ from the reference's;
// the table and the report are still written, and the exit status is the failed-check verdict 4.
// A snapshot file works as an input beside --gen.
TEST(CliBench, NullDisagreesAndExitsFour) {
  r1::test::TempDir dir;
  const fs::path snap = dir / "ring.tsv", out = dir / "bench";
  ASSERT_EQ(run_cli({"gen", "ring", "--n", "120", "-o", snap.string()}).exit_code, 0);
  const auto r = run_cli({"bench", snap.string(), "--backend", "null", "--size", kSize, "-o", out.string()});
  EXPECT_EQ(r.exit_code, 4) << r.out << r.err;
  EXPECT_NE(r.out.find("bench: DISAGREE: null on ring"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("DIFFER"), std::string::npos) << r.out;
  const json j = read_json(out / "bench.json");
  EXPECT_FALSE(j.at("agree").get<bool>());
  const json& null = run_of(j, "ring", "null");
  EXPECT_FALSE(null.at("agrees").get<bool>());
  EXPECT_EQ(null.at("epoch_agreement").at("method"), "bytes");
  const auto files = null.at("epoch_agreement").at("differing_files").get<std::vector<std::string>>();
  EXPECT_NE(std::find(files.begin(), files.end(), "positions.q32"), files.end());
  EXPECT_NE(std::find(files.begin(), files.end(), "manifest.json"), files.end());
  // particles.ids is the pipeline's, not a stage's: the same bytes even from null.
  EXPECT_EQ(std::find(files.begin(), files.end(), "particles.ids"), files.end());
  EXPECT_EQ(j.at("inputs")[0].at("path"), snap.string());
  EXPECT_TRUE(j.at("inputs")[0].at("generated").is_null());
}

// R1-BEN-012: a backend that is not deterministic Q32 (fp64) is held to the conformance
// position bound rather than to bytes, and reports the deviation it measured.
TEST(CliBench, AnFp64BackendIsComparedByPositions) {
  r1::test::TempDir dir;
  const fs::path out = dir / "bench";
  const auto r = run_cli({"bench", "--gen", "grid:8x8", "--backend", "fp64", "--size", kSize, "-o", out.string()});
  ASSERT_TRUE(r.exit_code == 0 || r.exit_code == 4) << r.out << r.err;
  const json j = read_json(out / "bench.json");
  const json& fp = run_of(j, "grid-8x8", "fp64");
  EXPECT_EQ(fp.at("epoch_agreement").at("method"), "positions");
  const double dev = fp.at("epoch_agreement").at("max_deviation_r_scene").get<double>();
  EXPECT_GE(dev, 0);
  EXPECT_EQ(fp.at("epoch_agreement").at("agrees").get<bool>(), dev <= 1e-3);
  EXPECT_EQ(r.exit_code == 0, fp.at("agrees").get<bool>());
}

// R1-BEN-002: without --backend, the reference and every backend the registry expects to conform
// (`r1 conform --list` without "[fails by design]"), whatever this build registers.
TEST(CliBench, DefaultBackendsAreTheConformingOnes) {
  const auto list = run_cli({"conform", "--list"});
  ASSERT_EQ(list.exit_code, 0);
  std::vector<std::string> want;
  std::istringstream in(list.out);
  // The backends, up to the blank line before the devices.
  for (std::string line; std::getline(in, line) && !line.empty();)
    if (line.find("[fails by design]") == std::string::npos) want.push_back(line.substr(0, line.find(' ')));
  ASSERT_FALSE(want.empty());
  EXPECT_EQ(want.front(), "reference");
  r1::test::TempDir dir;
  const fs::path out = dir / "bench";
  const auto r = run_cli({"bench", "--gen", "path:40", "--size", "64x36", "-o", out.string()});
  const json j = read_json(out / "bench.json");
  std::vector<std::string> got;
  for (const auto& b : j.at("backends")) got.push_back(b.at("name"));
  EXPECT_EQ(got, want);
  EXPECT_EQ(r.exit_code == 0, j.at("agree").get<bool>()) << r.out;
}

// R1-BEN-004, R1-ERR-001: bad inputs are one line on standard error, exit 2, before any work:
// no output directory and no temporary beside it.
TEST(CliBench, BadInputsAreOneLineErrorsAndWriteNothing) {
  r1::test::TempDir dir;
  const fs::path out = dir / "bench";
  const fs::path bad = dir / "bad.tsv";
  r1::test::write_file(bad, "a\tb\tnot-a-weight\n");
  struct Case {
    std::vector<std::string> args;
    std::string says;
  };
  const std::vector<Case> cases = {
      {{(dir / "missing.graph").string()}, "missing.graph"},
      {{bad.string()}, "bad.tsv:1"},
      {{"--gen", "ba:100", "--backend", "no-such-backend"}, "unknown backend 'no-such-backend'"},
      {{"--gen", "ba:abc"}, "--gen 'ba:abc'"},
      {{"--gen", "nosuchkind:10"}, "--gen 'nosuchkind:10'"},
      {{"--gen", "crystal:10"}, "crystal takes no size"},
      {{"--gen", "ba:0"}, "--gen 'ba:0'"},
      {{"--gen", "ba:100", "--size", "10by10"}, "--size"},
      {{}, "give a snapshot or --gen"},
  };
  for (const auto& c : cases) {
    std::vector<std::string> args{"bench"};
    args.insert(args.end(), c.args.begin(), c.args.end());
    args.insert(args.end(), {"-o", out.string()});
    const auto r = run_cli(args);
    EXPECT_EQ(r.exit_code, 2) << c.says << ": " << r.err;
    EXPECT_EQ(lines(r.err), 1u) << r.err;
    EXPECT_EQ(r.err.rfind("r1: ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(c.says), std::string::npos) << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
    std::size_t entries = 0;
    for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir.path())) ++entries;
    EXPECT_EQ(entries, 1u) << c.says;  // bad.tsv alone
  }
}

// R1-BEN-042: an existing directory that is not a bench output is never replaced (exit 3, untouched);
// an earlier bench output is.
TEST(CliBench, ReplacesOnlyAnEarlierBenchOutput) {
  r1::test::TempDir dir;
  const fs::path out = dir / "bench";
  fs::create_directories(out);
  r1::test::write_file(out / "notes.txt", "mine");
  auto r = run_cli({"bench", "--gen", "path:30", "--backend", "reference", "--size", "64x36", "-o", out.string()});
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  EXPECT_EQ(r1::test::read_file(out / "notes.txt"), "mine");
  fs::remove_all(out);
  for (int k = 0; k < 2; ++k) {
    r = run_cli({"bench", "--gen", "path:30", "--backend", "reference", "--size", "64x36", "-o", out.string()});
    EXPECT_EQ(r.exit_code, 0) << r.err;
  }
  EXPECT_EQ(read_json(out / "bench.json").at("runs").size(), 1u);
}

}  // namespace
