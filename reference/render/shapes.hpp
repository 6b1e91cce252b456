// Analytic impostors of tiers T1/T2 (R-1.0 6.3, spec/render.md R1-RND-030..036): exact ray
// intersection with the six particle shapes, each inscribed in the particle's bounding sphere of
// radius r centred on X'(p) and axis-aligned in scene coordinates, plus the capsule-free open
// tube used for edges. Every function returns the nearest hit with t in (t_min, t_max), or none.
#pragma once

#include <optional>

#include "r1/spec/epoch.hpp"
#include "r1/spec/vec3.hpp"

namespace r1::render {

struct Hit {
  double t = 0;  // ray parameter of the hit
  Vec3 normal;   // unit outward normal at the hit
};

// Shape geometry relative to the bounding radius r (all documented in R1-RND-031):
//   sphere      radius r
//   torus       axis z, major radius kTorusMajor * r, minor radius kTorusMinor * r (R + a = r)
//   tetrahedron regular, vertices r (+1,+1,+1)/sqrt3, r (+1,-1,-1)/sqrt3, r (-1,+1,-1)/sqrt3, r (-1,-1,+1)/sqrt3
//   cube        axis-aligned, half side r / sqrt3 (corners on the sphere)
//   octahedron  |x| + |y| + |z| <= r
//   cylinder    axis z, radius r / sqrt2, half height r / sqrt2 (rims on the sphere)
inline constexpr double kTorusMajor = 0.65;
inline constexpr double kTorusMinor = 0.35;

std::optional<Hit> intersect_shape(Shape shape, const Vec3& center, double r, const Ray& ray, double t_min, double t_max);

// An open cylinder (tube) of radius `radius` around the segment a..b, no caps: edges (R-1.0 8.1).
// `u` of the hit is its parameter along the segment in [0, 1] (for the flow-strip texture).
struct TubeHit {
  Hit hit;
  double u = 0;
};
std::optional<TubeHit> intersect_tube(const Vec3& a, const Vec3& b, double radius, const Ray& ray, double t_min, double t_max);

// The real roots of the monic quartic x^4 + c3 x^3 + c2 x^2 + c1 x + c0, ascending, each polished
// by Newton steps (the ray-torus equation). Returns how many were written to `roots`.
int solve_quartic(double c3, double c2, double c1, double c0, double roots[4]);

}  // namespace r1::render
