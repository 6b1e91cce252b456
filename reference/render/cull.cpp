// Projected size, tiers, frustum culling by the hierarchy (R1-RND-020..026).
#include "cull.hpp"

#include <algorithm>
#include <cmath>

namespace r1::render {

double screen_diameter(double r, double depth, const CameraFrame& f) { return 2.0 * r * f.focal_px / depth; }

Tier tier_of(double s, const Tiers& t) {
  if (s > t.t0) return Tier::kT0;
  if (s > t.t1) return Tier::kT1;
  if (s > t.t2) return Tier::kT2;
  if (s > t.t3) return Tier::kT3;
  return Tier::kTinf;
}

Frustum make_frustum(const View& v, const CameraFrame& f) {
  Frustum fr;
  const Vec3 o = v.camera.position;
  const double ty = f.tan_half_fov, tx = f.tan_half_fov * v.width / v.height;
  // Side planes contain the camera and two image-corner directions; normals point inward.
  const Vec3 left = f.forward * tx + f.right, right = f.forward * tx - f.right;
  const Vec3 bottom = f.forward * ty + f.up, top = f.forward * ty - f.up;
  const std::array<Vec3, 4> side = {left, right, bottom, top};
  for (int k = 0; k < 4; ++k) {
    fr.normal[static_cast<std::size_t>(k)] = normalize(side[static_cast<std::size_t>(k)]);
    fr.offset[static_cast<std::size_t>(k)] = -dot(fr.normal[static_cast<std::size_t>(k)], o);
  }
  fr.normal[4] = f.forward;
  fr.offset[4] = -dot(f.forward, o) - kNear;
  return fr;
}

bool sphere_visible(const Frustum& fr, const Vec3& c, double r) {
  for (std::size_t k = 0; k < 5; ++k)
    if (dot(fr.normal[k], c) + fr.offset[k] < -r) return false;
  return true;
}

namespace {

// A box grown by g: wholly outside a plane when its corner farthest along the normal is outside
// by more than g.
bool box_outside(const Frustum& fr, const Vec3& lo, const Vec3& hi, double g) {
  for (std::size_t k = 0; k < 5; ++k) {
    const Vec3& nrm = fr.normal[k];
    const Vec3 far{nrm.x >= 0 ? hi.x : lo.x, nrm.y >= 0 ? hi.y : lo.y, nrm.z >= 0 ? hi.z : lo.z};
    // The slack covers the rounding of the two dot products, so a member the leaf test would keep
    // is never culled here (the walk must equal the brute-force test, R1-RND-023).
    const double slack = 1e-9 * (1.0 + std::fabs(fr.offset[k]) + std::fabs(far.x) + std::fabs(far.y) + std::fabs(far.z));
    if (dot(nrm, far) + fr.offset[k] < -g - slack) return true;
  }
  return false;
}

Visible classify(const Scene& s, const View& v, const CameraFrame& f, std::uint32_t p) {
  Visible out;
  out.particle = p;
  out.depth = dot(s.position[p] - v.camera.position, f.forward);
  // A sphere reaching behind the near plane has no finite screen size: it counts as the largest.
  out.s = out.depth > s.radius[p] + kNear ? screen_diameter(s.radius[p], out.depth, f) : 1e300;
  out.tier = tier_of(out.s, v.tiers);
  return out;
}

}  // namespace

std::vector<Visible> cull(const Scene& s, const View& v, const CameraFrame& f, CullStats* stats) {
  const Frustum fr = make_frustum(v, f);
  std::vector<Visible> out;
  CullStats local;
  // Depth-first from every top-level node. A box wholly outside by more than its largest member
  // radius holds no visible sphere (each member's centre lies in the box); the per-particle test at
  // the leaves is the brute-force test itself, so both return the same set.
  std::vector<std::pair<int, std::uint32_t>> stack;
  const auto& top = s.nodes[kLevels - 1];
  for (std::uint32_t id = static_cast<std::uint32_t>(top.size()); id-- > 0;) stack.push_back({kLevels - 1, id});
  while (!stack.empty()) {
    const auto [l, id] = stack.back();
    stack.pop_back();
    const NodeData& d = s.nodes[static_cast<std::size_t>(l)][id];
    ++local.nodes_tested;
    if (box_outside(fr, d.lo, d.hi, d.max_radius)) {
      ++local.nodes_culled;
      continue;
    }
    const auto& children = s.hierarchy->levels[static_cast<std::size_t>(l)][id].children;
    if (l == 0) {
      for (std::uint32_t p : children) {
        ++local.particles_tested;
        if (sphere_visible(fr, s.position[p], s.radius[p])) out.push_back(classify(s, v, f, p));
      }
    } else {
      for (std::size_t c = children.size(); c-- > 0;) stack.push_back({l - 1, children[c]});
    }
  }
  std::sort(out.begin(), out.end(), [](const Visible& a, const Visible& b) { return a.particle < b.particle; });
  if (stats) *stats = local;
  return out;
}

std::vector<Visible> cull_brute_force(const Scene& s, const View& v, const CameraFrame& f) {
  const Frustum fr = make_frustum(v, f);
  std::vector<Visible> out;
  for (std::uint32_t p = 0; p < s.n; ++p)
    if (sphere_visible(fr, s.position[p], s.radius[p])) out.push_back(classify(s, v, f, p));
  return out;
}

}  // namespace r1::render
