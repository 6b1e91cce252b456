// Projected size, tiers, frustum culling by the hierarchy (R1-RND-020..026).
#include "cull.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

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

double l1(const Vec3& a) { return std::fabs(a.x) + std::fabs(a.y) + std::fabs(a.z); }

// The rounding allowance of a plane or depth test over coordinates of this magnitude: a member the
// per-particle test would keep is never culled or misclassified by a box test (R1-RND-023, 025).
double slack_of(double magnitude) { return 1e-9 * (1.0 + magnitude); }

// A box grown by g: wholly outside a plane when its corner farthest along the normal is outside
// by more than g.
bool box_outside(const Frustum& fr, const Vec3& lo, const Vec3& hi, double g) {
  for (std::size_t k = 0; k < 5; ++k) {
    const Vec3& nrm = fr.normal[k];
    const Vec3 far{nrm.x >= 0 ? hi.x : lo.x, nrm.y >= 0 ? hi.y : lo.y, nrm.z >= 0 ? hi.z : lo.z};
    // The slack covers the rounding of the two dot products, so a member the leaf test would keep
    // is never culled here (the walk must equal the brute-force test, R1-RND-023).
    if (dot(nrm, far) + fr.offset[k] < -g - slack_of(std::fabs(fr.offset[k]) + l1(far))) return true;
  }
  return false;
}

// Whether every point of the box lies inside every frustum plane (so every member's sphere is
// visible: its centre is inside).
bool box_inside(const Frustum& fr, const Vec3& lo, const Vec3& hi) {
  for (std::size_t k = 0; k < 5; ++k) {
    const Vec3& nrm = fr.normal[k];
    const Vec3 near{nrm.x >= 0 ? lo.x : hi.x, nrm.y >= 0 ? lo.y : hi.y, nrm.z >= 0 ? lo.z : hi.z};
    if (dot(nrm, near) + fr.offset[k] < slack_of(std::fabs(fr.offset[k]) + l1(near))) return false;
  }
  return true;
}

}  // namespace

Visible classify(const Scene& s, const View& v, const CameraFrame& f, std::uint32_t p) {
  Visible out;
  out.particle = p;
  out.depth = dot(s.position[p] - v.camera.position, f.forward);
  // A sphere reaching behind the near plane has no finite screen size: it counts as the largest.
  out.s = out.depth > s.radius[p] + kNear ? screen_diameter(s.radius[p], out.depth, f) : 1e300;
  out.tier = tier_of(out.s, v.tiers);
  return out;
}

Rect project_box(const View& v, const CameraFrame& f, const Vec3& lo, const Vec3& hi) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  double minx = kInf, miny = kInf, maxx = -kInf, maxy = -kInf;
  for (int c = 0; c < 8; ++c) {
    const Vec3 corner{c & 1 ? hi.x : lo.x, c & 2 ? hi.y : lo.y, c & 4 ? hi.z : lo.z};
    const Projected p = project(v, f, corner);
    if (p.depth <= kNear) return {0, 0, v.width, v.height};
    minx = std::min(minx, p.px), maxx = std::max(maxx, p.px);
    miny = std::min(miny, p.py), maxy = std::max(maxy, p.py);
  }
  const auto clampi = [](double d, int top) { return static_cast<int>(std::clamp(d, 0.0, static_cast<double>(top))); };
  return {clampi(std::floor(minx), v.width), clampi(std::floor(miny), v.height), clampi(std::ceil(maxx) + 1, v.width),
          clampi(std::ceil(maxy) + 1, v.height)};
}

FarClass far_class(const NodeData& d, const View& v, const CameraFrame& f) {
  // The box's least and greatest view depth, widened by the rounding of a member's depth.
  const Vec3& fw = f.forward;
  const Vec3 o = v.camera.position;
  const Vec3 near{fw.x >= 0 ? d.lo.x : d.hi.x, fw.y >= 0 ? d.lo.y : d.hi.y, fw.z >= 0 ? d.lo.z : d.hi.z};
  const Vec3 far{fw.x >= 0 ? d.hi.x : d.lo.x, fw.y >= 0 ? d.hi.y : d.lo.y, fw.z >= 0 ? d.hi.z : d.lo.z};
  const double slack = slack_of(l1(d.lo) + l1(d.hi) + l1(o));
  const double depth_min = dot(near - o, fw) - slack, depth_max = dot(far - o, fw) + slack;
  if (depth_max <= kNear) return FarClass::kBehind;
  if (!(depth_min > d.max_radius + kNear)) return FarClass::kMixed;
  // The largest member's size at the least depth bounds every member's (relative rounding 1e-9).
  const double s_max = screen_diameter(d.max_radius, depth_min, f) * (1 + 1e-9);
  return s_max <= v.tiers.t3 - v.tiers.band ? FarClass::kFar : FarClass::kMixed;
}

CullResult cull_frame(const Scene& s, const View& v, const CameraFrame& f, CullStats* stats) {
  const Frustum fr = make_frustum(v, f);
  CullResult result;
  std::vector<Visible>& out = result.visible;
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
    if (box_inside(fr, d.lo, d.hi) && far_class(d, v, f) == FarClass::kFar) {
      result.far.push_back({l, id});
      result.far_particles += d.count;
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
  return result;
}

Status check_cull_result(const Scene& s, const CullResult& r) {
  for (std::size_t i = 0; i < r.visible.size(); ++i) {
    const Visible& vis = r.visible[i];
    if (vis.particle >= s.n || (i > 0 && vis.particle <= r.visible[i - 1].particle))
      return Status::internal("cull pass: visible entry " + std::to_string(i) + " (particle " + std::to_string(vis.particle) +
                              ") is not in ascending particle order below " + std::to_string(s.n));
    if (static_cast<int>(vis.tier) > static_cast<int>(Tier::kTinf))
      return Status::internal("cull pass: particle " + std::to_string(vis.particle) + " has no tier");
  }
  std::uint64_t members = 0;
  for (const FarNode& node : r.far) {
    if (node.level < 0 || node.level >= kLevels || node.id >= s.nodes[static_cast<std::size_t>(node.level)].size())
      return Status::internal("cull pass: far node " + std::to_string(node.id) + " of level " + std::to_string(node.level) +
                              " does not exist");
    members += s.nodes[static_cast<std::size_t>(node.level)][node.id].count;
  }
  if (members != r.far_particles)
    return Status::internal("cull pass: " + std::to_string(r.far_particles) + " far particles, the far nodes hold " +
                            std::to_string(members));
  return Status::ok();
}

std::vector<Visible> cull(const Scene& s, const View& v, const CameraFrame& f, CullStats* stats) {
  CullResult r = cull_frame(s, v, f, stats);
  for (const FarNode& node : r.far) {
    for_each_member(s, node.level, node.id, [&](std::uint32_t p) { r.visible.push_back(classify(s, v, f, p)); });
    if (stats) stats->particles_tested += s.nodes[static_cast<std::size_t>(node.level)][node.id].count;
  }
  std::sort(r.visible.begin(), r.visible.end(), [](const Visible& a, const Visible& b) { return a.particle < b.particle; });
  return std::move(r.visible);
}

std::vector<Visible> cull_brute_force(const Scene& s, const View& v, const CameraFrame& f) {
  const Frustum fr = make_frustum(v, f);
  std::vector<Visible> out;
  for (std::uint32_t p = 0; p < s.n; ++p)
    if (sphere_visible(fr, s.position[p], s.radius[p])) out.push_back(classify(s, v, f, p));
  return out;
}

}  // namespace r1::render
