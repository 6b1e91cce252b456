// The legibility measures of spec/render.md R1-RND-120..123 (see legibility.hpp).
#include "render/legibility.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>
#include <unordered_map>
#include <vector>

#include "render/cull.hpp"
#include "render/view.hpp"

namespace r1::render {

namespace {

struct Disc {
  double x = 0, y = 0, r = 0, depth = 0;
  std::uint32_t particle = 0;
};

// Nearer in the drawing order: smaller depth, ties by the lower index.
bool nearer(const Disc& a, const Disc& b) { return a.depth != b.depth ? a.depth < b.depth : a.particle < b.particle; }

}  // namespace

Legibility legibility(const Scene& s, const View& v) {
  Legibility out;
  const CameraFrame f = camera_frame(v);
  const std::vector<Visible> vis = cull(s, v, f);
  out.visible = vis.size();
  std::vector<Disc> discs;
  std::vector<double> xs, ys;
  for (const Visible& p : vis) {
    const Projected pr = project(v, f, s.position[p.particle]);
    xs.push_back(pr.px);
    ys.push_back(pr.py);
    if (p.s > v.tiers.t2) discs.push_back({pr.px, pr.py, std::min(p.s, 1e7) / 2, p.depth, p.particle});
  }
  // R1-RND-121: a disc overlaps when another's disc is nearer and their centres are closer than
  // the sum of the radii. Discs go into 64-pixel cells (clipped to the image grown by 64 px, so
  // a disc reaching far outside costs no more than the image); pairs are tested per shared cell.
  out.shapes = discs.size();
  constexpr double kCell = 64;
  const auto cell_of = [&](double c, int limit) {
    return static_cast<int>(std::floor(std::clamp(c, -kCell, limit + kCell) / kCell));
  };
  std::unordered_map<std::int64_t, std::vector<std::uint32_t>> cells;
  for (std::uint32_t i = 0; i < discs.size(); ++i) {
    const Disc& d = discs[i];
    for (int cy = cell_of(d.y - d.r, v.height); cy <= cell_of(d.y + d.r, v.height); ++cy)
      for (int cx = cell_of(d.x - d.r, v.width); cx <= cell_of(d.x + d.r, v.width); ++cx)
        cells[(static_cast<std::int64_t>(cy) << 32) + cx].push_back(i);
  }
  std::vector<bool> hidden(discs.size(), false);
  for (const auto& [key, members] : cells)
    for (std::size_t a = 0; a < members.size(); ++a)
      for (std::size_t b = a + 1; b < members.size(); ++b) {
        const Disc& da = discs[members[a]];
        const Disc& db = discs[members[b]];
        const double dx = da.x - db.x, dy = da.y - db.y, rr = da.r + db.r;
        if (dx * dx + dy * dy >= rr * rr) continue;
        hidden[nearer(da, db) ? members[b] : members[a]] = true;
      }
  out.overlapped = static_cast<std::uint64_t>(std::count(hidden.begin(), hidden.end(), true));
  out.overlap_share = out.shapes ? static_cast<double>(out.overlapped) / static_cast<double>(out.shapes) : 0.0;

  // R1-RND-122: the disc about the coordinate-wise median of the projected centres that holds
  // ceil(0.9 N) of them (nearest rank), its area over the image's, at most 1.
  if (!xs.empty()) {
    std::vector<double> sx(xs), sy(ys);
    std::nth_element(sx.begin(), sx.begin() + static_cast<std::ptrdiff_t>(sx.size() / 2), sx.end());
    std::nth_element(sy.begin(), sy.begin() + static_cast<std::ptrdiff_t>(sy.size() / 2), sy.end());
    const double mx = sx[sx.size() / 2], my = sy[sy.size() / 2];
    std::vector<double> dist(xs.size());
    for (std::size_t i = 0; i < xs.size(); ++i) dist[i] = std::hypot(xs[i] - mx, ys[i] - my);
    const std::size_t rank = static_cast<std::size_t>(std::ceil(0.9 * static_cast<double>(dist.size())));
    std::nth_element(dist.begin(), dist.begin() + static_cast<std::ptrdiff_t>(rank - 1), dist.end());
    const double r = dist[rank - 1];
    out.core_share = std::min(1.0, kPi * r * r / (static_cast<double>(v.width) * v.height));
  }

  // R1-RND-123: exact position ties over all particles.
  std::vector<std::uint32_t> order(s.n);
  for (std::uint32_t p = 0; p < s.n; ++p) order[p] = p;
  const auto key = [&](std::uint32_t p) { return std::tuple(s.position[p].x, s.position[p].y, s.position[p].z); };
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return key(a) < key(b); });
  for (std::size_t i = 0; i < order.size(); ++i) {
    const bool same_prev = i > 0 && key(order[i]) == key(order[i - 1]);
    const bool same_next = i + 1 < order.size() && key(order[i]) == key(order[i + 1]);
    if (same_prev || same_next) ++out.coincident;
  }
  out.coincident_share = s.n ? static_cast<double>(out.coincident) / s.n : 0.0;
  return out;
}

}  // namespace r1::render
