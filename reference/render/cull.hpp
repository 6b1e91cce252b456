// Projected size, tiers and culling (R-1.0 6, 10.3; spec/render.md R1-RND-020..026).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "scene.hpp"
#include "view.hpp"
#include "r1/spec/status.hpp"

namespace r1::render {

enum class Tier : std::uint8_t { kT0 = 0, kT1 = 1, kT2 = 2, kT3 = 3, kTinf = 4 };

// s_p: the screen diameter in pixels of a sphere of radius r at view depth z > 0 (R1-RND-020):
// 2 r focal_px / z.
double screen_diameter(double r, double depth, const CameraFrame& f);

// R1-RND-021: T0 above t0, T1 in (t1, t0], T2 in (t2, t1], T3 in (t3, t2], T-inf at or below t3.
Tier tier_of(double s, const Tiers& t);

// The view frustum: four side planes through the camera and a near plane, normals inward.
struct Frustum {
  std::array<Vec3, 5> normal;
  std::array<double, 5> offset;  // a point x is inside plane k when dot(normal[k], x) + offset[k] >= 0
};
inline constexpr double kNear = 1e-3;  // near plane distance, scene units
Frustum make_frustum(const View& v, const CameraFrame& f);

// R1-RND-022: a sphere (c, r) is visible when no frustum plane has it wholly outside.
bool sphere_visible(const Frustum& fr, const Vec3& c, double r);

struct Visible {
  std::uint32_t particle = 0;
  double depth = 0;  // view depth of the centre
  double s = 0;      // screen diameter, pixels
  Tier tier = Tier::kTinf;
};

// Particle p's view depth, screen diameter (1e300 when its sphere reaches the near plane) and tier.
Visible classify(const Scene& s, const View& v, const CameraFrame& f, std::uint32_t p);

// The pixel rectangle [x0, x1) x [y0, y1) that holds every pixel whose centre sees the projection
// of a box (clamped to the image); the whole image when part of the box lies at or behind the
// near plane.
struct Rect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  bool empty() const { return x0 >= x1 || y0 >= y1; }
};
Rect project_box(const View& v, const CameraFrame& f, const Vec3& lo, const Vec3& hi);

struct CullStats {
  std::uint64_t nodes_tested = 0, nodes_culled = 0, particles_tested = 0;
};

// A node's standing in the far field this frame (R1-RND-025), from its box and largest member
// radius alone, so it costs the same whatever the node holds:
//  - kFar: every member lies beyond the near plane and projects at or below t3 - band pixels, so
//    every member is T-infinity with field weight exactly 1 (R1-RND-045);
//  - kBehind: every member lies at or before the near plane (field weight 0);
//  - kMixed: neither is certain.
// The bounds carry a slack covering the rounding of the per-particle depth and size, so kFar and
// kBehind never claim what the per-particle computation would not give.
enum class FarClass : std::uint8_t { kMixed = 0, kFar = 1, kBehind = 2 };
FarClass far_class(const NodeData& d, const View& v, const CameraFrame& f);

// A node of the hierarchy whose members are all visible and kFar: the frame draws it through the
// field's aggregates and never lists its members (R1-RND-025).
struct FarNode {
  int level = 0;
  std::uint32_t id = 0;
};

struct CullResult {
  std::vector<Visible> visible;  // ascending particle order, members of `far` nodes left out
  std::vector<FarNode> far;      // in walk order
  std::uint64_t far_particles = 0;  // members of the far nodes
};

// The frame's cull (R1-RND-025): the hierarchy walk of `cull`, stopping at nodes wholly inside the
// frustum whose class is kFar. A pure far view costs the nodes walked, not the particles.
CullResult cull_frame(const Scene& s, const View& v, const CameraFrame& f, CullStats* stats = nullptr);

// Whether a backend's cull result (R1-RND-074) has the shape of cull_frame's: visible particles
// strictly ascending and below |P|, tiers T0..T-inf, far nodes that exist, far_particles their
// members' count. An internal error naming the first fault otherwise.
Status check_cull_result(const Scene& s, const CullResult& r);

// Every particle whose bounding sphere is visible, in ascending particle order. The hierarchy walk
// (R1-RND-023) tests node boxes grown by their largest member radius and skips what lies wholly
// outside; it returns exactly what the brute-force test over all particles returns.
std::vector<Visible> cull(const Scene& s, const View& v, const CameraFrame& f, CullStats* stats = nullptr);
std::vector<Visible> cull_brute_force(const Scene& s, const View& v, const CameraFrame& f);

}  // namespace r1::render
