// The small graph a fuzz input's bytes make (R1-TEST-010), shared by the targets that run epochs.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "r1/spec/status.hpp"

#include "r1/reference/snapshot_builder.hpp"

namespace r1::fuzz {

// Particles a graph may name: 48 keeps the three conformant epochs of an input near 50 ms under
// ASan + UBSan (about 20 inputs a second) and still gives the hierarchy several level-0 clusters.
inline constexpr std::uint32_t kMaxParticles = 48;
// Links read from the input, 3 bytes each: enough for a 48-particle ring plus chords.
inline constexpr std::size_t kMaxLinks = 96;
// Link weights are (1 + the low 6 bits of the weight byte) / 16: 1/16 to 4, so weight ratios of
// up to 64 reach the focus and the frame without any weight being zero.
inline constexpr int kWeightShift = 28;

// The graph of the bytes. Byte 0: the particle count n = 1 + byte % 48 (names p0..p{n-1}). Then
// per link 3 bytes: source % n, target % n, and a byte whose low 6 bits give the weight and whose
// top 2 the valence (0: -1, 1: 0, 2: +1, 3: 0). Particles exist by appearing in a link, so small,
// disconnected graphs and particles known only from a self-loop (isolated) all occur.
inline r1::Result<r1::Snapshot> snapshot_of(const std::uint8_t* data, std::size_t size) {
  if (size < 4) return r1::Status::input("fewer than 4 bytes");
  const std::uint32_t n = 1 + data[0] % kMaxParticles;
  r1::SnapshotBuilder b("fuzz");
  b.snapshot().config = r1::text_input_config();
  for (std::size_t k = 0; k < kMaxLinks && 1 + 3 * k + 2 < size; ++k) {
    const std::uint8_t* l = data + 1 + 3 * k;
    r1::Link link;
    link.height = 1;
    link.amount = static_cast<r1::u128>(1 + (l[2] & 0x3F)) << kWeightShift;
    const int v = l[2] >> 6;
    link.valence = static_cast<std::int8_t>(v == 0 ? -1 : (v == 2 ? 1 : 0));
    link.from = b.particle_by_name("p" + std::to_string(l[0] % n));  // source before target: decision 2
    link.to = b.particle_by_name("p" + std::to_string(l[1] % n));
    b.add_link(link);
  }
  return b.finish();
}

}  // namespace r1::fuzz
