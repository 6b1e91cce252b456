// Canonical 128-byte records and the snapshot digest (R1-IN-020..024, R1-IN-040).
#include "r1/spec/snapshot.hpp"

#include <algorithm>
#include <bit>
#include <cstring>

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

hemera::Digest snapshot_digest(const Snapshot& s) {
  constexpr std::size_t per_chunk = hemera::CHUNK_BYTES / kRecordBytes;  // 32 records
  const std::uint64_t total = static_cast<std::uint64_t>(s.links.size()) * kRecordBytes;
  return hemera::root_hash_chunks(total, [&](std::uint64_t chunk, std::span<std::uint8_t> out) {
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
  });
}

std::string display_name(const Snapshot& s, std::size_t i) {
  if (i < s.titles.size() && !s.titles[i].empty()) return s.titles[i];
  if (i < s.names.size() && !s.names[i].empty()) return s.names[i];
  return hemera::to_hex(s.particles[i]).substr(0, 16);
}

}  // namespace r1
