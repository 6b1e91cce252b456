// The frame stage's result as a value (spec/render.md R1-RND-080, R1-BKD-014): premultiplied
// linear RGBA with sRGB/Rec.709 primaries, plus the T-infinity flow channels. Writing it (EXR,
// PNG through OpenColorIO) is the renderer's (reference/render/image.hpp).
#pragma once

#include <cstddef>
#include <vector>

namespace r1::render {

// Premultiplied linear RGBA, row-major from the top-left pixel, plus an optional 3-channel flow
// buffer (R-1.0 7.2: the T-infinity flow composited in a separate channel).
struct Image {
  int width = 0, height = 0;
  std::vector<float> rgba;  // 4 * width * height
  std::vector<float> flow;  // empty or 3 * width * height
  std::vector<double> depth;  // renderer only: ray distance of the nearest opaque hit (inf: none); not written

  Image() = default;
  Image(int w, int h) : width(w), height(h), rgba(static_cast<std::size_t>(w) * h * 4, 0.0f) {}
  float* px(int x, int y) { return rgba.data() + (static_cast<std::size_t>(y) * width + x) * 4; }
  const float* px(int x, int y) const { return rgba.data() + (static_cast<std::size_t>(y) * width + x) * 4; }
};

}  // namespace r1::render
