// The anchor of a frame (R1-FRM-020..023, R1-BKD-014): the first min(1024, |P|) particles with
// their positions. A stage-boundary value: the frame stage receives it, never the file's path.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "r1/fixedpoint/q32.hpp"
#include "r1/spec/snapshot.hpp"

namespace r1 {

struct AnchorEntry {
  ParticleId id{};
  std::array<fx::Q32, 3> position{};
  friend bool operator==(const AnchorEntry&, const AnchorEntry&) = default;
};

struct Anchor {
  std::vector<AnchorEntry> entries;  // 1..1024, distinct ids
  friend bool operator==(const Anchor&, const Anchor&) = default;
};

// The anchor file's layout (R1-FRM-021): a 16-byte header, then 56 bytes per entry.
inline constexpr std::size_t kAnchorHeaderBytes = 16;
inline constexpr std::size_t kAnchorEntryBytes = 56;
inline constexpr std::uint32_t kAnchorVersion = 1;
// |raw| bound of an anchor coordinate: 2^20 scene units (R1-FRM-021).
inline constexpr std::int64_t kAnchorCoordMax = std::int64_t{1} << 52;

}  // namespace r1
