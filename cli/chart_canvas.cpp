// The charts' canvas and log axes (chart_canvas.hpp), shared by r1 bench and r1 drift.
#include "chart_canvas.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace r1::cli::chart {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();

double coverage(int p, double lo, double hi) {
  return std::clamp(std::min(p + 1.0, hi) - std::max(static_cast<double>(p), lo), 0.0, 1.0);
}
}  // namespace

// Every colour below is at most 242 per channel, so the display tone map (identity below linear
// 0.8 = sRGB 231) hardly moves them.
Rgb srgb(std::uint8_t r, std::uint8_t g, std::uint8_t b) {
  return render::srgb8_to_linear(std::array<std::uint8_t, 3>{r, g, b});
}

Rgb series_colour(std::size_t i) {
  static const std::uint8_t k[10][3] = {{78, 121, 167},  {242, 142, 43}, {89, 161, 79},   {225, 87, 89},
                                        {118, 183, 178}, {237, 201, 72}, {176, 122, 161}, {255, 157, 167},
                                        {156, 117, 95},  {186, 176, 172}};
  const auto* c = k[i % 10];
  return srgb(c[0], c[1], c[2]);
}

const Rgb kInk = srgb(40, 40, 40);
const Rgb kGrid = srgb(212, 212, 212);
const Rgb kAxis = srgb(120, 120, 120);

Canvas::Canvas(int w, int h, Rgb bg) : img_(w, h) {
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) put(x, y, bg, 1);
}

void Canvas::rect(double x0, double y0, double x1, double y1, Rgb c) {
  if (x0 > x1) std::swap(x0, x1);
  if (y0 > y1) std::swap(y0, y1);
  for (int y = std::max(0, static_cast<int>(std::floor(y0))); y < std::min(img_.height, static_cast<int>(std::ceil(y1)));
       ++y)
    for (int x = std::max(0, static_cast<int>(std::floor(x0))); x < std::min(img_.width, static_cast<int>(std::ceil(x1)));
         ++x)
      put(x, y, c, coverage(x, x0, x1) * coverage(y, y0, y1));
}

void Canvas::line(double x0, double y0, double x1, double y1, double width, Rgb c) {
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

void Canvas::dot(double cx, double cy, double r, Rgb c) {
  for (int y = std::max(0, static_cast<int>(cy - r - 1)); y <= std::min(img_.height - 1, static_cast<int>(cy + r + 1)); ++y)
    for (int x = std::max(0, static_cast<int>(cx - r - 1)); x <= std::min(img_.width - 1, static_cast<int>(cx + r + 1)); ++x)
      put(x, y, c, std::clamp(r + 0.5 - std::hypot(x + 0.5 - cx, y + 0.5 - cy), 0.0, 1.0));
}

void Canvas::text(double x, double y, const std::string& s, int size, Rgb c, int align) {
  if (!font_error_.empty() || s.empty()) return;
  const double w = text_width(s, size);
  if (!font_error_.empty()) return;
  const int left = static_cast<int>(std::lround(x - (align == 1 ? w / 2 : align == 2 ? w : 0)));
  const Status st = render::draw_text(img_, left, static_cast<int>(std::lround(y)), s, size, c);
  if (!st.is_ok()) font_error_ = st.message();
}

void Canvas::put(int x, int y, Rgb c, double a) {
  if (a <= 0) return;
  float* p = img_.px(x, y);
  const auto f = static_cast<float>(a);
  for (int k = 0; k < 3; ++k) p[k] = p[k] * (1 - f) + c[k] * f;
  p[3] = 1;
}

// The drawn width: the label rendered alone, its rightmost covered column.
double Canvas::text_width(const std::string& s, int size) {
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

std::string decade_label(int e, const char* suffix) {
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

}  // namespace r1::cli::chart
