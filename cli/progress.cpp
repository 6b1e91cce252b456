// Terminal progress line.
#include "progress.hpp"

#include <unistd.h>

#include <cstdio>

namespace r1::cli {

ProgressLine::ProgressLine() : enabled_(::isatty(2) == 1), start_(std::chrono::steady_clock::now()) {}

ProgressLine::~ProgressLine() { finish(); }

ProgressFn ProgressLine::sink() {
  if (!enabled_) return {};
  return [this](std::string_view stage, std::uint64_t done, std::uint64_t total) { update(stage, done, total); };
}

void ProgressLine::update(std::string_view stage, std::uint64_t done, std::uint64_t total) {
  const std::lock_guard<std::mutex> lock(mu_);
  const auto now = std::chrono::steady_clock::now();
  if (now - start_ < std::chrono::seconds(1)) return;
  if (shown_ && now - last_ < std::chrono::milliseconds(100) && done < total) return;
  last_ = now;
  shown_ = true;
  const double secs = std::chrono::duration<double>(now - start_).count();
  if (total > 0) {
    std::fprintf(stderr, "\r\033[Kr1: %.*s %5.1f%% (%llu/%llu) %.0fs", static_cast<int>(stage.size()), stage.data(),
                 100.0 * static_cast<double>(done) / static_cast<double>(total), static_cast<unsigned long long>(done),
                 static_cast<unsigned long long>(total), secs);
  } else {
    std::fprintf(stderr, "\r\033[Kr1: %.*s %llu %.0fs", static_cast<int>(stage.size()), stage.data(),
                 static_cast<unsigned long long>(done), secs);
  }
  std::fflush(stderr);
}

void ProgressLine::finish() {
  const std::lock_guard<std::mutex> lock(mu_);
  if (shown_) {
    std::fputs("\r\033[K", stderr);
    std::fflush(stderr);
    shown_ = false;
  }
}

}  // namespace r1::cli
