// A progress line on the terminal: shown only when stderr is a terminal, only after the work has
// run for a second, redrawn at most ten times a second, erased when done.
#pragma once

#include <chrono>
#include <mutex>
#include <string>

#include "r1/spec/progress.hpp"

namespace r1::cli {

class ProgressLine {
 public:
  ProgressLine();
  ~ProgressLine();
  ProgressFn sink();
  void finish();  // erases the line

 private:
  void update(std::string_view stage, std::uint64_t done, std::uint64_t total);
  bool enabled_ = false;
  bool shown_ = false;
  std::chrono::steady_clock::time_point start_, last_;
  std::mutex mu_;
};

}  // namespace r1::cli
