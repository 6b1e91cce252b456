// Canonical 128-byte records and the snapshot digest (R1-IN-020..024, R1-IN-040).
#include "r1/spec/snapshot.hpp"

#include <algorithm>
#include <bit>
#include <cstring>
#include <memory>
#include <new>

#include <openssl/evp.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace r1 {

namespace {
// The low n bytes of v, little-endian (n <= sizeof(T)); one copy on a little-endian host.
template <class T>
void put_le(std::uint8_t* p, T v, std::size_t n) {
  if constexpr (std::endian::native == std::endian::little) {
    std::memcpy(p, &v, n);
  } else {
    for (std::size_t i = 0; i < n; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
  }
}
}  // namespace

void encode_record(const Snapshot& s, const Link& l, std::uint8_t out[kRecordBytes]) {
  std::memset(out, 0, kRecordBytes);
  std::memcpy(out + 0, s.neurons[l.neuron].data(), 32);
  std::memcpy(out + 32, s.particles[l.from].data(), 32);
  std::memcpy(out + 64, s.particles[l.to].data(), 32);
  put_le(out + 96, l.token, 4);
  put_le(out + 100, l.amount, 16);
  out[116] = static_cast<std::uint8_t>(l.valence);
  put_le(out + 117, l.height, 8);
  // [125, 128) stays zero.
}

namespace {

// Chunk `chunk` of the record stream (32 records, fewer at the end) into out; its byte count.
std::size_t record_chunk(const Snapshot& s, std::uint64_t chunk, std::span<std::uint8_t> out) {
  constexpr std::size_t per_chunk = hemera::CHUNK_BYTES / kRecordBytes;  // 32 records
  const std::size_t first = static_cast<std::size_t>(chunk) * per_chunk;
  const std::size_t last = std::min(s.links.size(), first + per_chunk);
  // The particle ids are cache misses on large snapshots: those of the record 8 on are fetched
  // early (speed only).
  constexpr std::size_t kAhead = 8;
  for (std::size_t i = first; i < last; ++i) {
    const Link& ahead = s.links[std::min(i + kAhead, s.links.size() - 1)];
    __builtin_prefetch(s.particles.data() + ahead.from);
    __builtin_prefetch(s.particles.data() + ahead.to);
    encode_record(s, s.links[i], out.data() + (i - first) * kRecordBytes);
  }
  return (last - first) * kRecordBytes;
}

std::uint64_t stream_bytes(const Snapshot& s) { return static_cast<std::uint64_t>(s.links.size()) * kRecordBytes; }

}  // namespace

hemera::Digest snapshot_digest(const Snapshot& s) {
  return hemera::root_hash_chunks(stream_bytes(s), [&](std::uint64_t chunk, std::span<std::uint8_t> out) {
    return record_chunk(s, chunk, out);
  });
}

Sha256 sha256(std::span<const std::uint8_t> bytes) {
  // One fetch of the algorithm per process and one context per thread: a 4096-byte chunk hashes
  // in about 2.4 us, which a fetch per call would add a good part to.
  static EVP_MD* const md = EVP_MD_fetch(nullptr, "SHA256", nullptr);
  thread_local const std::unique_ptr<EVP_MD_CTX, void (*)(EVP_MD_CTX*)> ctx(EVP_MD_CTX_new(), EVP_MD_CTX_free);
  Sha256 out{};
  unsigned len = 0;
  // OpenSSL fails here only when it cannot allocate.
  if (md == nullptr || ctx == nullptr || EVP_DigestInit_ex2(ctx.get(), md, nullptr) != 1 ||
      EVP_DigestUpdate(ctx.get(), bytes.data(), bytes.size()) != 1 || EVP_DigestFinal_ex(ctx.get(), out.data(), &len) != 1 ||
      len != out.size())
    throw std::bad_alloc();
  return out;
}

std::vector<std::uint64_t> leaves_by_sha(std::span<const Sha256> sha, std::span<const Sha256> previous_sha,
                                         std::span<const hemera::Digest> previous_leaves, std::span<hemera::Digest> leaves) {
  const bool reuse = sha.size() > 1 && previous_leaves.size() > 1 && previous_sha.size() == previous_leaves.size();
  std::vector<std::uint64_t> todo;
  for (std::size_t i = 0; i < sha.size(); ++i) {
    if (reuse && i < previous_sha.size() && sha[i] == previous_sha[i]) {
      leaves[i] = previous_leaves[i];
    } else {
      todo.push_back(i);
    }
  }
  return todo;
}

hemera::Digest snapshot_digest(const Snapshot& s, RecordChunks& chunks, const RecordChunks* previous) {
  const std::uint64_t total = stream_bytes(s);
  const std::size_t n = static_cast<std::size_t>(hemera::leaf_count(total));
  chunks.sha.assign(n, Sha256{});
  chunks.leaves.assign(n, hemera::Digest{});
  // A leaf digest binds its chunk, its index and whether it is the root (one leaf in all): with
  // more than one leaf on both sides, equal chunks at one index have equal leaves.
  const bool reuse = previous != nullptr && n > 1 && previous->leaves.size() > 1 &&
                     previous->sha.size() == previous->leaves.size();
  std::vector<std::uint64_t> todo;
  if (reuse) {
    // Every chunk's SHA-256 (encoded twice where it changed: here and for its leaf).
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 256), [&](const tbb::blocked_range<std::size_t>& r) {
      std::array<std::uint8_t, hemera::CHUNK_BYTES> buf;
      for (std::size_t i = r.begin(); i < r.end(); ++i) {
        const std::size_t len = record_chunk(s, i, buf);
        chunks.sha[i] = sha256(std::span<const std::uint8_t>(buf.data(), len));
      }
    });
    todo = leaves_by_sha(chunks.sha, previous->sha, previous->leaves, chunks.leaves);
    hemera::chunk_leaves(total, todo, [&](std::uint64_t i, std::span<std::uint8_t> out) { return record_chunk(s, i, out); },
                         chunks.leaves);
  } else {
    // One pass: each chunk, once encoded, gives its SHA-256 and then its leaf.
    todo.resize(n);
    for (std::size_t i = 0; i < n; ++i) todo[i] = i;
    hemera::chunk_leaves(
        total, todo,
        [&](std::uint64_t i, std::span<std::uint8_t> out) {
          const std::size_t len = record_chunk(s, i, out);
          chunks.sha[static_cast<std::size_t>(i)] = sha256(out.first(len));
          return len;
        },
        chunks.leaves);
  }
  chunks.hashed = todo.size();
  return hemera::root_of_leaves(chunks.leaves);
}

std::string display_name(const Snapshot& s, std::size_t i) {
  if (i < s.titles.size() && !s.titles[i].empty()) return s.titles[i];
  if (i < s.names.size() && !s.names[i].empty()) return s.names[i];
  return hemera::to_hex(s.particles[i]).substr(0, 16);
}

}  // namespace r1
