// Atomic output directories (R1-ERR-003, R1-EPO-010).
#include "r1/reference/atomic_dir.hpp"

#include <fcntl.h>
#include <stdio.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <fstream>

#include <nlohmann/json.hpp>

namespace r1 {

namespace fs = std::filesystem;

namespace {
Status fsync_path(const fs::path& p, const std::string& what) {
  const int fd = ::open(p.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return Status::output(what + ": cannot open for flushing: " + std::strerror(errno));
  const int rc = ::fsync(fd);
  ::close(fd);
  if (rc != 0) return Status::output(what + ": flush failed: " + std::strerror(errno));
  return Status::ok();
}
}  // namespace

AtomicDirectory::AtomicDirectory(fs::path target, std::function<bool(const fs::path&)> replaceable)
    : target_(std::move(target)), replaceable_(std::move(replaceable)) {}

AtomicDirectory::~AtomicDirectory() {
  if (!committed_ && !temp_.empty()) {
    std::error_code ec;
    fs::remove_all(temp_, ec);
  }
}

Status AtomicDirectory::open() {
  static std::atomic<unsigned> seq{0};
  std::error_code ec;
  const fs::path parent = target_.has_parent_path() ? target_.parent_path() : fs::path(".");
  if (!fs::is_directory(parent, ec)) return Status::output(target_.string() + ": directory " + parent.string() + " does not exist");
  if (fs::exists(target_, ec)) {
    if (!fs::is_directory(target_, ec)) return Status::output(target_.string() + ": exists and is not a directory");
    if (!replaceable_(target_))
      return Status::output(target_.string() + ": exists and is not an r1 output directory; refusing to replace it");
  }
  temp_ = parent / ("." + target_.filename().string() + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(seq++));
  if (!fs::create_directory(temp_, ec)) {
    temp_.clear();
    return Status::output(target_.string() + ": cannot create a temporary directory: " + ec.message());
  }
  return Status::ok();
}

Status AtomicDirectory::write(const std::string& name, std::string_view bytes) {
  const fs::path p = temp_ / name;
  // A name with folders (an epoch's content/K.ext, R1-EPO-031) gets them made inside the
  // temporary directory, each flushed at commit so its entries are as durable as the files.
  const fs::path rel = fs::path(name).lexically_normal();
  if (rel.is_absolute() || rel.empty() || *rel.begin() == "..")
    return Status::internal((target_ / name).string() + ": file name leaves the output directory");
  if (rel.has_parent_path()) {
    std::error_code ec;
    fs::create_directories(temp_ / rel.parent_path(), ec);
    if (ec) return Status::output((target_ / rel.parent_path()).string() + ": cannot create: " + ec.message());
    for (fs::path d = rel.parent_path(); !d.empty(); d = d.parent_path())
      if (std::find(subdirs_.begin(), subdirs_.end(), d) == subdirs_.end()) subdirs_.push_back(d);
  }
  const int fd = ::open(p.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) return Status::output((target_ / name).string() + ": cannot create: " + std::strerror(errno));
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      const int e = errno;
      ::close(fd);
      return Status::output((target_ / name).string() + ": write failed: " + std::strerror(e));
    }
    done += static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0 || ::close(fd) != 0) return Status::output((target_ / name).string() + ": flush failed");
  return Status::ok();
}

Status AtomicDirectory::commit() {
  for (const fs::path& d : subdirs_) R1_TRY(fsync_path(temp_ / d, (target_ / d).string()));
  R1_TRY(fsync_path(temp_, target_.string()));
  std::error_code ec;
  if (fs::exists(target_, ec)) {
    // Swap in one step, so readers see the old epoch or the new one, never neither.
    if (::renameat2(AT_FDCWD, temp_.c_str(), AT_FDCWD, target_.c_str(), RENAME_EXCHANGE) != 0)
      return Status::output(target_.string() + ": cannot replace: " + std::strerror(errno));
    committed_ = true;
    fs::remove_all(temp_, ec);  // now the old directory
  } else {
    if (::rename(temp_.c_str(), target_.c_str()) != 0)
      return Status::output(target_.string() + ": cannot create: " + std::strerror(errno));
    committed_ = true;
  }
  const fs::path parent = target_.has_parent_path() ? target_.parent_path() : fs::path(".");
  return fsync_path(parent, parent.string());
}

bool manifest_format_is(const fs::path& dir, std::string_view format, std::string_view file) {
  std::ifstream f(dir / file);
  if (!f) return false;
  try {
    return nlohmann::json::parse(f).value("format", "") == format;
  } catch (const nlohmann::json::exception&) {
    return false;
  }
}

}  // namespace r1
