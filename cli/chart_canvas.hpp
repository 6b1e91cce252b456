// The hand-drawn charts of r1 bench and r1 drift: a linear RGBA canvas with filled rectangles,
// anti-aliased lines and dots, DejaVu Sans labels through the renderer's draw_text, and the
// decade axes of log plots; written as a PNG with the renderer's OpenImageIO writer.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "render/image.hpp"

namespace r1::cli::chart {

using Rgb = std::array<float, 3>;

// Display sRGB -> the image's linear light.
Rgb srgb(std::uint8_t r, std::uint8_t g, std::uint8_t b);
// Tableau 10, by index (cycling): distinct to most colour-blind viewers.
Rgb series_colour(std::size_t i);

class Canvas {
 public:
  Canvas(int w, int h, Rgb bg);
  render::Image& image() { return img_; }
  void rect(double x0, double y0, double x1, double y1, Rgb c);
  // A segment `width` pixels wide, one pixel of linear ramp at the rim (anti-aliasing).
  void line(double x0, double y0, double x1, double y1, double width, Rgb c);
  void dot(double cx, double cy, double r, Rgb c);
  // Text with its baseline at y; `align` 0 left, 1 centred, 2 right of x. Labels are optional:
  // without a font the first failure is kept and the rest are skipped.
  void text(double x, double y, const std::string& s, int size, Rgb c, int align = 0);
  const std::string& font_error() const { return font_error_; }

 private:
  void put(int x, int y, Rgb c, double a);
  double text_width(const std::string& s, int size);
  render::Image img_;
  std::string font_error_;
};

// A power of ten as a tick label: plain decimals from 0.001 to 100000, else 1eN.
std::string decade_label(int e, const char* suffix = "");
// The decades [lo, hi] (exponents) that hold every positive finite value and `also` (when > 0);
// at least one decade wide.
std::pair<int, int> decades(const std::vector<double>& v, double also);

struct Panel {
  double x0, y0, x1, y1;  // the plot area in pixels (y0 top)
};

extern const Rgb kInk, kGrid, kAxis;
constexpr int kTitle = 15, kLabel = 12;

// Grid lines and labels at the powers of ten of a log axis, short ticks at 2..9 times each power.
void y_decades(Canvas& cv, const Panel& p, int lo, int hi, const char* suffix);
void x_decades(Canvas& cv, const Panel& p, int lo, int hi);

}  // namespace r1::cli::chart
