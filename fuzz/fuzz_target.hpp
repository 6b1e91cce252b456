// libFuzzer target convention (R1-TEST-010): a target is a function registered by name; the
// libFuzzer build wraps exactly one of them, the replay test runs every committed corpus.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <ostream>
#include <string>
#include <vector>

namespace r1::fuzz {

using TargetFn = int (*)(const std::uint8_t* data, std::size_t size);

struct Target {
  const char* name;
  TargetFn fn;
};

// Test output names the target rather than dumping its bytes.
inline void PrintTo(const Target& t, std::ostream* os) { *os << t.name; }

std::vector<Target>& registry();
bool register_target(const char* name, TargetFn fn);

[[noreturn]] inline void fail(const char* file, int line, const char* what) {
  std::fprintf(stderr, "fuzz property failed at %s:%d: %s\n", file, line, what);
  std::abort();
}

}  // namespace r1::fuzz

// Defines and registers target `name`; the body follows as a function body.
#define R1_FUZZ_TARGET(name)                                                                  \
  static int r1_fuzz_##name(const std::uint8_t* data, std::size_t size);                     \
  [[maybe_unused]] static const bool r1_fuzz_registered_##name =                             \
      ::r1::fuzz::register_target(#name, &r1_fuzz_##name);                                    \
  static int r1_fuzz_##name(const std::uint8_t* data, std::size_t size)

// A property of the target: on failure the input is reported as a crash.
#define R1_FUZZ_CHECK(cond) \
  do {                      \
    if (!(cond)) ::r1::fuzz::fail(__FILE__, __LINE__, #cond); \
  } while (0)
