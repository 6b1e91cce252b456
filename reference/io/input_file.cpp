// Input files: mmap or read fully (R1-ERR-001).
#include "r1/reference/input_file.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace r1 {

namespace {
Status read_all(int fd, const std::string& name, std::string& out) {
  char buf[1 << 16];
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n == 0) return Status::ok();
    if (n < 0) {
      if (errno == EINTR) continue;
      return Status::input(name + ": read failed: " + std::strerror(errno));
    }
    out.append(buf, static_cast<std::size_t>(n));
  }
}
}  // namespace

Result<std::unique_ptr<InputFile>> InputFile::open(const std::string& path) {
  std::unique_ptr<InputFile> f(new InputFile());
  if (path == "-") {
    f->name_ = "<stdin>";
    R1_TRY(read_all(0, f->name_, f->owned_));
    f->data_ = reinterpret_cast<const std::uint8_t*>(f->owned_.data());
    f->size_ = f->owned_.size();
    return f;
  }
  f->name_ = path;
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return Status::input(path + ": cannot open: " + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    const int e = errno;
    ::close(fd);
    return Status::input(path + ": cannot stat: " + std::strerror(e));
  }
  if (S_ISDIR(st.st_mode)) {
    ::close(fd);
    return Status::input(path + ": is a directory, not a file");
  }
  if (S_ISREG(st.st_mode) && st.st_size > 0) {
    void* m = ::mmap(nullptr, static_cast<std::size_t>(st.st_size), PROT_READ, MAP_PRIVATE, fd, 0);
    if (m != MAP_FAILED) {
      ::close(fd);
      f->map_ = m;
      f->data_ = static_cast<const std::uint8_t*>(m);
      f->size_ = static_cast<std::size_t>(st.st_size);
      return f;
    }
  }
  // Pipes, devices, empty files and files mmap refuses: read them.
  const Status s = read_all(fd, path, f->owned_);
  ::close(fd);
  if (!s.is_ok()) return s;
  f->data_ = reinterpret_cast<const std::uint8_t*>(f->owned_.data());
  f->size_ = f->owned_.size();
  return f;
}

void InputFile::drop_pages(std::string_view part) const {
  if (map_ == nullptr || part.empty()) return;
  const auto lo = reinterpret_cast<std::uintptr_t>(part.data());
  const auto hi = lo + part.size();
  const auto first = reinterpret_cast<std::uintptr_t>(data_), last = first + size_;
  if (lo < first || hi > last) return;  // not this file's bytes
  const auto page = static_cast<std::uintptr_t>(::sysconf(_SC_PAGESIZE));
  const std::uintptr_t begin = (lo + page - 1) / page * page, end = hi / page * page;
  if (end > begin) (void)::madvise(reinterpret_cast<void*>(begin), end - begin, MADV_DONTNEED);  // advice: ignoring a refusal is safe
}

InputFile::~InputFile() {
  if (map_ != nullptr) ::munmap(map_, size_);
}

}  // namespace r1
