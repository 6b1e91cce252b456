// Atomic output files (R1-ERR-003).
#include "r1/reference/atomic_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>

namespace r1 {

namespace fs = std::filesystem;

AtomicFile::AtomicFile(fs::path target) : target_(std::move(target)) {}

AtomicFile::~AtomicFile() {
  if (!committed_) discard();
}

Status AtomicFile::open() {
  static std::atomic<unsigned> seq{0};
  const fs::path dir = target_.has_parent_path() ? target_.parent_path() : fs::path(".");
  std::error_code ec;
  if (fs::is_directory(target_, ec)) return Status::output(target_.string() + ": is a directory");
  if (!fs::is_directory(dir, ec)) return Status::output(target_.string() + ": directory " + dir.string() + " does not exist");
  // A hidden name in the same directory so that rename() stays within one file system.
  temp_ = dir / ("." + target_.filename().string() + ".tmp." + std::to_string(::getpid()) + "." +
                 std::to_string(seq++));
  fd_ = ::open(temp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd_ < 0) return Status::output(target_.string() + ": cannot create: " + std::strerror(errno));
  return Status::ok();
}

Status AtomicFile::write(std::span<const std::uint8_t> bytes) {
  if (fd_ < 0) return Status::internal(target_.string() + ": write before open");
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd_, bytes.data() + done, bytes.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      return Status::output(target_.string() + ": write failed: " + std::strerror(errno));
    }
    done += static_cast<std::size_t>(n);
  }
  return Status::ok();
}

Status AtomicFile::commit() {
  if (fd_ < 0) return Status::internal(target_.string() + ": commit before open");
  if (::fsync(fd_) != 0 || ::close(fd_) != 0) {
    fd_ = -1;
    return Status::output(target_.string() + ": flush failed: " + std::strerror(errno));
  }
  fd_ = -1;
  if (::rename(temp_.c_str(), target_.c_str()) != 0)
    return Status::output(target_.string() + ": rename failed: " + std::strerror(errno));
  committed_ = true;
  return Status::ok();
}

void AtomicFile::discard() {
  if (fd_ >= 0) {
    ::close(fd_);
    fd_ = -1;
  }
  if (!temp_.empty()) {
    std::error_code ec;
    fs::remove(temp_, ec);
  }
}

Status write_file_atomic(const fs::path& target, std::string_view bytes) {
  AtomicFile f(target);
  R1_TRY(f.open());
  R1_TRY(f.write(bytes));
  return f.commit();
}

}  // namespace r1
