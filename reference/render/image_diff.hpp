// Perceptual image comparison shared by `r1 diff` and the conformance harness (spec/render.md
// R1-RND-112..116, spec/errors.md R1-ERR-005): images read as display sRGB, per-pixel CIEDE2000
// and CIE76, summary statistics, a verdict and a heatmap.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <span>
#include <vector>

#include "r1/spec/status.hpp"
#include "view.hpp"

namespace r1::render {

struct DiffOptions {
  // Per-pixel CIEDE2000 above which a pixel counts as "over" (strictly greater). About 2 is where
  // a difference between neighbouring patches starts to be noticed by most observers.
  double threshold = 2.0;
  // The comparison fails when the mean CIEDE2000 over all pixels exceeds this (strictly greater):
  // a mean of 2 is a difference visible across the whole image.
  double fail_mean = 2.0;
  // The largest per-pixel CIEDE2000 that is still only a warning; one pixel above it fails the
  // comparison (OpenImageIO idiff's "hard fail"). Off (infinity) by default: antialiased edges of
  // two conforming renderers differ by tens of units on single pixels, and that is a warning, not
  // a failure. Scripts that need a hard ceiling set it.
  double warn_max = std::numeric_limits<double>::infinity();
};

struct DiffStats {
  int width = 0, height = 0;
  std::uint64_t pixels = 0;
  double mean_2000 = 0, max_2000 = 0, p95_2000 = 0, p99_2000 = 0;
  double mean_76 = 0, max_76 = 0, p99_76 = 0;
  std::uint64_t over = 0;  // pixels with CIEDE2000 > DiffOptions::threshold
  int max_x = 0, max_y = 0;  // the first pixel (row-major from the top left) where max_2000 occurs
};

// The verdict and its exit status (R1-ERR-005).
enum class Verdict { kPass = 0, kWarn = 1, kFail = 4, kSizeMismatch = 5 };

// FAIL when mean_2000 > fail_mean or max_2000 > warn_max; else WARN when any pixel is over the
// threshold; else PASS. (Size mismatch is decided before any pixel is compared.)
Verdict judge(const DiffStats& stats, const DiffOptions& options);
// "PASS", "WARN", "FAIL", "SIZE MISMATCH".
const char* verdict_name(Verdict v);

// The nearest-rank percentile: with the N values sorted ascending, the value of rank
// ceil(percent x N / 100) (1-based; rank 1 for percent 0). `values` is reordered. 0 when empty.
double percentile_nearest_rank(std::span<double> values, int percent);

// Compares two display sRGB images (3 bytes a pixel, row-major from the top left, `width` x
// `height` each). Every pixel is converted to CIELAB (r1/color/delta_e.hpp: IEC 61966-2-1 decode,
// D65) and differenced; identical bytes give exactly 0. Means are the row-major sums over all
// pixels divided by the pixel count; p95/p99 are nearest-rank percentiles. When `heat` is given
// it receives the per-pixel CIEDE2000 (width x height floats, row-major). When a span is not
// 3 x width x height bytes (or the size is not positive) the stats are all 0 with pixels = 0.
DiffStats diff_srgb8(std::span<const std::uint8_t> a, std::span<const std::uint8_t> b, int width, int height,
                     const DiffOptions& options, std::vector<float>* heat);

// The mean CIEDE2000 over the pixels either image covers (bytes other than `background`), from
// diff_srgb8's per-pixel `heat`: a far view covers a few percent of the frame, so a mean over every
// pixel would let a frame that draws nothing pass; over the covered pixels it cannot (R1-CONF-063).
// `b_covered` counts the second image's own covered pixels (0: nothing to compare against).
struct CoveredMean {
  double mean_2000 = 0;
  std::uint64_t covered = 0, b_covered = 0;
};
CoveredMean covered_mean_2000(std::span<const std::uint8_t> a, std::span<const std::uint8_t> b, std::span<const float> heat,
                              const std::array<std::uint8_t, 3>& background);

// Reads an image as 8-bit display sRGB RGB (3 bytes a pixel, row-major), setting width and height:
//  - PNG, 8 bits a channel, RGB or RGBA. RGB is taken as it is. RGBA is straight (unassociated)
//    alpha as PNG defines it; it is composited over `background` in linear light (IEC 61966-2-1
//    decode, C a + B (1 - a)) and encoded back like r1 render's PNG (OpenColorIO sRGB encode,
//    round to nearest); alpha 255 keeps the bytes, alpha 0 gives the background's bytes.
//  - EXR: scene-linear premultiplied R, G, B and optional A (absent: opaque), through
//    display_srgb8 over `background` (decoded to linear): the bytes r1 render writes to a PNG.
// `background` is display sRGB, by default the view's default background (#0a0c12). Images are
// 1..16384 pixels a side. A missing or unreadable file, another format, bit depth or channel
// layout is an input error naming the file.
Result<std::vector<std::uint8_t>> read_srgb8(const std::filesystem::path& path, int* width, int* height,
                                             std::array<std::uint8_t, 3> background = View{}.background);

// Writes per-pixel differences as an 8-bit RGB PNG, atomically (R1-ERR-003). The ramp, with
// t = clamp(v / scale, 0, 1) (NaN: 1) and s = 3t: R = round(255 clamp(s, 0, 1)),
// G = round(255 clamp(s - 1, 0, 1)), B = round(255 clamp(s - 2, 0, 1)), round = floor(x + 0.5):
// 0 is black, scale / 3 pure red, 2 scale / 3 yellow, >= scale white. The same values give the
// same bytes. `out` must end in .png (input error otherwise); scale must be positive and finite.
Status write_heatmap(std::span<const float> heat, int width, int height, double scale,
                     const std::filesystem::path& out);

}  // namespace r1::render
