// The frame buffer and its outputs (R-1.0 decision 10, spec/render.md R1-RND-080..086): linear
// light with sRGB/Rec.709 primaries, written as scene-linear float EXR or as a display-referred
// sRGB PNG through OpenColorIO after a documented tone map. Writes are atomic (R1-ERR-003).
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "r1/spec/image.hpp"
#include "r1/spec/status.hpp"

namespace r1::render {

// Display sRGB code value (0..255) -> linear light, the exact IEC 61966-2-1 curve.
float srgb8_to_linear(std::uint8_t v);
// The same per channel: a display sRGB colour (a view's background) as linear RGB.
std::array<float, 3> srgb8_to_linear(const std::array<std::uint8_t, 3>& rgb);

// The tone map for display (R1-RND-082): linear values above display white roll off smoothly.
// Applied to the colour's largest channel, so hue is kept. Identity below the knee.
std::array<float, 3> tone_map(std::array<float, 3> rgb);

// The tone map's constants (R1-RND-082): identity up to the knee, asymptote 1 (display white).
inline constexpr double kToneKnee = 0.8;

// The OpenColorIO step of display_srgb8 alone (R1-RND-083): scene-linear Rec.709 RGB triples ->
// sRGB display-encoded values, in place; no tone map, no quantization. Exposed so tests can hold
// OCIO's transform against the closed-form IEC 61966-2-1 encode.
Status ocio_linear_to_srgb(std::span<float> rgb);

// Linear premultiplied RGBA over `background` (linear RGB) -> 8-bit display sRGB RGB through
// OpenColorIO (scene-linear Rec.709 -> sRGB display), row-major, 3 bytes a pixel.
Result<std::vector<std::uint8_t>> display_srgb8(const Image& image, std::array<float, 3> background);

// OK when `path` ends in .png or .exr (any case); else the input error write_image returns.
// Callers check it before the work that produces the image.
Status check_image_extension(const std::filesystem::path& path);

// Writes `image` by the extension of `path`: .exr (32-bit float RGBA, scene-linear, premultiplied,
// plus flow.X/Y/Z when present) or .png (display sRGB over `background`). Atomic: the file
// appears complete or not at all. Another extension is an input error.
Status write_image(const Image& image, const std::filesystem::path& path, std::array<float, 3> background);

// Draws `text` in linear colour `rgb` with its baseline-left at pixel (x, y), `size` pixels high,
// over the image (OpenImageIO's text renderer). Fails with an error when no font is available.
Status draw_text(Image& image, int x, int y, std::string_view text, int size, std::array<float, 3> rgb);

// The advance width in pixels of `text` set in draw_text's font at `size` pixels (OpenImageIO's
// text_size), or -1 when no font is available. For typesetting T0 text and cards (R1-RND-133).
int text_width(std::string_view text, int size);

}  // namespace r1::render
