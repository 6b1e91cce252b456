// Output directories appear atomically or not at all (R1-ERR-003, R1-EPO-010): files are written
// into a temporary directory beside the target, which then replaces the target in one rename (or
// one atomic exchange when the target is a directory r1 wrote before).
#pragma once

#include <filesystem>
#include <functional>
#include <string_view>
#include <vector>

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
  // One file, flushed; `name` may hold folders below the directory (made as needed).
  Status write(const std::string& name, std::string_view bytes);
  // The temporary directory after open(), for writers that make their own files there (images).
  const std::filesystem::path& temp_path() const { return temp_; }
  Status commit();

 private:
  std::filesystem::path target_, temp_;
  std::function<bool(const std::filesystem::path&)> replaceable_;
  std::vector<std::filesystem::path> subdirs_;  // folders made for names with a '/', relative to temp_
  bool committed_ = false;
};

// True when `dir` holds a JSON `file` (manifest.json unless named) whose "format" is `format`: the
// test of whether r1 wrote a directory (an epoch, a golden set, a bench or drift report) and may
// replace it.
bool manifest_format_is(const std::filesystem::path& dir, std::string_view format,
                        std::string_view file = "manifest.json");

}  // namespace r1
