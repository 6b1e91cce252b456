// The registry of fuzz targets (R1-TEST-010).
#include "fuzz_target.hpp"

namespace r1::fuzz {

std::vector<Target>& registry() {
  static std::vector<Target> targets;
  return targets;
}

bool register_target(const char* name, TargetFn fn) {
  registry().push_back({name, fn});
  return true;
}

}  // namespace r1::fuzz
