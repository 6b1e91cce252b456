// Progress reporting for long work (house rule: anything over a few seconds shows progress).
// Stages call the sink with monotonically growing `done`; the sink decides what to show.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <string_view>

namespace r1 {

using ProgressFn = std::function<void(std::string_view stage, std::uint64_t done, std::uint64_t total)>;

// Calls `fn` when set; a null sink costs one branch.
inline void report(const ProgressFn& fn, std::string_view stage, std::uint64_t done, std::uint64_t total) {
  if (fn) fn(stage, done, total);
}

// Wall-clock seconds since `t`, for stage timings.
inline double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

}  // namespace r1
