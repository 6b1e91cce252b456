// The epoch's chunk table: SHA-256 and Hemera leaf per chunk of each file (R1-EPO-018).
#include "file_chunks.hpp"

#include <algorithm>
#include <cstring>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace r1::epoch_chunks {

namespace {

std::span<const std::uint8_t> chunk_of(std::span<const std::uint8_t> bytes, std::size_t i) {
  const std::size_t at = i * hemera::CHUNK_BYTES;
  return bytes.subspan(at, std::min(hemera::CHUNK_BYTES, bytes.size() - at));
}

}  // namespace

std::vector<Sha256> chunk_sha(std::span<const std::uint8_t> bytes) {
  const auto n = static_cast<std::size_t>(hemera::leaf_count(bytes.size()));
  std::vector<Sha256> sha(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 64), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) sha[i] = sha256(chunk_of(bytes, i));
  });
  return sha;
}

FileChunks chunk_file(std::span<const std::uint8_t> bytes, std::span<const Sha256> previous_sha,
                      std::span<const hemera::Digest> previous_leaves) {
  FileChunks f;
  f.sha = chunk_sha(bytes);
  if (previous_leaves.empty()) {
    f.leaves = hemera::tree_leaves(bytes);
    return f;
  }
  f.leaves.assign(f.sha.size(), hemera::Digest{});
  const std::vector<std::uint64_t> todo = leaves_by_sha(f.sha, previous_sha, previous_leaves, f.leaves);
  hemera::chunk_leaves(
      bytes.size(), todo,
      [&](std::uint64_t i, std::span<std::uint8_t> out) {
        const auto c = chunk_of(bytes, static_cast<std::size_t>(i));
        std::copy(c.begin(), c.end(), out.begin());
        return c.size();
      },
      f.leaves);
  return f;
}

std::string table_bytes(std::span<const FileChunks> files) {
  std::size_t rows = 0;
  for (const FileChunks& f : files) rows += f.sha.size();
  std::string out(rows * kRowBytes, '\0');
  char* p = out.data();
  for (const FileChunks& f : files)
    for (std::size_t i = 0; i < f.sha.size(); ++i) {
      std::memcpy(p, f.sha[i].data(), 32);
      std::memcpy(p + 32, f.leaves[i].data(), 32);
      p += kRowBytes;
    }
  return out;
}

Result<FileChunks> check_file(std::span<const std::uint8_t> bytes, std::string_view rows, const hemera::Digest& digest,
                              const std::string& path) {
  const auto n = static_cast<std::size_t>(hemera::leaf_count(bytes.size()));
  if (rows.size() != n * kRowBytes)
    return Status::input(path + ": files.chunks holds " + std::to_string(rows.size() / kRowBytes) + " chunks of it, the file has " +
                         std::to_string(n));
  FileChunks f;
  f.sha = chunk_sha(bytes);
  f.leaves.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (std::memcmp(f.sha[i].data(), rows.data() + i * kRowBytes, 32) != 0)
      return Status::input(path + ": chunk " + std::to_string(i) + " differs from its SHA-256 in files.chunks (the file was modified)");
    std::memcpy(f.leaves[i].data(), rows.data() + i * kRowBytes + 32, 32);
  }
  if (hemera::root_of_leaves(f.leaves) != digest)
    return Status::input(path + ": the leaves in files.chunks do not merge to its Hemera digest in the manifest");
  return f;
}

}  // namespace r1::epoch_chunks
