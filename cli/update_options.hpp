// Options of the incremental update that r1 epoch --from and r1 drift share (spec/incremental.md
// R1-INC-020, R1-INC-030, R1-INC-036): --hops, --eps-x, --full-every, --full-norm, --keep-local,
// checked in one place.
#pragma once

#include <CLI/CLI.hpp>

#include <cmath>
#include <optional>
#include <string>

#include "r1/reference/incremental.hpp"

namespace r1::cli {

struct UpdateCliOptions {
  std::optional<std::uint32_t> hops, full_every;
  std::optional<double> eps_x, full_norm;
  bool keep_local = false;

  // `prefix` goes before each help text ("with --from: " for r1 epoch).
  void add_to(CLI::App& cmd, const std::string& prefix = "") {
    cmd.add_option("--hops", hops, prefix + "h, the neighbourhood of the edits (default from --eps-x and --mu)");
    cmd.add_option("--eps-x", eps_x, prefix + "position bound eps_X as a fraction of R_scene (0.001)");
    cmd.add_option("--full-every", full_every, prefix + "a full solve at least every N epochs (64)");
    cmd.add_option("--full-norm", full_norm, prefix + "a full solve once the summed ||dL|| bound exceeds this (0.05)");
    cmd.add_flag("--keep-local", keep_local,
                 prefix + "keep the local update when its certificate exceeds eps_X (recorded as uncertified; for timing and drift studies)");
  }

  bool any() const { return hops || full_every || eps_x || full_norm || keep_local; }

  // The options, or an input error naming the flag; `command` starts each message ("epoch").
  Result<UpdateOptions> make(const std::string& command) const {
    if (eps_x && !(*eps_x > 0 && *eps_x < 1)) return Status::input(command + ": --eps-x must lie in (0, 1)");
    if (full_norm && !(*full_norm >= 0 && std::isfinite(*full_norm)))
      return Status::input(command + ": --full-norm must be a finite number >= 0");
    if (full_every && *full_every == 0) return Status::input(command + ": --full-every must be at least 1");
    if (hops && *hops > 64) return Status::input(command + ": --hops must be at most 64");
    UpdateOptions uo;
    if (eps_x) uo.eps = *eps_x;
    uo.hops = hops;
    if (full_every) uo.full_every = *full_every;
    if (full_norm) uo.full_norm = *full_norm;
    uo.keep_local = keep_local;
    return uo;
  }
};

}  // namespace r1::cli
