// The backend registry (R1-BKD-001..005): the built backends by name, the environment override,
// and the error for a name that is not built.
#include "r1/backends/registry.hpp"

#include <array>
#include <cstdlib>
#include <stdexcept>

#include "adapters/adapters.hpp"

namespace r1::backends {

std::string_view domain_name(Domain d) {
  switch (d) {
    case Domain::kFp32: return "FP32";
    case Domain::kFp64: return "FP64";
    case Domain::kFixedQ32: return "FixedQ32";
    case Domain::kGoldilocks: return "Goldilocks";
  }
  return "?";
}

const std::vector<BackendInfo>& registered_backends() {
  // Built once; the order is the listing order of `r1 conform --list` and the differential
  // fuzzer's. Which backends beyond reference and null exist is CMake's choice (R1_BACKEND_*
  // options, R1-BKD-005).
  static const std::vector<BackendInfo> all = [] {
    std::vector<BackendInfo> v;
    v.push_back({"reference", "the cpu-reference: single-threaded, Q32 epoch, fp64 frame (the oracle)", true,
                 [] { return make_reference_backend(); }});
#if R1_BACKEND_CPU
    v.push_back({"cpu", "every core, vectorised exact kernels: the reference's bytes (R1-BKD-040)", true,
                 [] { return make_cpu_backend(); }});
#endif
#if R1_BACKEND_VULKAN
    v.push_back({"vulkan", "cull, impostors, edge tubes, splat sort, field and composite with neural inference, the spectral and focus kernels on a Vulkan 1.3 device (lavapipe in CI), the rest on the host (R1-BKD-065)", true,
                 [] { return make_vulkan_backend(); }});
#endif
#if R1_BACKEND_FP64
    // Not expected to conform: where eigenvalues repeat (ring, torus) the fp64 and Q32 solvers
    // return different bases of the same eigenspace, so positions and topology differ (README).
    v.push_back({"fp64", "the reference stages with spectral and focus in IEEE doubles (R1-EPO-003)", false,
                 [] { return make_reference_backend(true); }});
#endif
    v.push_back({"null", "well-formed but wrong results: the suite must fail it", false, [] { return make_null_backend(); }});
#if R1_BACKEND_SELFTEST
    for (SelfTestFault f : {SelfTestFault::kPosition, SelfTestFault::kTopology, SelfTestFault::kHue}) {
      v.push_back({std::string(self_test_name(f)), std::string(self_test_summary(f)), false,
                   [f] { return make_self_test_backend(f); }});
    }
#endif
    return v;
  }();
  return all;
}

bool is_known_unbuilt(std::string_view name) {
  // 13.2-13.3 and DESIGN.md name these; none is built yet.
  static constexpr std::array<std::string_view, 7> planned{"cpu", "vulkan", "cuda", "honeycrisp", "wgpu", "webgpu",
                                                           "vulkan-native"};
  for (auto p : planned)
    if (p == name) return true;
  return false;
}

namespace {
std::string built_names() {
  std::string s;
  for (const auto& b : registered_backends()) s += (s.empty() ? "" : ", ") + b.name;
  return s;
}
}  // namespace

Result<std::unique_ptr<Backend>> make_backend(std::string_view name) {
  for (const auto& b : registered_backends())
    if (b.name == name) {
      try {
        return b.make();
      } catch (const std::invalid_argument& e) {  // a setting the backend cannot run with ($R1_CPU_SIMD)
        return Status::input("backend '" + std::string(name) + "': " + e.what());
      }
    }
  if (is_known_unbuilt(name))
    return Status::input("backend '" + std::string(name) + "' is not built in this r1 (built: " + built_names() + ")");
  return Status::input("unknown backend '" + std::string(name) + "' (built: " + built_names() + ")");
}

std::string choose_backend_name(std::string_view requested, std::string* source) {
  if (!requested.empty()) {
    if (source) *source = "--backend";
    return std::string(requested);
  }
  const char* env = std::getenv(kBackendEnv);
  if (env && *env) {
    if (source) *source = kBackendEnv;
    return env;
  }
  if (source) *source = "default";
  return "reference";
}

}  // namespace r1::backends
