// How legible a frame is (spec/render.md R1-RND-120..123): how many of the particles drawn as
// shapes hide behind a nearer one, how much of the image the bulk of the particles spreads over,
// and how many particles share their exact position with another.
#pragma once

#include <cstdint>

#include "r1/spec/view.hpp"
#include "render/scene.hpp"

namespace r1::render {

struct Legibility {
  std::uint64_t shapes = 0;       // visible particles drawn as shapes (s > t2: T0, T1, T2)
  std::uint64_t overlapped = 0;   // of those, whose projected disc meets a nearer one's
  double overlap_share = 0;       // overlapped / shapes (0 when none)
  std::uint64_t visible = 0;      // visible particles
  double core_share = 0;          // the disc about the median holding 90% of them, over the image area (at most 1)
  std::uint64_t coincident = 0;   // particles whose X' equals another particle's exactly
  double coincident_share = 0;    // coincident / n
};

Legibility legibility(const Scene& s, const View& v);

}  // namespace r1::render
