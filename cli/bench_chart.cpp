// r1 bench's chart (spec/bench.md R1-BEN-040): two panels drawn by hand into a linear RGBA
// image (filled rectangles, anti-aliased lines and dots, DejaVu Sans labels through the
// renderer's draw_text) and written as a PNG with the renderer's OpenImageIO writer.
#include "bench_chart.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "render/image.hpp"

namespace r1::cli {

namespace {

using Rgb = std::array<float, 3>;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Display sRGB -> the image's linear light. Every colour below is at most 242 per channel, so the
// display tone map (identity below linear 0.8 = sRGB 231) hardly moves them.
Rgb srgb(std::uint8_t r, std::uint8_t g, std::uint8_t b) {
  return render::srgb8_to_linear(std::array<std::uint8_t, 3>{r, g, b});
}

// Tableau 10: distinct to most colour-blind viewers; the reference is always the first (blue).
Rgb backend_colour(std::size_t i) {
  static const std::uint8_t k[10][3] = {{78, 121, 167},  {242, 142, 43}, {89, 161, 79},   {225, 87, 89},
                                        {118, 183, 178}, {237, 201, 72}, {176, 122, 161}, {255, 157, 167},
                                        {156, 117, 95},  {186, 176, 172}};
  const auto* c = k[i % 10];
  return srgb(c[0], c[1], c[2]);
}

class Canvas {
 public:
  Canvas(int w, int h, Rgb bg) : img_(w, h) {
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) put(x, y, bg, 1);
  }
  render::Image& image() { return img_; }

  void rect(double x0, double y0, double x1, double y1, Rgb c) {
    if (x0 > x1) std::swap(x0, x1);
    if (y0 > y1) std::swap(y0, y1);
    for (int y = std::max(0, static_cast<int>(std::floor(y0)));
         y < std::min(img_.height, static_cast<int>(std::ceil(y1))); ++y)
      for (int x = std::max(0, static_cast<int>(std::floor(x0)));
           x < std::min(img_.width, static_cast<int>(std::ceil(x1))); ++x)
        put(x, y, c, coverage(x, x0, x1) * coverage(y, y0, y1));
  }

  // A segment `width` pixels wide: each pixel centre covered by its distance to the segment, one
  // pixel of linear ramp at the rim (anti-aliasing).
  void line(double x0, double y0, double x1, double y1, double width, Rgb c) {
    const double pad = width / 2 + 1;
    const double dx = x1 - x0, dy = y1 - y0, len2 = dx * dx + dy * dy;
    for (int y = std::max(0, static_cast<int>(std::min(y0, y1) - pad));
         y <= std::min(img_.height - 1, static_cast<int>(std::max(y0, y1) + pad)); ++y)
      for (int x = std::max(0, static_cast<int>(std::min(x0, x1) - pad));
           x <= std::min(img_.width - 1, static_cast<int>(std::max(x0, x1) + pad)); ++x) {
        const double px = x + 0.5, py = y + 0.5;
        const double t = len2 > 0 ? std::clamp(((px - x0) * dx + (py - y0) * dy) / len2, 0.0, 1.0) : 0.0;
        const double d = std::hypot(px - (x0 + t * dx), py - (y0 + t * dy));
        put(x, y, c, std::clamp(width / 2 + 0.5 - d, 0.0, 1.0));
      }
  }

  void dot(double cx, double cy, double r, Rgb c) {
    for (int y = std::max(0, static_cast<int>(cy - r - 1));
         y <= std::min(img_.height - 1, static_cast<int>(cy + r + 1)); ++y)
      for (int x = std::max(0, static_cast<int>(cx - r - 1));
           x <= std::min(img_.width - 1, static_cast<int>(cx + r + 1)); ++x)
        put(x, y, c, std::clamp(r + 0.5 - std::hypot(x + 0.5 - cx, y + 0.5 - cy), 0.0, 1.0));
  }

  // Text with its baseline at y; `align` 0 left, 1 centred, 2 right of x. Labels are optional:
  // without a font the first failure is kept and the rest are skipped.
  void text(double x, double y, const std::string& s, int size, Rgb c, int align = 0) {
    if (!font_error_.empty() || s.empty()) return;
    const double w = text_width(s, size);
    if (!font_error_.empty()) return;
    const int left = static_cast<int>(std::lround(x - (align == 1 ? w / 2 : align == 2 ? w : 0)));
    const Status st = render::draw_text(img_, left, static_cast<int>(std::lround(y)), s, size, c);
    if (!st.is_ok()) font_error_ = st.message();
  }
  const std::string& font_error() const { return font_error_; }

 private:
  static double coverage(int p, double lo, double hi) {
    return std::clamp(std::min(p + 1.0, hi) - std::max(static_cast<double>(p), lo), 0.0, 1.0);
  }
  void put(int x, int y, Rgb c, double a) {
    if (a <= 0) return;
    float* p = img_.px(x, y);
    const auto f = static_cast<float>(a);
    for (int k = 0; k < 3; ++k) p[k] = p[k] * (1 - f) + c[k] * f;
    p[3] = 1;
  }
  // The drawn width: the label rendered alone, its rightmost covered column.
  double text_width(const std::string& s, int size) {
    render::Image scratch(static_cast<int>(s.size()) * size + 4, 2 * size);
    const Status st = render::draw_text(scratch, 0, size + size / 2, s, size, {1, 1, 1});
    if (!st.is_ok()) {
      font_error_ = st.message();
      return 0;
    }
    int right = 0;
    for (int y = 0; y < scratch.height; ++y)
      for (int x = 0; x < scratch.width; ++x)
        if (scratch.px(x, y)[0] > 0.02f) right = std::max(right, x + 1);
    return right;
  }

  render::Image img_;
  std::string font_error_;
};

// A power of ten as a tick label: plain decimals from 0.001 to 100000, else 1eN.
std::string decade_label(int e, const char* suffix = "") {
  char buf[32];
  if (e >= 0 && e <= 5) {
    std::snprintf(buf, sizeof buf, "%.0f%s", std::pow(10.0, e), suffix);
  } else if (e < 0 && e >= -3) {
    std::snprintf(buf, sizeof buf, "%.*f%s", -e, std::pow(10.0, e), suffix);
  } else {
    std::snprintf(buf, sizeof buf, "1e%d%s", e, suffix);
  }
  return buf;
}

// The decades [lo, hi] (exponents) that hold every positive value and `also` (when > 0); at
// least one decade wide.
std::pair<int, int> decades(const std::vector<double>& v, double also) {
  double mn = also > 0 ? also : kInf, mx = also > 0 ? also : -kInf;
  for (double x : v)
    if (x > 0 && std::isfinite(x)) mn = std::min(mn, x), mx = std::max(mx, x);
  if (!std::isfinite(mn)) return {0, 1};
  int lo = static_cast<int>(std::floor(std::log10(mn) + 1e-9));
  int hi = static_cast<int>(std::ceil(std::log10(mx) - 1e-9));
  if (hi <= lo) hi = lo + 1;
  return {lo, hi};
}

struct Panel {
  double x0, y0, x1, y1;  // the plot area in pixels (y0 top)
};

const Rgb kInk = srgb(40, 40, 40);
const Rgb kGrid = srgb(212, 212, 212);
const Rgb kAxis = srgb(120, 120, 120);
constexpr int kTitle = 15, kLabel = 12;

// Horizontal grid lines and labels at the powers of ten of a log axis, short ticks at 2..9 times
// each power on the axis line.
void y_decades(Canvas& cv, const Panel& p, int lo, int hi, const char* suffix) {
  const double per = (p.y1 - p.y0) / (hi - lo);
  for (int e = lo; e <= hi; ++e) {
    const double y = p.y1 - (e - lo) * per;
    cv.line(p.x0, y, p.x1, y, 1, kGrid);
    cv.line(p.x0 - 5, y, p.x0, y, 1, kAxis);
    cv.text(p.x0 - 8, y + 4, decade_label(e, suffix), kLabel, kInk, 2);
    for (int m = 2; m < 10 && e < hi; ++m) {
      const double ym = y - std::log10(m) * per;
      cv.line(p.x0 - 3, ym, p.x0, ym, 1, kAxis);
    }
  }
}

// The same along the bottom of a panel for the x axis.
void x_decades(Canvas& cv, const Panel& p, int lo, int hi) {
  const double per = (p.x1 - p.x0) / (hi - lo);
  for (int e = lo; e <= hi; ++e) {
    const double x = p.x0 + (e - lo) * per;
    cv.line(x, p.y0, x, p.y1, 1, kGrid);
    cv.line(x, p.y1, x, p.y1 + 5, 1, kAxis);
    cv.text(x, p.y1 + 20, decade_label(e), kLabel, kInk, 1);
    for (int m = 2; m < 10 && e < hi; ++m) {
      const double xm = x + std::log10(m) * per;
      cv.line(xm, p.y1, xm, p.y1 + 3, 1, kAxis);
    }
  }
}

// A bar's value in at most four characters (the table has the exact ones): 0.9, 12.5, 179, 62k.
std::string bar_label(double s) {
  char v[32];
  if (s < 100)
    std::snprintf(v, sizeof v, "%.1f", s);
  else if (s < 1000)
    std::snprintf(v, sizeof v, "%.0f", s);
  else
    std::snprintf(v, sizeof v, "%.0fk", s / 1000);
  return v;
}

void speedup_panel(Canvas& cv, const BenchChart& c, const Panel& p) {
  cv.text(p.x0, p.y0 - 34, c.speedup_title, kTitle, kInk);
  std::vector<double> all;
  for (const auto& row : c.speedup) all.insert(all.end(), row.begin(), row.end());
  const auto [lo, hi] = decades(all, 1.0);
  y_decades(cv, p, lo, hi, "x");
  auto y_of = [&, lo = lo, hi = hi](double s) { return p.y1 - (std::log10(s) - lo) * (p.y1 - p.y0) / (hi - lo); };
  const double one = y_of(1.0);
  const std::size_t groups = c.stages.size(), bars = c.speedup.size();
  const double gw = (p.x1 - p.x0) / std::max<std::size_t>(groups, 1);
  // Bars fill 80% of a group; the rest separates the groups.
  const double bw = bars ? 0.8 * gw / bars : 0;
  for (std::size_t g = 0; g < groups; ++g) {
    const double gx = p.x0 + g * gw;
    cv.text(gx + gw / 2, p.y1 + 20, c.stages[g], kLabel, kInk, 1);
    for (std::size_t b = 0; b < bars; ++b) {
      const double s = g < c.speedup[b].size() ? c.speedup[b][g] : kNaN;
      if (!(s > 0) || !std::isfinite(s)) continue;
      const double bx = gx + 0.1 * gw + b * bw;
      const double ys = std::clamp(y_of(s), p.y0, p.y1);
      cv.rect(bx + 1, std::min(one, ys), bx + bw - 1, std::max(one, ys), backend_colour(b + 1));
      if (bw >= 20) cv.text(bx + bw / 2, s >= 1 ? ys - 4 : ys + 12, bar_label(s), 10, kInk, 1);
    }
  }
  if (bars == 0) cv.text((p.x0 + p.x1) / 2, (p.y0 + p.y1) / 2, "no backend besides the reference", kLabel, kInk, 1);
  cv.line(p.x0, one, p.x1, one, 1.5, kAxis);  // 1x: as fast as the reference
  cv.line(p.x0, p.y0, p.x0, p.y1, 1, kAxis);
}

void scaling_panel(Canvas& cv, const BenchChart& c, const Panel& p) {
  cv.text(p.x0, p.y0 - 34, "epoch time (s) against particles |P|, log-log", kTitle, kInk);
  std::vector<double> xs, ys;
  for (const auto& series : c.scaling)
    for (const auto& [x, y] : series) xs.push_back(x), ys.push_back(y);
  const auto [xlo, xhi] = decades(xs, 0);
  const auto [ylo, yhi] = decades(ys, 0);
  y_decades(cv, p, ylo, yhi, "");
  x_decades(cv, p, xlo, xhi);
  cv.line(p.x0, p.y1, p.x1, p.y1, 1, kAxis);
  cv.line(p.x0, p.y0, p.x0, p.y1, 1, kAxis);
  auto at = [&, xlo = xlo, xhi = xhi, ylo = ylo, yhi = yhi](std::pair<double, double> v) {
    return std::pair<double, double>{p.x0 + (std::log10(v.first) - xlo) * (p.x1 - p.x0) / (xhi - xlo),
                                     p.y1 - (std::log10(v.second) - ylo) * (p.y1 - p.y0) / (yhi - ylo)};
  };
  for (std::size_t b = 0; b < c.scaling.size(); ++b) {
    std::vector<std::pair<double, double>> pts;
    for (const auto& v : c.scaling[b])
      if (v.first > 0 && v.second > 0) pts.push_back(v);
    std::sort(pts.begin(), pts.end());
    for (std::size_t k = 0; k + 1 < pts.size(); ++k) {
      const auto a = at(pts[k]), z = at(pts[k + 1]);
      cv.line(a.first, a.second, z.first, z.second, 2.5, backend_colour(b));
    }
    for (const auto& v : pts) {
      const auto a = at(v);
      cv.dot(a.first, a.second, 4, backend_colour(b));
    }
  }
}

}  // namespace

Status write_bench_chart(const BenchChart& c, const std::filesystem::path& png, std::string* warning) {
  constexpr int kW = 1400, kH = 600;
  Canvas cv(kW, kH, srgb(255, 255, 255));
  // Legend across the top: one swatch per backend, in the colours of both panels.
  double x = 80;
  for (std::size_t b = 0; b < c.backends.size(); ++b) {
    cv.rect(x, 18, x + 14, 32, backend_colour(b));
    cv.text(x + 20, 30, c.backends[b], 14, kInk);
    x += 40 + 9.0 * static_cast<double>(c.backends[b].size());
  }
  speedup_panel(cv, c, {80, 100, 680, kH - 50});
  scaling_panel(cv, c, {790, 100, kW - 40, kH - 50});
  if (warning && !cv.font_error().empty()) *warning = "bench.png has no labels: " + cv.font_error();
  return render::write_image(cv.image(), png, srgb(255, 255, 255));
}

}  // namespace r1::cli
