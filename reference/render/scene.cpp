// The render scene: epoch values in fp64 and hierarchy aggregates (R1-RND-013..016).
#include "scene.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>

#include "image.hpp"

namespace r1::render {

double brightness(double n_phi) { return std::clamp(std::sqrt(std::sqrt(std::max(n_phi, 0.0))), 0.6, 3.0); }

Scene make_scene(const Epoch& e) {
  static std::atomic<std::uint64_t> serials{0};
  Scene s;
  s.serial = ++serials;
  s.n = static_cast<std::uint32_t>(e.ids.size());
  const double n = s.n;
  s.position.resize(s.n);
  s.radius.resize(s.n);
  s.phi.resize(s.n);
  s.color.resize(s.n);
  s.shape = e.encoding.shape;
  s.label.resize(s.n);
  s.u5.resize(s.n);
  s.degree.assign(s.n, 0.0);
  s.edges = e.edges;
  double phi_total = 0;
  Vec3 weighted;
  for (std::uint32_t i = 0; i < s.n; ++i) {
    const auto& p = e.frame.position[i];
    s.position[i] = {p[0].to_double(), p[1].to_double(), p[2].to_double()};
    s.radius[i] = e.encoding.radius[i].to_double();
    s.phi[i] = e.focus.phi[i].to_double();
    const auto& c = e.encoding.color[i];
    s.color[i] = Vec3{static_cast<double>(srgb8_to_linear(c[0])), static_cast<double>(srgb8_to_linear(c[1])),
                      static_cast<double>(srgb8_to_linear(c[2]))} *
                 brightness(n * s.phi[i]);
    s.label[i] = i < e.titles.size() && !e.titles[i].empty() ? e.titles[i] : hemera::to_hex(e.ids[i]).substr(0, 8);
    s.u5[i] = e.spectrum.u[3].empty() ? 0.0 : e.spectrum.u[3][i].to_double();
    phi_total += s.phi[i];
    weighted += s.position[i] * s.phi[i];
  }
  s.centroid = phi_total > 0 ? weighted / phi_total : Vec3{};
  for (const LayoutEdge& edge : s.edges) {
    const double w = Q32::from_raw(edge.w_raw).to_double();
    s.degree[edge.p] += w;
    s.degree[edge.q] += w;
  }
  if (s.n > 0) {
    std::vector<double> r = s.radius;
    std::nth_element(r.begin(), r.begin() + r.size() / 2, r.end());
    s.median_radius = std::max(r[r.size() / 2], 1e-6);
  }
  s.tau0 = e.hierarchy.tau0 > 0 ? e.hierarchy.tau0 : 1.0;
  for (int b = 0; b < 8; ++b) s.seed |= static_cast<std::uint64_t>(e.snapshot_digest[static_cast<std::size_t>(b)]) << (8 * b);
  s.hierarchy = &e.hierarchy;

  // Aggregates, finest level first; higher levels combine their children's.
  for (int l = 0; l < kLevels; ++l) {
    const auto& level = e.hierarchy.levels[static_cast<std::size_t>(l)];
    auto& out = s.nodes[static_cast<std::size_t>(l)];
    out.resize(level.size());
    for (std::size_t id = 0; id < level.size(); ++id) {
      const ClusterNode& node = level[id];
      NodeData& d = out[id];
      d.lo = {node.lo[0].to_double(), node.lo[1].to_double(), node.lo[2].to_double()};
      d.hi = {node.hi[0].to_double(), node.hi[1].to_double(), node.hi[2].to_double()};
      Vec3 centroid, color;
      double r2 = 0, weight = 0;
      // Member particles of this node: gather through the children.
      std::vector<std::uint32_t> members;
      std::vector<std::uint32_t> frontier = node.children;
      for (int down = l; down > 0; --down) {
        std::vector<std::uint32_t> next;
        for (std::uint32_t c : frontier) {
          const auto& ch = e.hierarchy.levels[static_cast<std::size_t>(down - 1)][c].children;
          next.insert(next.end(), ch.begin(), ch.end());
        }
        frontier = std::move(next);
      }
      members = std::move(frontier);
      d.count = static_cast<std::uint32_t>(members.size());
      for (std::uint32_t p : members) {
        d.phi += s.phi[p];
        weight += n * s.phi[p];
        centroid += s.position[p] * s.phi[p];
        color += s.color[p] * (n * s.phi[p]);
        d.max_radius = std::max(d.max_radius, s.radius[p]);
        r2 += s.radius[p] * s.radius[p];
      }
      d.centroid = d.phi > 0 ? centroid / d.phi : (d.lo + d.hi) * 0.5;
      d.color = weight > 0 ? color / weight : Vec3{};
      d.radius = std::sqrt(r2);
      for (std::uint32_t p : members) {
        d.extent = std::max(d.extent, length(s.position[p] - d.centroid));
        if (weight > 0) d.spread.add(n * s.phi[p] / weight, s.color[p], d.color, s.position[p] - d.centroid);
      }
    }
  }
  return s;
}

double scene_extent(const Scene& s) {
  double fit = 0;
  for (std::uint32_t p = 0; p < s.n; ++p) fit = std::max(fit, length(s.position[p] - s.centroid) + s.radius[p]);
  return fit;
}

double focus_extent(const Scene& s, double share) {
  // Particles by |X' - c| + r, ties by index; the first distance at which the running sum of
  // phi reaches `share` of the whole.
  std::vector<std::pair<double, std::uint32_t>> by(s.n);
  double total = 0;
  for (std::uint32_t p = 0; p < s.n; ++p) {
    by[p] = {length(s.position[p] - s.centroid) + s.radius[p], p};
    total += s.phi[p];
  }
  std::sort(by.begin(), by.end());
  double held = 0;
  for (const auto& [d, p] : by) {
    held += s.phi[p];
    if (held >= share * total) return d;
  }
  return by.empty() ? 0.0 : by.back().first;
}

double fit_distance(const Scene& s, double fov_deg) {
  return 1.05 * std::max(1.0, focus_extent(s, kFramedFocus)) / std::sin(fov_deg * kPi / 360.0);
}

}  // namespace r1::render
