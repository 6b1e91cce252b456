// The analytic impostors: quartic roots, hits on the implicit surfaces, outward unit normals,
// analytic distances, silhouette areas, inside rays, the bounding sphere, the edge tube (R1-RND-030..036).
#include "shapes.hpp"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

namespace {

using r1::Shape;
using r1::render::Hit;
using r1::render::intersect_shape;
using r1::render::intersect_tube;
using r1::render::kTorusMajor;
using r1::render::kTorusMinor;
using r1::render::Ray;
using r1::render::solve_quartic;
using r1::render::Vec3;
using r1::render::kPi;

const double kSqrt3 = std::sqrt(3.0);
const double kSqrt2 = std::sqrt(2.0);
constexpr double kInf = std::numeric_limits<double>::infinity();

constexpr std::array<Shape, 6> kShapes = {Shape::kSphere,     Shape::kTorus,      Shape::kTetrahedron,
                                          Shape::kCube,       Shape::kOctahedron, Shape::kCylinder};

std::string name(Shape s) {
  switch (s) {
    case Shape::kSphere: return "sphere";
    case Shape::kTorus: return "torus";
    case Shape::kTetrahedron: return "tetrahedron";
    case Shape::kCube: return "cube";
    case Shape::kOctahedron: return "octahedron";
    case Shape::kCylinder: return "cylinder";
  }
  return "?";
}

// The shapes' definitions written independently of shapes.cpp: a signed function, negative inside,
// zero on the surface, of the position p relative to the centre in units of r. Each is a distance
// (or within a factor of order 1 of one) so one tolerance fits all.
double implicit(Shape s, const Vec3& p) {
  switch (s) {
    case Shape::kSphere: return r1::render::length(p) - 1;
    case Shape::kTorus: {
      const double rho = std::sqrt(p.x * p.x + p.y * p.y);
      return std::sqrt((rho - kTorusMajor) * (rho - kTorusMajor) + p.z * p.z) - kTorusMinor;
    }
    case Shape::kTetrahedron: {
      // Faces opposite the vertices v/sqrt3: distance of each face plane is 1/3.
      double f = -kInf;
      for (const Vec3 v : {Vec3{1, 1, 1}, Vec3{1, -1, -1}, Vec3{-1, 1, -1}, Vec3{-1, -1, 1}}) {
        f = std::max(f, -r1::render::dot(v, p) / kSqrt3 - 1.0 / 3);
      }
      return f;
    }
    case Shape::kCube: return std::max({std::fabs(p.x), std::fabs(p.y), std::fabs(p.z)}) - 1 / kSqrt3;
    case Shape::kOctahedron: return (std::fabs(p.x) + std::fabs(p.y) + std::fabs(p.z) - 1) / kSqrt3;
    case Shape::kCylinder:
      return std::max(std::sqrt(p.x * p.x + p.y * p.y) - 1 / kSqrt2, std::fabs(p.z) - 1 / kSqrt2);
  }
  return 0;
}

Vec3 random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0, 1);
  for (;;) {
    const Vec3 v{n(rng), n(rng), n(rng)};
    const double l = r1::render::length(v);
    if (l > 1e-3) return v / l;
  }
}

// ---- solve_quartic ---------------------------------------------------------------------------------

// Coefficients of the monic (x - a)(x - b)(x - c)(x - d).
std::array<double, 4> from_roots(double a, double b, double c, double d) {
  return {-(a + b + c + d), a * b + a * c + a * d + b * c + b * d + c * d, -(a * b * c + a * b * d + a * c * d + b * c * d),
          a * b * c * d};
}

// Coefficients of the monic (x - a)(x - b)(x^2 - 2 re x + re^2 + im^2).
std::array<double, 4> from_two_roots_and_pair(double a, double b, double re, double im) {
  const double s = a + b, p = a * b, u = -2 * re, v = re * re + im * im;
  // (x^2 - s x + p)(x^2 + u x + v)
  return {u - s, v - s * u + p, -s * v + p * u, p * v};
}

double rel_err(double got, double want) { return std::fabs(got - want) / std::max(1.0, std::fabs(want)); }

// Condition number of the real root x of prod (t - reals_j) (t^2 - 2 re t + re^2 + im^2) under
// relative perturbations of the coefficients as the test rounds them (each coefficient is a sum
// of products, so its error scales with the sum of their absolute values): the forward error of x
// relative to max(1, |x|) is about kappa * eps.
double kappa(double x, const std::vector<double>& reals, double re = 0, double im = -1) {
  const double ax = std::fabs(x);
  double abs_sum = 1, deriv = 1;  // prod (|x| + |x_j|) and |p'(x)|
  bool skipped = false;
  for (const double xj : reals) {
    abs_sum *= ax + std::fabs(xj);
    if (xj == x && !skipped) {
      skipped = true;
    } else {
      deriv *= std::fabs(x - xj);
    }
  }
  if (im >= 0) {
    abs_sum *= ax * ax + 2 * std::fabs(re) * ax + re * re + im * im;
    deriv *= (x - re) * (x - re) + im * im;
  }
  return abs_sum / (std::max(1.0, ax) * deriv);
}

// Backward stability, which holds however ill-conditioned the roots are: each returned root makes
// the quartic vanish to within a few roundings of its terms.
bool small_residual(const std::array<double, 4>& c, double x) {
  const double f = (((x + c[0]) * x + c[1]) * x + c[2]) * x + c[3];
  const double ax = std::fabs(x);
  const double scale = (((ax + std::fabs(c[0])) * ax + std::fabs(c[1])) * ax + std::fabs(c[2])) * ax + std::fabs(c[3]);
  return std::fabs(f) <= 64 * 0x1p-52 * scale;
}

// Roots in [-10, 10] on a 1e-3 grid. Always: the count and small residuals. Where the roots are
// well-conditioned (kappa <= 1e5, so rounding the coefficients moves them by < ~2e-11): 1e-9.
RC_GTEST_PROP(SolveQuartic, RecoversFourDistinctRealRoots, ()) {
  std::vector<double> want(4);
  for (double& x : want) x = *rc::gen::inRange(-10000, 10001) / 1000.0;
  std::sort(want.begin(), want.end());
  for (int i = 0; i < 3; ++i) RC_PRE(want[i + 1] - want[i] >= 0.05);  // distinct: double roots are SpecialForms
  const auto c = from_roots(want[0], want[1], want[2], want[3]);
  double got[4];
  RC_ASSERT(solve_quartic(c[0], c[1], c[2], c[3], got) == 4);
  for (int i = 0; i < 4; ++i) {
    RC_ASSERT(small_residual(c, got[i]));
    if (kappa(want[i], want) <= 1e5) RC_ASSERT(rel_err(got[i], want[i]) <= 1e-9);
  }
  RC_CLASSIFY(kappa(want[0], want) <= 1e5 && kappa(want[3], want) <= 1e5, "well-conditioned");
}

RC_GTEST_PROP(SolveQuartic, ComplexPairGivesTwoRoots, ()) {
  std::vector<double> want(2);
  for (double& x : want) x = *rc::gen::inRange(-10000, 10001) / 1000.0;
  std::sort(want.begin(), want.end());
  RC_PRE(want[1] - want[0] >= 0.05);
  const double re = *rc::gen::inRange(-10000, 10001) / 1000.0;
  const double im = *rc::gen::inRange(100, 10001) / 1000.0;  // |im| >= 0.1: clearly not real
  const auto c = from_two_roots_and_pair(want[0], want[1], re, im);
  double got[4];
  RC_ASSERT(solve_quartic(c[0], c[1], c[2], c[3], got) == 2);
  for (int i = 0; i < 2; ++i) {
    RC_ASSERT(small_residual(c, got[i]));
    if (kappa(want[i], want, re, im) <= 1e5) RC_ASSERT(rel_err(got[i], want[i]) <= 1e-9);
  }
}

RC_GTEST_PROP(SolveQuartic, TwoComplexPairsGiveNoRoot, ()) {
  const double re0 = *rc::gen::inRange(-10000, 10001) / 1000.0, im0 = *rc::gen::inRange(100, 10001) / 1000.0;
  const double re1 = *rc::gen::inRange(-10000, 10001) / 1000.0, im1 = *rc::gen::inRange(100, 10001) / 1000.0;
  // (x^2 + u0 x + v0)(x^2 + u1 x + v1)
  const double u0 = -2 * re0, v0 = re0 * re0 + im0 * im0, u1 = -2 * re1, v1 = re1 * re1 + im1 * im1;
  double got[4];
  RC_ASSERT(solve_quartic(u0 + u1, v0 + v1 + u0 * u1, u0 * v1 + u1 * v0, v0 * v1, got) == 0);
}

TEST(SolveQuartic, SpecialForms) {
  double got[4];
  // Biquadratic (x^2 - 1)(x^2 - 4): the odd coefficients vanish, the resolvent's alpha is 0.
  ASSERT_EQ(solve_quartic(0, -5, 0, 4, got), 4);
  const double bi[4] = {-2, -1, 1, 2};
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(got[i], bi[i], 1e-14);
  // x^4 = 0 and (x - 1)^4: a fourfold root comes back four times within the sqrt-eps^(1/4) limit.
  ASSERT_EQ(solve_quartic(0, 0, 0, 0, got), 4);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(got[i], 0);
  ASSERT_EQ(solve_quartic(-4, 6, -4, 1, got), 4);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(got[i], 1, 1e-3);
  // Two double roots (x - 1)^2 (x + 2)^2.
  const auto c = from_roots(1, 1, -2, -2);
  ASSERT_EQ(solve_quartic(c[0], c[1], c[2], c[3], got), 4);
  EXPECT_NEAR(got[0], -2, 1e-7);
  EXPECT_NEAR(got[1], -2, 1e-7);
  EXPECT_NEAR(got[2], 1, 1e-7);
  EXPECT_NEAR(got[3], 1, 1e-7);
  // x^4 + 1: no real root.
  EXPECT_EQ(solve_quartic(0, 0, 0, 1, got), 0);
}

// ---- every shape: random rays from outside ----------------------------------------------------------

struct Frame {
  Vec3 center{1.25, -3.5, 0.75};  // not the origin: the centre offset is part of what is tested
  double r = 2.5;
};

// A ray from a random point at distance 1.5 r..10 r aimed at a random point of the bounding ball,
// with a direction of random (not unit) length: intersect_shape must not assume |d| = 1.
Ray random_ray(std::mt19937_64& rng, const Frame& fr, bool unit) {
  std::uniform_real_distribution<double> u(0, 1);
  const Vec3 o = fr.center + random_unit(rng) * (fr.r * (1.5 + 8.5 * u(rng)));
  const Vec3 target = fr.center + random_unit(rng) * (fr.r * std::cbrt(u(rng)));
  const Vec3 d = r1::render::normalize(target - o) * (unit ? 1.0 : 0.25 + 4 * u(rng));
  return {o, d};
}

TEST(IntersectShape, HitsLieOnTheSurfaceWithOutwardUnitNormals) {
  const Frame fr;
  for (const Shape s : kShapes) {
    SCOPED_TRACE(name(s));
    std::mt19937_64 rng(0x5eed + static_cast<int>(s));
    int hits = 0;
    for (int i = 0; i < 20000; ++i) {
      const Ray ray = random_ray(rng, fr, i % 2 == 0);
      const auto hit = intersect_shape(s, fr.center, fr.r, ray, 0, kInf);
      if (!hit) continue;
      ++hits;
      const Vec3 p = (ray.at(hit->t) - fr.center) / fr.r;
      ASSERT_LE(std::fabs(implicit(s, p)), 1e-12) << "ray " << i;
      ASSERT_NEAR(r1::render::length(hit->normal), 1, 1e-14);
      ASSERT_LT(r1::render::dot(hit->normal, ray.d), 0) << "ray " << i;
      // Outward: a small step along the normal leaves the shape.
      ASSERT_GT(implicit(s, p + hit->normal * 1e-6), 0.5e-6 * 0.3);
      // Nearest: nothing in front of the hit; the range is open at t_max.
      ASSERT_FALSE(intersect_shape(s, fr.center, fr.r, ray, 0, hit->t)) << "ray " << i;
    }
    // The rays aim into the bounding ball; every shape fills a fair part of it.
    EXPECT_GT(hits, 20000 / 4);
  }
}

// The normal of a polytope hit is the normal of a face whose plane contains the hit; of a smooth
// surface, the normalised gradient of the implicit function (central differences).
TEST(IntersectShape, NormalsMatchTheGeometry) {
  const Frame fr;
  for (const Shape s : kShapes) {
    SCOPED_TRACE(name(s));
    std::mt19937_64 rng(0xface + static_cast<int>(s));
    for (int i = 0; i < 5000; ++i) {
      const Ray ray = random_ray(rng, fr, true);
      const auto hit = intersect_shape(s, fr.center, fr.r, ray, 0, kInf);
      if (!hit) continue;
      const Vec3 p = (ray.at(hit->t) - fr.center) / fr.r;
      const double e = 1e-7;
      Vec3 grad{implicit(s, p + Vec3{e, 0, 0}) - implicit(s, p - Vec3{e, 0, 0}),
                implicit(s, p + Vec3{0, e, 0}) - implicit(s, p - Vec3{0, e, 0}),
                implicit(s, p + Vec3{0, 0, e}) - implicit(s, p - Vec3{0, 0, e})};
      // Differences across an edge or rim mix two faces; a random hit lands within e of one
      // with probability ~1e-6, so skip the (rare) case where the gradient is not unit-length.
      const double gl = r1::render::length(grad) / (2 * e);
      if (std::fabs(gl - 1) > 1e-4) continue;
      grad = r1::render::normalize(grad);
      EXPECT_GT(r1::render::dot(grad, hit->normal), 1 - 1e-6) << "ray " << i;
    }
  }
}

// ---- analytic distances along axes --------------------------------------------------------------------

TEST(IntersectShape, AnalyticDistancesAlongAxes) {
  const Frame fr;
  const double r = fr.r;
  const double dist = 7.75;  // origin distance from the centre
  const double tol = 1e-14 * dist;
  const std::array<Vec3, 6> axes = {Vec3{1, 0, 0}, Vec3{-1, 0, 0}, Vec3{0, 1, 0},
                                    Vec3{0, -1, 0}, Vec3{0, 0, 1}, Vec3{0, 0, -1}};
  // Ray from centre - dist * dir towards the centre: the first surface point on the axis. Where
  // that point lies inside a face (not on a vertex or edge) its normal is -dir.
  auto t_along = [&](Shape s, const Vec3& dir, bool on_face = true) -> std::optional<double> {
    const auto hit = intersect_shape(s, fr.center, r, Ray{fr.center - dir * dist, dir}, 0, kInf);
    if (!hit) return std::nullopt;
    if (on_face) { EXPECT_NEAR(r1::render::dot(hit->normal, dir), -1, 1e-14) << name(s); }
    return hit->t;
  };
  for (const Vec3& ax : axes) {
    EXPECT_NEAR(*t_along(Shape::kSphere, ax), dist - r, tol);
    EXPECT_NEAR(*t_along(Shape::kCube, ax), dist - r / kSqrt3, tol);
    EXPECT_NEAR(*t_along(Shape::kOctahedron, ax, false), dist - r, tol);  // a vertex
  }
  EXPECT_EQ(*t_along(Shape::kSphere, {1, 0, 0}), dist - r);   // exact for these dyadic values
  EXPECT_EQ(*t_along(Shape::kOctahedron, {1, 0, 0}, false), dist - r);
  for (const Vec3& ax : {axes[0], axes[1], axes[2], axes[3]}) {
    EXPECT_NEAR(*t_along(Shape::kTorus, ax), dist - r, tol);                 // the outer equator
    EXPECT_NEAR(*t_along(Shape::kCylinder, ax), dist - r / kSqrt2, tol);     // the side wall
  }
  for (const Vec3& ax : {axes[4], axes[5]}) {
    EXPECT_FALSE(t_along(Shape::kTorus, ax));                                // through the hole
    EXPECT_NEAR(*t_along(Shape::kCylinder, ax), dist - r / kSqrt2, tol);     // a cap
  }
  // Torus along z through the tube's centre line at x = R: the top of the tube at z = a.
  {
    const Vec3 off{kTorusMajor * r, 0, 0};
    const auto hit = intersect_shape(Shape::kTorus, fr.center, r, Ray{fr.center + off - Vec3{0, 0, dist}, {0, 0, 1}}, 0, kInf);
    ASSERT_TRUE(hit);
    EXPECT_NEAR(hit->t, dist - kTorusMinor * r, tol);
  }
  // Diagonals: the cube's corner and the octahedron's face centre at r/sqrt3 on (1,1,1)/sqrt3.
  const Vec3 diag = r1::render::normalize(Vec3{1, 1, 1});
  EXPECT_NEAR(*t_along(Shape::kCube, diag, false), dist - r, 1e-13);  // a corner
  EXPECT_NEAR(*t_along(Shape::kOctahedron, diag), dist - r / kSqrt3, 1e-13);
  // Tetrahedron: coming down -(1,1,1) it meets the vertex r (1,1,1)/sqrt3; going up (1,1,1) it
  // meets the opposite face at distance r/3.
  EXPECT_NEAR(*t_along(Shape::kTetrahedron, -diag, false), dist - r, 1e-13);  // a vertex
  EXPECT_NEAR(*t_along(Shape::kTetrahedron, diag), dist - r / 3, 1e-13);
}

// ---- silhouette areas --------------------------------------------------------------------------------

// Fraction of an n x n grid of parallel rays along `axis` (0 x, 1 y, 2 z; pixel centres over the
// bounding square) that hit, times the square's area, in units of r^2.
double silhouette_area(Shape s, int axis, int n) {
  const Frame fr;
  const int u_axis = (axis + 1) % 3, v_axis = (axis + 2) % 3;
  auto put = [](Vec3& v, int k, double x) { (k == 0 ? v.x : (k == 1 ? v.y : v.z)) = x; };
  long hits = 0;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      Vec3 o, d;
      put(o, u_axis, fr.r * (-1 + (2 * i + 1) / static_cast<double>(n)));
      put(o, v_axis, fr.r * (-1 + (2 * j + 1) / static_cast<double>(n)));
      put(o, axis, -2 * fr.r);
      put(d, axis, 1);
      if (intersect_shape(s, fr.center, fr.r, Ray{fr.center + o, d}, 0, kInf)) ++hits;
    }
  }
  return 4.0 * static_cast<double>(hits) / (static_cast<double>(n) * n);
}

// Measured with a 1000 x 1000 grid: curved outlines agree to < 1e-4; straight outlines are
// quantised to whole pixels (the cube's side, 577.35 pixels, counts as 578; the octahedron's
// diagonal outline runs through rows of pixel centres, which count as hits), about 2e-3. The bound of 1% is far above both and far below any wrong geometry constant.
TEST(IntersectShape, SilhouetteAreasMatchProjections) {
  const double R = kTorusMajor, a = kTorusMinor;
  struct Case {
    Shape s;
    int axis;
    double area;  // units of r^2
  };
  const std::vector<Case> cases = {
      {Shape::kSphere, 0, kPi},
      {Shape::kSphere, 1, kPi},
      {Shape::kSphere, 2, kPi},
      {Shape::kTorus, 2, kPi * ((R + a) * (R + a) - (R - a) * (R - a))},  // an annulus
      {Shape::kTorus, 0, 4 * R * a + kPi * a * a},  // a stadium: discs of radius a along [-R, R]
      {Shape::kTorus, 1, 4 * R * a + kPi * a * a},
      {Shape::kCube, 0, 4.0 / 3},  // (2 r/sqrt3)^2
      {Shape::kCube, 1, 4.0 / 3},
      {Shape::kCube, 2, 4.0 / 3},
      {Shape::kTetrahedron, 0, 4.0 / 3},  // along any axis a square with corners (+-1, +-1) r/sqrt3
      {Shape::kTetrahedron, 1, 4.0 / 3},
      {Shape::kTetrahedron, 2, 4.0 / 3},
      {Shape::kOctahedron, 0, 2},  // the square |u| + |v| <= r
      {Shape::kOctahedron, 1, 2},
      {Shape::kOctahedron, 2, 2},
      {Shape::kCylinder, 2, kPi / 2},  // a disc of radius r/sqrt2
      {Shape::kCylinder, 0, 2},        // a rectangle 2 rc x 2 hc = 2 r^2
      {Shape::kCylinder, 1, 2},
  };
  for (const Case& c : cases) {
    const double got = silhouette_area(c.s, c.axis, 1000);
    const double err = (got - c.area) / c.area;
    std::printf("silhouette %-11s axis %c: area %.6f r^2, analytic %.6f, rel err %+.2e\n", name(c.s).c_str(),
                "xyz"[c.axis], got, c.area, err);
    EXPECT_LT(std::fabs(err), 0.01) << name(c.s) << " axis " << c.axis;
  }
}

// ---- inside rays -------------------------------------------------------------------------------------

TEST(IntersectShape, RaysFromInsideFindTheExit) {
  const Frame fr;
  std::mt19937_64 rng(0x1d5);
  for (const Shape s : kShapes) {
    SCOPED_TRACE(name(s));
    for (int i = 0; i < 2000; ++i) {
      const Vec3 dir = random_unit(rng);
      // Convex shapes: from the centre. Torus: from a point of its core circle.
      Vec3 start = fr.center;
      if (s == Shape::kTorus) {
        const double phi = 2 * kPi * std::uniform_real_distribution<double>(0, 1)(rng);
        start = fr.center + Vec3{std::cos(phi), std::sin(phi), 0} * (kTorusMajor * fr.r);
      }
      const Ray ray{start, dir};
      const auto hit = intersect_shape(s, fr.center, fr.r, ray, 0, kInf);
      ASSERT_TRUE(hit) << "ray " << i;
      const Vec3 p = (ray.at(hit->t) - fr.center) / fr.r;
      ASSERT_LE(std::fabs(implicit(s, p)), 1e-12);
      ASSERT_GT(r1::render::dot(hit->normal, dir), 0);  // leaving: the outward normal faces along the ray
      // The shape contains the ball of radius (inradius) around the start, and the exit lies in the
      // bounding ball (for the torus up to ~1.44 r away: a ray along a chord of the core circle).
      if (s == Shape::kTorus) { ASSERT_GE(hit->t, kTorusMinor * fr.r * (1 - 1e-12)); }
      if (s == Shape::kCube) { ASSERT_GE(hit->t, fr.r / kSqrt3 * (1 - 1e-12)); }
      if (s == Shape::kTetrahedron) { ASSERT_GE(hit->t, fr.r / 3 * (1 - 1e-12)); }
      ASSERT_LE(r1::render::length(p), 1 + 1e-12);
      if (s != Shape::kTorus) { ASSERT_LE(hit->t, fr.r * (1 + 1e-12)); }
    }
  }
  // Exactly: from the centre along +x, the sphere's exit is at r, the cube's at r/sqrt3.
  EXPECT_EQ(intersect_shape(Shape::kSphere, fr.center, fr.r, Ray{fr.center, {1, 0, 0}}, 0, kInf)->t, fr.r);
  EXPECT_NEAR(intersect_shape(Shape::kCube, fr.center, fr.r, Ray{fr.center, {1, 0, 0}}, 0, kInf)->t, fr.r / kSqrt3,
              1e-14);
}

// Excluding the entry with t_min finds the exit; t_max below the entry finds nothing.
TEST(IntersectShape, RangeSelectsTheNextHit) {
  const Frame fr;
  for (const Shape s : kShapes) {
    SCOPED_TRACE(name(s));
    const Vec3 dir{1, 0, 0};
    const Ray ray{fr.center - dir * 10.0, dir};
    const auto entry = intersect_shape(s, fr.center, fr.r, ray, 0, kInf);
    ASSERT_TRUE(entry);
    const auto next = intersect_shape(s, fr.center, fr.r, ray, entry->t, kInf);
    ASSERT_TRUE(next);
    EXPECT_GT(next->t, entry->t);
    EXPECT_GT(r1::render::dot(next->normal, dir), 0);  // an exit
    EXPECT_FALSE(intersect_shape(s, fr.center, fr.r, ray, 0, entry->t * (1 - 1e-9)));
    EXPECT_FALSE(intersect_shape(s, fr.center, fr.r, ray, next->t, next->t));  // empty range
  }
  // The torus along x crosses the tube twice: entry, exit, entry into the far side, exit.
  const Ray ray{fr.center - Vec3{10, 0, 0}, {1, 0, 0}};
  double t = 0;
  std::vector<double> ts;
  while (const auto h = intersect_shape(Shape::kTorus, fr.center, fr.r, ray, t, kInf)) ts.push_back(t = h->t);
  const double R = kTorusMajor * fr.r, a = kTorusMinor * fr.r;
  ASSERT_EQ(ts.size(), 4u);
  EXPECT_NEAR(ts[0], 10 - R - a, 1e-13);
  EXPECT_NEAR(ts[1], 10 - R + a, 1e-13);
  EXPECT_NEAR(ts[2], 10 + R - a, 1e-13);
  EXPECT_NEAR(ts[3], 10 + R + a, 1e-13);
}

// ---- the torus against a brute-force march (differential) --------------------------------------------

// March the implicit distance along the ray in steps of 1e-4 r across the bounding ball; where it
// changes sign, the quartic must have found the same crossing. Catches roots the solver loses.
TEST(IntersectShape, TorusAgreesWithMarching) {
  const Frame fr;
  std::mt19937_64 rng(0x7042);
  int compared = 0;
  for (int i = 0; i < 3000; ++i) {
    const Ray ray = random_ray(rng, fr, true);
    const Vec3 o = (ray.o - fr.center) / fr.r;
    const double b = r1::render::dot(o, ray.d);
    const double disc = b * b - (r1::render::dot(o, o) - 1);
    if (disc <= 0) continue;
    const double s0 = -b - std::sqrt(disc), s1 = -b + std::sqrt(disc);
    const double step = 1e-4;
    double prev = implicit(Shape::kTorus, o + ray.d * s0);
    std::optional<double> march;
    for (double s = s0 + step; s <= s1 + step; s += step) {
      const double f = implicit(Shape::kTorus, o + ray.d * s);
      if (prev > 0 && f <= 0) {
        march = s;
        break;
      }
      prev = f;
    }
    const auto hit = intersect_shape(Shape::kTorus, fr.center, fr.r, ray, 0, kInf);
    if (!march) {
      // No sign change seen: any hit is a graze dipping less than one step into the tube.
      if (hit) { EXPECT_LT(std::fabs(hit->t / fr.r - s0), s1 - s0 + step); }
      continue;
    }
    ++compared;
    ASSERT_TRUE(hit) << "ray " << i;
    EXPECT_LE(hit->t / fr.r, *march + 1e-9) << "ray " << i;
    EXPECT_GE(hit->t / fr.r, *march - step - 1e-9) << "ray " << i;
  }
  EXPECT_GT(compared, 1000);
}

// The ray origin's distance must not cost accuracy beyond what the direction's rounding implies
// (the quartic is formed at the bounding sphere's entry): the same line from 1000 r and from 2 r
// away gives the same hits.
TEST(IntersectShape, TorusFarOriginsMatchNearOrigins) {
  const Frame fr;
  std::mt19937_64 rng(0xfa7);
  std::uniform_real_distribution<double> u(0, 1);
  int hits = 0;
  for (int i = 0; i < 20000; ++i) {
    const Vec3 target = fr.center + random_unit(rng) * (fr.r * std::cbrt(u(rng)));
    const Vec3 dir = random_unit(rng);
    const Ray far{target - dir * (1000 * fr.r), dir}, near{target - dir * (2 * fr.r), dir};
    const auto hf = intersect_shape(Shape::kTorus, fr.center, fr.r, far, 0, kInf);
    const auto hn = intersect_shape(Shape::kTorus, fr.center, fr.r, near, 0, kInf);
    ASSERT_EQ(hf.has_value(), hn.has_value()) << "ray " << i;
    if (!hf) continue;
    ++hits;
    ASSERT_NEAR(hf->t - 998 * fr.r, hn->t, 1e-10 * fr.r) << "ray " << i;
    ASSERT_LE(std::fabs(implicit(Shape::kTorus, (far.at(hf->t) - fr.center) / fr.r)), 1e-11);
  }
  EXPECT_GT(hits, 10000);
}

// ---- bounding sphere -----------------------------------------------------------------------------------

RC_GTEST_PROP(IntersectShape, MissingTheBoundingSphereMissesEveryShape, ()) {
  const auto coord = [] { return *rc::gen::inRange(-100000, 100001) / 1000.0; };
  const Vec3 center{coord(), coord(), coord()};
  const double r = *rc::gen::inRange(1, 100001) / 1000.0;
  const Vec3 o{coord(), coord(), coord()};
  const Vec3 d{coord(), coord(), coord()};
  RC_PRE(r1::render::dot(d, d) > 1e-6);
  // Closest approach of the whole line (t over all reals) farther than r (with margin for rounding).
  const Vec3 oc = o - center;
  const Vec3 f = oc - d * (r1::render::dot(oc, d) / r1::render::dot(d, d));
  RC_PRE(r1::render::length(f) > r * (1 + 1e-9));
  for (const Shape s : kShapes) RC_ASSERT(!intersect_shape(s, center, r, Ray{o, d}, -kInf, kInf));
}

RC_GTEST_PROP(IntersectShape, HitsLieInTheBoundingBall, ()) {
  const auto coord = [] { return *rc::gen::inRange(-10000, 10001) / 1000.0; };
  const Vec3 center{coord(), coord(), coord()};
  const double r = *rc::gen::inRange(10, 10001) / 1000.0;
  const Vec3 o{coord(), coord(), coord()};
  const Vec3 d{coord(), coord(), coord()};
  RC_PRE(r1::render::dot(d, d) > 1e-6);
  for (const Shape s : kShapes) {
    const auto hit = intersect_shape(s, center, r, Ray{o, d}, -kInf, kInf);
    if (hit) { RC_ASSERT(r1::render::length(Ray{o, d}.at(hit->t) - center) <= r * (1 + 1e-9)); }
  }
}

// ---- intersect_tube --------------------------------------------------------------------------------------

TEST(IntersectTube, HitsTheWallBetweenTheEnds) {
  const Vec3 a{1, 2, 3}, b{5, 2, 3};  // along x, length 4
  const double radius = 0.5;
  // Perpendicular from above at x = 2: t = 10 - radius, u = 1/4, normal +z.
  const auto hit = intersect_tube(a, b, radius, Ray{{2, 2, 13}, {0, 0, -1}}, 0, kInf);
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->hit.t, 10 - radius);
  EXPECT_EQ(hit->u, 0.25);
  EXPECT_EQ(hit->hit.normal, (Vec3{0, 0, 1}));
  // Beyond the ends: miss.
  EXPECT_FALSE(intersect_tube(a, b, radius, Ray{{0.5, 2, 13}, {0, 0, -1}}, 0, kInf));
  EXPECT_FALSE(intersect_tube(a, b, radius, Ray{{5.5, 2, 13}, {0, 0, -1}}, 0, kInf));
  // Parallel to the axis: miss (inside or outside).
  EXPECT_FALSE(intersect_tube(a, b, radius, Ray{{-3, 2, 3}, {1, 0, 0}}, 0, kInf));
  EXPECT_FALSE(intersect_tube(a, b, radius, Ray{{-3, 2, 4}, {1, 0, 0}}, 0, kInf));
  // From the axis: the exit at t = radius with the normal along the ray.
  const auto in = intersect_tube(a, b, radius, Ray{{4, 2, 3}, {0, 1, 0}}, 0, kInf);
  ASSERT_TRUE(in);
  EXPECT_EQ(in->hit.t, radius);
  EXPECT_EQ(in->u, 0.75);
  EXPECT_EQ(in->hit.normal, (Vec3{0, 1, 0}));
  // Through the open end: the near wall crossing lies beyond the end, the far one is hit from inside.
  const Vec3 d = r1::render::normalize(Vec3{1, 0, -0.3});
  const auto end = intersect_tube(a, b, radius, Ray{Vec3{1, 2, 3} - d * 3.0, d}, 0, kInf);
  ASSERT_TRUE(end);
  EXPECT_LT(r1::render::dot(end->hit.normal, Vec3{0, 0, -1}), 1 + 1e-15);
  EXPECT_GT(r1::render::dot(end->hit.normal, Vec3{0, 0, -1}), 1 - 1e-12);
  EXPECT_GT(end->u, 0);
  EXPECT_LT(end->u, 1);
}

TEST(IntersectTube, RandomHitsLieOnTheWall) {
  std::mt19937_64 rng(0x70be);
  std::uniform_real_distribution<double> u(-5, 5);
  int hits = 0;
  for (int i = 0; i < 20000; ++i) {
    const Vec3 a{u(rng), u(rng), u(rng)}, b{u(rng), u(rng), u(rng)};
    const double radius = 0.05 + std::fabs(u(rng)) / 5;
    const Vec3 target = a + (b - a) * (0.5 + u(rng) / 8) + random_unit(rng) * radius * 1.2;
    const Vec3 o = target + random_unit(rng) * 20.0;
    const Ray ray{o, r1::render::normalize(target - o)};
    const auto hit = intersect_tube(a, b, radius, ray, 0, kInf);
    if (!hit) continue;
    ++hits;
    ASSERT_GE(hit->u, 0);
    ASSERT_LE(hit->u, 1);
    const Vec3 p = ray.at(hit->hit.t);
    const Vec3 axis_pt = a + (b - a) * hit->u;
    const Vec3 radial = p - axis_pt;
    ASSERT_NEAR(r1::render::length(radial), radius, 1e-12 * 20);
    ASSERT_NEAR(r1::render::dot(radial, b - a), 0, 1e-11 * 20);  // u is the foot of the perpendicular
    ASSERT_NEAR(r1::render::length(hit->hit.normal), 1, 1e-14);
    ASSERT_GT(r1::render::dot(hit->hit.normal, radial), 0);  // away from the axis
    ASSERT_FALSE(intersect_tube(a, b, radius, ray, 0, hit->hit.t));  // nearest
  }
  EXPECT_GT(hits, 10000);
}

}  // namespace
