// Metadata overlays as values (R1-ENC-030..043, R1-BKD-014): crystal-keyed tables plus
// per-particle entries. The encoding stage receives an overlay, never the file it came from.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "r1/fixedpoint/q32.hpp"
#include "r1/spec/crystal.hpp"
#include "r1/spec/epoch.hpp"

namespace r1 {

using Rgb8 = std::array<std::uint8_t, 3>;

// What an overlay sets for one particle; unset fields keep the schemaless value.
struct OverlayStyle {
  std::optional<Shape> shape;
  std::optional<Rgb8> color;
  std::optional<fx::Q32> size;  // radius multiplier in (0, 16]
  friend bool operator==(const OverlayStyle&, const OverlayStyle&) = default;
};

struct OverlayParticle {
  std::string key;          // a particle name or 64 hex digits
  OverlayStyle style;
  std::size_t line = 0;     // where it was given, for messages (0: built in code)
  friend bool operator==(const OverlayParticle& a, const OverlayParticle& b) { return a.key == b.key && a.style == b.style; }
};

// A metadata overlay: crystal-keyed tables plus per-particle entries (R1-ENC-040).
struct CustomOverlay {
  std::array<std::optional<Shape>, kCrystalTypes.size()> type_shape;
  std::array<std::optional<Rgb8>, kCrystalDomains.size()> domain_color;
  std::array<std::optional<fx::Q32>, kCrystalSizes.size()> size_multiplier;
  std::vector<OverlayParticle> particles;  // in key order, keys distinct
  friend bool operator==(const CustomOverlay&, const CustomOverlay&) = default;
};

inline constexpr std::array<std::string_view, 6> kShapeNames = {"sphere", "torus", "tetrahedron", "cube", "octahedron", "cylinder"};
// The largest size multiplier an overlay may give (R1-ENC-040).
inline constexpr std::int64_t kMaxSizeMultiplier = 16;

}  // namespace r1
