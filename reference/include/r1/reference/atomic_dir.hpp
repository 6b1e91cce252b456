// Output directories appear atomically or not at all (R1-ERR-003, R1-EPO-010): files are written
// into a temporary directory beside the target, which then replaces the target in one rename (or
// one atomic exchange when the target is a directory r1 wrote before).
#pragma once

#include <filesystem>
#include <functional>
#include <string_view>

#include "r1/spec/status.hpp"

namespace r1 {

class AtomicDirectory {
 public:
  // `replaceable(dir)` decides whether an existing target may be replaced (else: an error).
  AtomicDirectory(std::filesystem::path target, std::function<bool(const std::filesystem::path&)> replaceable);
  ~AtomicDirectory();  // removes the temporary unless commit() succeeded
  AtomicDirectory(const AtomicDirectory&) = delete;
  AtomicDirectory& operator=(const AtomicDirectory&) = delete;

  Status open();
  Status write(const std::string& name, std::string_view bytes);  // one file, flushed
  Status commit();

 private:
  std::filesystem::path target_, temp_;
  std::function<bool(const std::filesystem::path&)> replaceable_;
  bool committed_ = false;
};

}  // namespace r1
