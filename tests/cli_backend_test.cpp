// `--backend` on every command that runs stages (spec/backends.md R1-BKD-003, R1-BKD-016): epoch,
// render, spectrum, golden and conform take the option, else $R1_BACKEND, else reference; an
// unknown name is one line naming the built backends and exit 2, and the chosen backend did the work.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <nlohmann/json.hpp>
#include <string>

#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;
using r1::test::run_cli;

TEST(CliBackend, EveryStageCommandRejectsAnUnknownBackendWithTheBuiltNames) {
  r1::test::ScopedEnv env("R1_BACKEND", nullptr);
  r1::test::TempDir d;
  ASSERT_EQ(run_cli({"gen", "ring", "--n", "30", "-o", (d / "g.graph").string()}).exit_code, 0);
  ASSERT_EQ(run_cli({"epoch", (d / "g.graph").string(), "-q", "-o", (d / "e").string()}).exit_code, 0);
  const std::vector<std::vector<std::string>> commands = {
      {"epoch", (d / "g.graph").string(), "-o", (d / "x").string()},
      {"render", (d / "e").string(), "-o", (d / "x.png").string()},
      {"spectrum", (d / "g.graph").string()},
      {"golden", "-o", (d / "gold").string()},
      {"conform", "-o", (d / "c.toml").string()},
  };
  for (auto args : commands) {
    args.push_back("--backend");
    args.push_back("no-such-backend");
    const auto r = run_cli(args);
    EXPECT_EQ(r.exit_code, 2) << args[0];
    EXPECT_NE(r.err.find("unknown backend 'no-such-backend' (built: reference"), std::string::npos) << args[0] << ": " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  EXPECT_FALSE(fs::exists(d / "x"));
  EXPECT_FALSE(fs::exists(d / "gold"));
}

TEST(CliBackend, TheEnvironmentChoosesWhenTheOptionIsAbsentAndTheOptionWins) {
  r1::test::TempDir d;
  ASSERT_EQ(run_cli({"gen", "ba", "--n", "200", "-o", (d / "g.graph").string()}).exit_code, 0);
  {
    r1::test::ScopedEnv env("R1_BACKEND", nullptr);
    ASSERT_EQ(run_cli({"epoch", (d / "g.graph").string(), "--no-timings", "-q", "-o", (d / "ref").string()}).exit_code, 0);
  }
  r1::test::ScopedEnv env("R1_BACKEND", "null");
  // $R1_BACKEND=null: the null backend's epoch, which is not the reference's.
  ASSERT_EQ(run_cli({"epoch", (d / "g.graph").string(), "--no-timings", "-q", "-o", (d / "null").string()}).exit_code, 0);
  EXPECT_NE(r1::test::read_file(d / "null" / "positions.q32"), r1::test::read_file(d / "ref" / "positions.q32"));
  // The option wins over the environment: the cpu backend gives the reference's bytes.
  ASSERT_EQ(run_cli({"epoch", (d / "g.graph").string(), "--backend", "cpu", "--no-timings", "-q", "-o",
                     (d / "par").string()})
                .exit_code,
            0);
  for (const char* f : {"manifest.json", "positions.q32", "hierarchy.bin", "anchor.bin"})
    EXPECT_EQ(r1::test::read_file(d / "par" / f), r1::test::read_file(d / "ref" / f)) << f;
  // render through the environment's backend: null draws nothing, so the frame is background only.
  const auto r = run_cli({"render", (d / "ref").string(), "--size", "32x18", "-q", "-o", (d / "n.png").string()});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  const auto ref = run_cli({"render", (d / "ref").string(), "--backend", "reference", "--size", "32x18", "-q", "-o",
                            (d / "r.png").string()});
  EXPECT_EQ(ref.exit_code, 0) << ref.err;
  EXPECT_NE(r1::test::read_file(d / "n.png"), r1::test::read_file(d / "r.png"));
  // spectrum through the chosen backend: null's vectors are all zero.
  const auto s = run_cli({"spectrum", (d / "g.graph").string(), "--json"});
  EXPECT_EQ(s.exit_code, 0) << s.err;
  const auto fp = run_cli({"spectrum", (d / "g.graph").string(), "--domain", "fp64"});
  EXPECT_EQ(fp.exit_code, 2);
  EXPECT_NE(fp.err.find("--domain fp64"), std::string::npos) << fp.err;
}

// `r1 spectrum` on every built backend solves what the epoch's spectral stage solves: the
// manifest's eigenvalues exactly, and its vectors (spectral.q32, after the sign convention) up to
// one sign per vector; the exported operator is the n x n matrix (R1-SPEC-077: the command holds
// only what the solve reads, which must not change a value).
TEST(CliSpectrum, EveryBackendGivesTheEpochsSpectrum) {
  r1::test::ScopedEnv env("R1_BACKEND", nullptr);
  r1::test::TempDir d;
  const std::size_t n = 400;
  ASSERT_EQ(run_cli({"gen", "ba", "--n", std::to_string(n), "--m", "3", "-o", (d / "g.graph").string()}).exit_code, 0);
  ASSERT_EQ(run_cli({"epoch", (d / "g.graph").string(), "--no-field", "--no-timings", "-q", "-o", (d / "e").string()}).exit_code, 0);
  const auto manifest = nlohmann::json::parse(r1::test::read_file(d / "e" / "manifest.json"));
  const std::string u = r1::test::read_file(d / "e" / "spectral.q32");
  ASSERT_EQ(u.size(), n * 5 * 8);
  for (const char* backend : {"reference", "cpu"}) {
    SCOPED_TRACE(backend);
    const fs::path vec = d / (std::string(backend) + ".f64"), lap = d / (std::string(backend) + ".mtx");
    const auto r = run_cli({"spectrum", (d / "g.graph").string(), "--backend", backend, "--json", "--vectors", vec.string(),
                            "--laplacian", lap.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j.at("n").get<std::size_t>(), n);
    EXPECT_EQ(j.at("eigenvalues"), manifest.at("eigenvalues"));
    const std::string v = r1::test::read_file(vec);
    ASSERT_EQ(v.size(), n * 5 * 8);
    for (std::size_t c = 0; c < 5; ++c) {
      int sign = 0;
      for (std::size_t i = 0; i < n; ++i) {
        double got = 0;
        std::int64_t raw = 0;
        std::memcpy(&got, v.data() + (i * 5 + c) * 8, 8);
        std::memcpy(&raw, u.data() + (i * 5 + c) * 8, 8);
        const double want = std::ldexp(static_cast<double>(raw), -32);
        if (sign == 0 && want != 0) sign = got == want ? 1 : -1;
        ASSERT_EQ(got, sign < 0 ? -want : want) << "u_" << c + 2 << " row " << i;
      }
    }
    const std::string mtx = r1::test::read_file(lap);
    EXPECT_EQ(mtx.rfind("%%MatrixMarket", 0), 0u);
    EXPECT_NE(mtx.find("\n" + std::to_string(n) + " " + std::to_string(n) + " "), std::string::npos);
  }
}

}  // namespace
