// Outputs appear atomically or not at all (R1-ERR-003): write to a temporary beside the target,
// flush, rename over it; on any failure the temporary is removed and the target is untouched.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>

#include "r1/spec/status.hpp"

namespace r1 {

class AtomicFile {
 public:
  explicit AtomicFile(std::filesystem::path target);
  ~AtomicFile();  // discards unless commit() succeeded
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  Status open();
  Status write(std::span<const std::uint8_t> bytes);
  Status write(std::string_view s) {
    return write(std::span(reinterpret_cast<const std::uint8_t*>(s.data()), s.size()));
  }
  Status commit();
  void discard();

 private:
  std::filesystem::path target_, temp_;
  int fd_ = -1;
  bool committed_ = false;
};

// Convenience: the whole content at once.
Status write_file_atomic(const std::filesystem::path& target, std::string_view bytes);

}  // namespace r1
