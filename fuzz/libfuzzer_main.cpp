// libFuzzer entry point: runs the one target linked into this executable.
#include "fuzz_target.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const r1::fuzz::TargetFn fn = [] {
    if (r1::fuzz::registry().size() != 1) {
      std::fprintf(stderr, "expected exactly one fuzz target in this executable\n");
      std::abort();
    }
    return r1::fuzz::registry().front().fn;
  }();
  return fn(data, size);
}
