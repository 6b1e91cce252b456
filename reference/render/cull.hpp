// Projected size, tiers and culling (R-1.0 6, 10.3; spec/render.md R1-RND-020..026).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "scene.hpp"
#include "view.hpp"

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

struct CullStats {
  std::uint64_t nodes_tested = 0, nodes_culled = 0, particles_tested = 0;
};

// Every particle whose bounding sphere is visible, in ascending particle order. The hierarchy walk
// (R1-RND-023) tests node boxes grown by their largest member radius and skips what lies wholly
// outside; it returns exactly what the brute-force test over all particles returns.
std::vector<Visible> cull(const Scene& s, const View& v, const CameraFrame& f, CullStats* stats = nullptr);
std::vector<Visible> cull_brute_force(const Scene& s, const View& v, const CameraFrame& f);

}  // namespace r1::render
