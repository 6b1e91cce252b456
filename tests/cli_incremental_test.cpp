// r1 epoch --from and r1 drift (spec/incremental.md R1-INC-001..040, spec/drift.md R1-DRF-001..030):
// the update record, the same bytes on the cpu backend, bad input with one line and nothing
// written, and the drift report with its certificate check.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>

#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using r1::test::run_cli;

// An rgg graph whose lambda_2..4 are separated: a small reweight is certified at h = 3.
struct Chain {
  r1::test::TempDir d;
  fs::path g, next, prev;
  Chain() {
    g = d / "g.tsv";
    next = d / "next.graph";
    prev = d / "prev.epoch";
    EXPECT_EQ(run_cli({"gen", "rgg", "--n", "1000", "--seed", "3", "-o", g.string()}).exit_code, 0);
    r1::test::write_file(d / "batch.txt", "reweight\trgg/1\trgg/847\t0.999\n");
    EXPECT_EQ(run_cli({"edit", g.string(), (d / "batch.txt").string(), "-o", next.string()}).exit_code, 0);
    EXPECT_EQ(run_cli({"epoch", g.string(), "--no-timings", "-q", "-o", prev.string()}).exit_code, 0);
  }
};

json manifest(const fs::path& dir) { return json::parse(r1::test::read_file(dir / "manifest.json")); }

TEST(CliIncremental, FromWritesTheUpdateRecordAndEveryBackendTheSameBytes) {
  Chain c;
  const auto r = run_cli({"epoch", c.next.string(), "--from", c.prev.string(), "--hops", "3", "--no-timings", "-o",
                          (c.d / "inc").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("update             incremental: 2 touched"), std::string::npos) << r.out;
  const json u = manifest(c.d / "inc").at("update");
  EXPECT_EQ(u.at("mode"), "incremental");
  EXPECT_EQ(u.at("focus"), "local");
  EXPECT_NE(r.out.find("focus updated on N_h"), std::string::npos) << r.out;
  EXPECT_EQ(u.at("hops"), 3);
  EXPECT_LE(u.at("certificate").get<double>(), u.at("eps_x").get<double>());
  EXPECT_EQ(u.at("vector_bound").at(4), nullptr);
  // The hierarchy at PREV's scale (R1-INC-035); the manifest's radii say so.
  EXPECT_EQ(u.at("hierarchy_radius"), "kept");
  EXPECT_EQ(u.at("radius_scale"), "kept");
  EXPECT_EQ(manifest(c.d / "inc").at("hierarchy").at("radii"), manifest(c.prev).at("hierarchy").at("radii"));
  // The digest from PREV's record chunks (R1-EPO-017) is the one `r1 info` finds by hashing every
  // record, and the chunks are those of an epoch of NEXT by itself.
  const auto info = run_cli({"info", c.next.string()});
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_NE(info.out.find("digest             " + manifest(c.d / "inc").at("snapshot").at("digest").get<std::string>()),
            std::string::npos)
      << info.out;
  ASSERT_EQ(run_cli({"epoch", c.next.string(), "--no-timings", "-q", "-o", (c.d / "alone").string()}).exit_code, 0);
  EXPECT_EQ(r1::test::read_file(c.d / "inc/records.chunks"), r1::test::read_file(c.d / "alone/records.chunks"));
  EXPECT_NE(r1::test::read_file(c.d / "inc/records.chunks"), r1::test::read_file(c.prev / "records.chunks"));
  // The reweight changed one record in place: one chunk hashed, the rest taken from PREV.
  const std::size_t chunks = r1::test::read_file(c.prev / "records.chunks").size() / 64;
  EXPECT_NE(r.out.find("digest             1 of " + std::to_string(chunks) + " record chunks hashed"), std::string::npos) << r.out;
  // The chain goes on: the next update reads the record (epochs since the full solve: 2).
  const auto again = run_cli({"epoch", c.next.string(), "--from", (c.d / "inc").string(), "--hops", "3", "--no-timings",
                              "-q", "-o", (c.d / "inc2").string()});
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_EQ(manifest(c.d / "inc2").at("update").at("epochs_since_full"), 2);
  // The cpu backend: the same directory.
  ASSERT_EQ(run_cli({"epoch", c.next.string(), "--from", c.prev.string(), "--hops", "3", "--backend", "cpu", "--no-timings",
                     "-q", "-o", (c.d / "cpu").string()})
                .exit_code,
            0);
  for (const auto& f : fs::directory_iterator(c.d / "inc"))
    EXPECT_EQ(r1::test::read_file(f.path()), r1::test::read_file(c.d / "cpu" / f.path().filename())) << f.path().filename();
  // --full: the full solve aligned to the earlier anchor, with the reason.
  ASSERT_EQ(run_cli({"epoch", c.next.string(), "--from", c.prev.string(), "--full", "--no-timings", "-q", "-o",
                     (c.d / "full").string()})
                .exit_code,
            0);
  EXPECT_EQ(manifest(c.d / "full").at("update").at("reason"), "forced (--full)");
  EXPECT_EQ(manifest(c.d / "full").at("update").at("hierarchy_radius"), "searched");
  EXPECT_EQ(manifest(c.d / "full").at("update").at("radius_scale"), "measured");
  EXPECT_EQ(r1::test::read_file(c.d / "full/records.chunks"), r1::test::read_file(c.d / "alone/records.chunks"));
  EXPECT_FALSE(manifest(c.d / "full").at("alignment").at("genesis").get<bool>());
}

// An eps_X no certificate meets: a full solve, unless --keep-local keeps the update (R1-INC-036),
// which the record and the summary call uncertified.
TEST(CliIncremental, KeepLocalKeepsAnUncertifiedUpdateAndSaysSo) {
  Chain c;
  const auto strict = run_cli({"epoch", c.next.string(), "--from", c.prev.string(), "--hops", "3", "--eps-x", "1e-9",
                               "--no-timings", "-q", "-o", (c.d / "strict").string()});
  ASSERT_EQ(strict.exit_code, 0) << strict.err;
  const json s = manifest(c.d / "strict").at("update");
  EXPECT_EQ(s.at("mode"), "full");
  EXPECT_FALSE(s.at("certified").get<bool>());
  EXPECT_EQ(s.at("reason").get<std::string>().rfind("certificate ", 0), 0u) << s.at("reason");
  const auto kept = run_cli({"epoch", c.next.string(), "--from", c.prev.string(), "--hops", "3", "--eps-x", "1e-9",
                             "--keep-local", "--no-timings", "-o", (c.d / "kept").string()});
  ASSERT_EQ(kept.exit_code, 0) << kept.err;
  const json k = manifest(c.d / "kept").at("update");
  EXPECT_EQ(k.at("mode"), "incremental");
  EXPECT_FALSE(k.at("certified").get<bool>());
  EXPECT_EQ(k.at("reason").get<std::string>().rfind("uncertified (--keep-local): certificate ", 0), 0u) << k.at("reason");
  EXPECT_GT(k.at("certificate").get<double>(), k.at("eps_x").get<double>());
  EXPECT_NE(kept.out.find("(uncertified, --keep-local)"), std::string::npos) << kept.out;
  // The same update as the certified one at the default eps_X: only the record differs.
  ASSERT_EQ(run_cli({"epoch", c.next.string(), "--from", c.prev.string(), "--hops", "3", "--no-timings", "-q", "-o",
                     (c.d / "certified").string()})
                .exit_code,
            0);
  EXPECT_TRUE(manifest(c.d / "certified").at("update").at("certified").get<bool>());
  EXPECT_EQ(r1::test::read_file(c.d / "kept" / "positions.q32"), r1::test::read_file(c.d / "certified" / "positions.q32"));
  EXPECT_EQ(r1::test::read_file(c.d / "kept" / "focus.q32"), r1::test::read_file(c.d / "certified" / "focus.q32"));
}

// R1-NRF-050: with --field, an incremental epoch updates the earlier epoch's field in the box of
// the particles that moved (the same bytes twice); a full solve trains it whole.
TEST(CliIncremental, FieldIsUpdatedLocallyWithTheUpdate) {
  Chain c;
  ASSERT_EQ(run_cli({"epoch", c.g.string(), "--field", "--field-steps", "8", "--no-timings", "-q", "-o",
                     (c.d / "fprev").string()})
                .exit_code,
            0);
  std::string field[2];
  for (int k = 0; k < 2; ++k) {
    const fs::path out = c.d / ("finc" + std::to_string(k));
    const auto r = run_cli({"epoch", c.next.string(), "--from", (c.d / "fprev").string(), "--hops", "3", "--field",
                            "--field-steps", "8", "--no-timings", "-o", out.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("field              field.nrf updated locally: "), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("(update 1 since the field was trained whole)"), std::string::npos) << r.out;
    field[k] = r1::test::read_file(out / "field.nrf");
  }
  EXPECT_EQ(field[0], field[1]);
  EXPECT_NE(field[0], r1::test::read_file(c.d / "fprev" / "field.nrf"));
  const auto full = run_cli({"epoch", c.next.string(), "--from", (c.d / "fprev").string(), "--full", "--field",
                             "--field-steps", "8", "--no-timings", "-o", (c.d / "ffull").string()});
  ASSERT_EQ(full.exit_code, 0) << full.err;
  EXPECT_NE(full.out.find("field.nrf trained whole: the positions were solved in full"), std::string::npos) << full.out;
}

TEST(CliIncremental, BadInputIsOneLineExitTwoAndNothingWritten) {
  Chain c;
  r1::test::TempDir out;
  // A truncated epoch: one file shorter than its manifest says.
  fs::copy(c.prev, c.d / "cut.epoch");
  const std::string pos = r1::test::read_file(c.d / "cut.epoch" / "positions.q32");
  r1::test::write_file(c.d / "cut.epoch" / "positions.q32", pos.substr(0, pos.size() / 2));
  // An epoch with one byte changed: PREV is checked through its chunk table (R1-EPO-018).
  fs::copy(c.prev, c.d / "flipped.epoch");
  std::string flipped = pos;
  flipped[flipped.size() - 1] ^= 1;
  r1::test::write_file(c.d / "flipped.epoch" / "positions.q32", flipped);
  // An epoch of another chain.
  ASSERT_EQ(run_cli({"gen", "ring", "--n", "50", "-o", (c.d / "ring.tsv").string()}).exit_code, 0);
  ASSERT_EQ(run_cli({"epoch", (c.d / "ring.tsv").string(), "-q", "-o", (c.d / "ring.epoch").string()}).exit_code, 0);
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"--from", (c.d / "none").string()}, "none: not an epoch directory"},
      {{"--from", (c.d / "cut.epoch").string()}, "positions.q32"},
      {{"--from", (c.d / "flipped.epoch").string()}, "positions.q32: chunk " + std::to_string((pos.size() - 1) / 4096) +
                                                          " differs from its SHA-256 in files.chunks"},
      {{"--from", (c.d / "ring.epoch").string()}, "not an epoch of this snapshot's chain"},
      {{"--hops", "3"}, "need --from"},
      {{"--from", c.prev.string(), "--anchor", (c.prev / "anchor.bin").string()}, "leave out --anchor"},
      {{"--from", c.prev.string(), "--eps-x", "2"}, "--eps-x must lie in (0, 1)"},
      {{"--from", c.prev.string(), "--hops", "65"}, "--hops must be at most 64"},
  };
  for (const auto& [extra, want] : cases) {
    std::vector<std::string> args = {"epoch", c.next.string(), "-o", (out / "e").string()};
    args.insert(args.end(), extra.begin(), extra.end());
    const auto r = run_cli(args);
    EXPECT_EQ(r.exit_code, 2) << want << ": " << r.err;
    EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << r.err;
    EXPECT_NE(r.err.find(want), std::string::npos) << r.err;
    EXPECT_TRUE(fs::is_empty(out.path())) << want;
  }
}

TEST(CliDrift, ReportsIncrementalAgainstFullAndChecksTheCertificate) {
  Chain c;
  auto drift = [&](const std::string& dir) {
    return run_cli({"drift", c.g.string(), "--epochs", "3", "--batch", "2", "--kind", "reweight", "--scale", "0.002",
                    "--hops", "3", "-o", (c.d / dir).string()});
  };
  const auto r = drift("d1");
  ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
  EXPECT_NE(r.out.find("0 violations"), std::string::npos) << r.out;
  const json j = json::parse(r1::test::read_file(c.d / "d1" / "drift.json"));
  EXPECT_EQ(j.at("format"), "r1-drift");
  ASSERT_EQ(j.at("epochs").size(), 3u);
  std::size_t checked = 0;
  for (const json& e : j.at("epochs")) {
    if (e.at("mode") != "incremental") continue;
    EXPECT_EQ(e.at("check"), "ok");
    EXPECT_LE(e.at("true_drift").get<double>(), e.at("certificate").get<double>() + e.at("full_error").get<double>());
    ++checked;
  }
  EXPECT_GT(checked, 0u) << r.out;
  EXPECT_TRUE(fs::exists(c.d / "d1" / "drift.png"));
  const std::string table = r1::test::read_file(c.d / "d1" / "drift.tsv");
  EXPECT_EQ(std::count(table.begin(), table.end(), '\n'), 4);
  // The same seed, the same batches and results (times aside).
  ASSERT_EQ(drift("d2").exit_code, 0);
  json a = j, b = json::parse(r1::test::read_file(c.d / "d2" / "drift.json"));
  for (json* x : {&a, &b})
    for (json& e : x->at("epochs")) e.erase("seconds_incremental"), e.erase("seconds_full");
  EXPECT_EQ(a, b);
  const auto bad = run_cli({"drift", c.g.string(), "--kind", "swap"});
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--kind 'swap' is not add, remove, reweight or mixed"), std::string::npos) << bad.err;
}

}  // namespace
