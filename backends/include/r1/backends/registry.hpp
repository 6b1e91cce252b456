// The backend registry (R1-BKD-001..005): backends by name; `--backend NAME` and the R1_BACKEND
// environment variable choose one. A name that is not built is an error, never a fallback.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "r1/backends/backend.hpp"

namespace r1::backends {

// The environment variable that overrides the default backend (R1-BKD-003).
inline constexpr const char* kBackendEnv = "R1_BACKEND";

struct BackendInfo {
  std::string name;
  std::string summary;
  // Conformant candidates run in the differential fuzzer and are expected to pass `r1 conform`;
  // `null` and the self-test backends are built to fail it (R1-BKD-020).
  bool expected_conformant = true;
  std::function<std::unique_ptr<Backend>()> make;
};

// Every built backend, in registration order (reference first).
const std::vector<BackendInfo>& registered_backends();

// Names and DESIGN.md plan that this build may lack (cpu, vulkan, cuda, honeycrisp, ...):
// asking for one gives "not built in this r1" rather than "unknown".
bool is_known_unbuilt(std::string_view name);

// The backend called `name`; an input error naming the built ones when there is none.
Result<std::unique_ptr<Backend>> make_backend(std::string_view name);

// The name to use: `requested` when not empty, else $R1_BACKEND when set and not empty, else
// "reference" (R1-BKD-003). `source` (optional) says which of the three decided.
std::string choose_backend_name(std::string_view requested, std::string* source = nullptr);

}  // namespace r1::backends
