// The render scene (spec/render.md R1-RND-013..016): an epoch converted once to the fp64 values
// the frame stages use, with per-node aggregates of the hierarchy for culling, the far field and
// edge bundling.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "r1/spec/epoch.hpp"
#include "r1/spec/vec3.hpp"

namespace r1::render {

// A node's colour beyond its mean (R1-RND-055): the colour's first moment with position over the
// members, `grad[3 j + k] = sum_i s_i (c_i - cbar)_j (x_i - mu)_k` (s_i = w_i / W, the member's
// share of the node's weight; row j a colour channel, column k an axis), and the members' colour
// range per channel. An aggregate taken whole at x with kernel width sigma has the colour
// `cbar + grad (x - mu) / sigma^2`, clamped into the range: the first-order term of the members'
// kernel-weighted mean colour, which the mean alone drops.
struct ColourSpread {
  std::array<double, 9> grad{};
  Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  // Adds a member of colour c at offset dx = x_i - mu from the centroid with share s of the
  // node's weight (mean: the node's mean colour).
  void add(double share, const Vec3& c, const Vec3& mean, const Vec3& dx) {
    add_moment(grad, share, c - mean, dx);
    lo = Vec3{std::min(lo.x, c.x), std::min(lo.y, c.y), std::min(lo.z, c.z)};
    hi = Vec3{std::max(hi.x, c.x), std::max(hi.y, c.y), std::max(hi.z, c.z)};
  }
  // The first moment alone: grad[3 j + k] += share dc_j dx_k (in that order of products).
  static void add_moment(std::array<double, 9>& grad, double share, const Vec3& dc, const Vec3& dx) {
    const double c[3] = {dc.x, dc.y, dc.z}, d[3] = {dx.x, dx.y, dx.z};
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) grad[static_cast<std::size_t>(3 * j + k)] += share * c[j] * d[k];
  }
  // The colour at u = (x - mu) / sigma^2 of a node of mean colour `mean`: per channel j,
  // mean_j + grad[3 j] u_x + grad[3 j + 1] u_y + grad[3 j + 2] u_z, added left to right, clamped
  // into [lo_j, hi_j]. Written out per channel: the analytic frames call it for every aggregate at
  // every sample.
  Vec3 at(const Vec3& mean, const Vec3& u) const {
    const auto& g = grad;
    return {std::min(std::max(mean.x + g[0] * u.x + g[1] * u.y + g[2] * u.z, lo.x), hi.x),
            std::min(std::max(mean.y + g[3] * u.x + g[4] * u.y + g[5] * u.z, lo.y), hi.y),
            std::min(std::max(mean.z + g[6] * u.x + g[7] * u.y + g[8] * u.z, lo.z), hi.z)};
  }
};

struct NodeData {
  Vec3 lo, hi;           // AABB of the members' positions
  Vec3 centroid;         // phi-weighted mean position
  double extent = 0;     // max distance of a member from the centroid
  double max_radius = 0; // largest member radius
  double phi = 0;        // sum of member phi
  Vec3 color;            // (n phi)-weighted mean of the members' linear colour times brightness
  double radius = 0;     // sqrt(sum of member radius^2): the area-equivalent radius for edges
  std::uint32_t count = 0;  // member particles
  ColourSpread spread;      // the (n phi)-weighted colour's spread (R1-RND-055)
};

struct NeuralField;
struct ContentScene;

struct Scene {
  // A number no other make_scene of this process returns: a backend may keep device copies of a
  // scene's particles and hierarchy under it (R1-RND-016). Code that changes a scene's positions,
  // radii, colours, shapes or hierarchy after make_scene sets it to 0 (no copies kept).
  std::uint64_t serial = 0;
  std::uint32_t n = 0;
  std::vector<Vec3> position;      // X'(p) in scene units
  std::vector<double> radius;      // r(p), scene units
  std::vector<double> phi;         // phi*(p)
  std::vector<Vec3> color;         // linear light colour (from color.rgb8) times brightness b(p)
  std::vector<Shape> shape;
  std::vector<std::string> label;  // title, else the first 8 hex digits of the id
  std::vector<double> u5;          // for stretched splats
  std::vector<double> degree;      // weighted degree on the layout graph
  std::vector<LayoutEdge> edges;
  std::array<std::vector<NodeData>, kLevels> nodes;
  const Hierarchy* hierarchy = nullptr;  // ids, children, parents (borrowed from the epoch)
  Vec3 centroid;                   // phi-weighted centroid of G (R-1.0 9.5)
  double tau0 = 1;                 // finest heat-kernel scale of the hierarchy, scene units^2
  double median_radius = 1;
  std::uint64_t seed = 0;          // counter-based jitter seed: the snapshot digest's first 8 bytes
  // The trained far field (R1-NRF-031), borrowed; null: the analytic field draws T-infinity.
  const NeuralField* neural = nullptr;
  // T0 content (R1-RND-130), borrowed; null: a particle above s_T0 is drawn as T1.
  const ContentScene* content = nullptr;
};

// b(p) = clamp((n phi / 1)^(1/4), 0.6, 3): brighter particles carry more focus (R1-RND-014).
double brightness(double n_phi);

Scene make_scene(const Epoch& e);

// Calls fn(p) for every member particle p of node `id` at `level`, in hierarchy order (children in
// order, level 0's particles in order).
template <class Fn>
void for_each_member(const Scene& s, int level, std::uint32_t id, Fn&& fn) {
  const auto& children = s.hierarchy->levels[static_cast<std::size_t>(level)][id].children;
  if (level == 0) {
    for (std::uint32_t p : children) fn(p);
    return;
  }
  for (std::uint32_t c : children) for_each_member(s, level - 1, c, fn);
}

// The largest |X'(p) - centroid| + r(p): the radius of the ball about the focus centroid that holds
// every particle.
double scene_extent(const Scene& s);

// The share of the focus the default views frame (R1-RND-007).
inline constexpr double kFramedFocus = 0.9;

// The radius of the smallest ball about the focus centroid whose particles (|X'(p) - c| + r(p)
// within it) hold `share` of the focus.
double focus_extent(const Scene& s, double share);

// R1-RND-007: the camera distance from the focus centroid at which the ball holding 90% of the
// focus fits the vertical field of view `fov_deg`, with 5% margin (the default orbit radius).
double fit_distance(const Scene& s, double fov_deg);

}  // namespace r1::render
