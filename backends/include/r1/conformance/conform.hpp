// `r1 conform`: every check of section 15 on one backend, and the r1_conformance.toml
// sidecar (spec/conformance.md R1-CONF-050..064).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "r1/conformance/harness.hpp"

namespace r1::conformance {

enum class Check { kTopo, kPos, kPix, kFps, kTinf };
inline constexpr std::array<Check, 5> kAllChecks{Check::kTopo, Check::kPos, Check::kPix, Check::kFps, Check::kTinf};
const char* check_key(Check c);  // "P_RENDER_TOPO", ...
Result<std::vector<Check>> parse_checks(std::string_view list);  // "topo,pos,pix" (or "all")

struct ConformOptions {
  Suite suite;
  std::optional<GoldenSet> golden;  // the reference's results; unset: computed now by `reference`
  std::vector<Check> checks{kAllChecks.begin(), kAllChecks.end()};
  std::string fps_epoch;                 // an epoch directory of ~10^6 particles for P_RENDER_FPS
  std::vector<std::string> tinf_epochs;  // extra epoch directories for P_RENDER_TINF
  std::vector<std::int64_t> tinf_sizes{1000, 10000};  // BA graphs generated for P_RENDER_TINF
  int tinf_width = 480, tinf_height = 270;
  // P_RENDER_TINF's candidate far field (R1-CONF-064): false, the backend's frames; true, the
  // neural field trained for each epoch, drawn by the reference renderer.
  bool tinf_neural = false;
  std::uint32_t tinf_field_steps = 120;  // its training's Adam steps (R1-NRF-011)
  bool tinf_field_clifford = false;      // its network with the Clifford render block (R1-NRF-003)
  // With the neural field: its literal march (every pixel's samples, R1-NRF-033) instead of the
  // skipping one.
  bool tinf_literal = false;
};

struct CheckResult {
  Check check;
  bool passed = false;
  std::string comment;  // the measured value, as the sidecar's comment
};

struct ConformReport {
  std::string backend, hardware, suite;
  std::vector<CheckResult> results;  // in kAllChecks order, only the checks run
  std::vector<std::string> lines;    // per-graph detail, for the terminal
  bool all_passed() const;
};

// Runs the checks. `say` receives progress lines as the work goes.
Result<ConformReport> conform(backends::Backend& candidate, const ConformOptions& options,
                              const std::function<void(const std::string&)>& say = {});

// The sidecar in 15's layout: [r1_conformance], one `KEY = 0|1  # measured` line per check.
std::string sidecar_toml(const ConformReport& report);

// "Intel(R) Xeon(R) ... (2 threads)" from /proc/cpuinfo, or "unknown CPU".
std::string hardware_name();

}  // namespace r1::conformance
