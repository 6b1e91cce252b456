// r1 bench's chart (spec/bench.md R1-BEN-040): two panels on the shared chart canvas
// (chart_canvas.hpp), written as a PNG.
#include "bench_chart.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "chart_canvas.hpp"

namespace r1::cli {

namespace {

using namespace chart;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The reference is always the first colour (blue).
Rgb backend_colour(std::size_t i) { return series_colour(i); }

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
