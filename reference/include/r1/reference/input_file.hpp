// Read-only access to an input file's bytes: memory-mapped for regular files, read fully for
// standard input ("-") and pipes. Errors name the file (R1-ERR-001).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "r1/spec/status.hpp"

namespace r1 {

class InputFile {
 public:
  // `path` "-" means standard input.
  static Result<std::unique_ptr<InputFile>> open(const std::string& path);
  ~InputFile();
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;

  std::span<const std::uint8_t> bytes() const { return {data_, size_}; }
  std::string_view text() const { return {reinterpret_cast<const char*>(data_), size_}; }
  const std::string& name() const { return name_; }  // for messages: the path, or "<stdin>"
  // A reader done with `part` (a range of text()) lets its pages go from this process's memory
  // (R1-IN-022): for a mapped file the whole pages inside it are dropped (MADV_DONTNEED; read
  // again, they come back from the file, the same bytes); a file read into memory keeps them.
  void drop_pages(std::string_view part) const;

 private:
  InputFile() = default;
  std::string name_;
  const std::uint8_t* data_ = nullptr;
  std::size_t size_ = 0;
  void* map_ = nullptr;
  std::string owned_;  // standard input and non-mappable files
};

}  // namespace r1
