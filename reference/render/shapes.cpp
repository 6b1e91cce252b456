// Analytic ray intersection with the six particle impostors, the edge tube and the quartic solver (R1-RND-030..036).
#include "shapes.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace r1::render {

namespace {

// 1/sqrt(3) and 1/sqrt(2) as decimal literals the compiler rounds correctly (std::sqrt is not
// constexpr in C++20); they scale the shape definitions of shapes.hpp.
constexpr double kInvSqrt3 = 0.57735026918962576450914878050196;
constexpr double kInvSqrt2 = 0.70710678118654752440084436210485;
constexpr double kInf = std::numeric_limits<double>::infinity();

// Newton steps that polish a root: a handful suffices from a Ferrari/Cardano estimate (quadratic
// convergence); more only burn time on roots already at the rounding floor.
constexpr int kPolishSteps = 8;

// The real roots of a x^2 + 2 bh x + c = 0 (a > 0) given disc = bh^2 - a c computed by the caller
// (callers compute it geometrically to avoid the cancellation of bh^2 - a c). Ascending. The root
// of larger magnitude comes from q = -(bh + sign(bh) sqrt(disc)), the other from c / q: neither
// subtracts nearly equal numbers.
int quadratic_roots(double a, double bh, double c, double disc, double roots[2]) {
  if (!(disc >= 0)) return 0;  // negative or NaN: no real root (grazing rays count as misses)
  const double s = std::sqrt(disc);
  const double q = -(bh + std::copysign(s, bh));
  if (q == 0) {  // bh == 0 and disc == 0, so c == 0: a double root at 0
    roots[0] = roots[1] = 0;
    return 2;
  }
  double x0 = q / a, x1 = c / q;
  if (x0 > x1) std::swap(x0, x1);
  roots[0] = x0;
  roots[1] = x1;
  return 2;
}

// ---- convex polytopes: Kay-Kajiya clipping against half-spaces n.x <= h -------------------------

struct HalfSpace {
  Vec3 n;      // integer-valued, not unit: keeps n.o and n.d exact for axis-aligned rays
  double h;    // offset in units of r
  double inv;  // 1 / |n|, turns n into the unit outward normal of the face
};

// Tetrahedron: the face opposite vertex s_i (s_i in {(1,1,1), (1,-1,-1), (-1,1,-1), (-1,-1,1)}, times
// r/sqrt3) has outward unit normal -s_i/sqrt3 at distance r/3, i.e. -s_i . x <= r/sqrt3.
constexpr std::array<HalfSpace, 4> kTetrahedron = {{
    {{-1, -1, -1}, kInvSqrt3, kInvSqrt3},
    {{-1, +1, +1}, kInvSqrt3, kInvSqrt3},
    {{+1, -1, +1}, kInvSqrt3, kInvSqrt3},
    {{+1, +1, -1}, kInvSqrt3, kInvSqrt3},
}};
// Cube: |x_k| <= r/sqrt3.
constexpr std::array<HalfSpace, 6> kCube = {{
    {{+1, 0, 0}, kInvSqrt3, 1},
    {{-1, 0, 0}, kInvSqrt3, 1},
    {{0, +1, 0}, kInvSqrt3, 1},
    {{0, -1, 0}, kInvSqrt3, 1},
    {{0, 0, +1}, kInvSqrt3, 1},
    {{0, 0, -1}, kInvSqrt3, 1},
}};
// Octahedron: |x| + |y| + |z| <= r, one half-space per sign pattern.
constexpr std::array<HalfSpace, 8> kOctahedron = {{
    {{+1, +1, +1}, 1, kInvSqrt3},
    {{+1, +1, -1}, 1, kInvSqrt3},
    {{+1, -1, +1}, 1, kInvSqrt3},
    {{+1, -1, -1}, 1, kInvSqrt3},
    {{-1, +1, +1}, 1, kInvSqrt3},
    {{-1, +1, -1}, 1, kInvSqrt3},
    {{-1, -1, +1}, 1, kInvSqrt3},
    {{-1, -1, -1}, 1, kInvSqrt3},
}};

// The parameter interval [t_enter, t_exit] of a ray inside a convex body, with the outward unit
// normals of the surfaces where it enters and leaves.
struct Span {
  double t_enter = -kInf, t_exit = kInf;
  Vec3 n_enter, n_exit;
  bool empty = false;
};

// Clips the span by one half-space n.x <= h (x = o + t d relative to the centre). Ties keep the
// earlier constraint: at an edge or corner every adjacent face normal is a valid normal, and a
// fixed order makes the choice deterministic.
void clip(Span& span, const Vec3& n, double h, const Vec3& unit_n, const Vec3& o, const Vec3& d) {
  const double denom = dot(n, d);
  const double num = h - dot(n, o);
  if (denom == 0) {  // parallel to the plane: the ray is inside the slab for all t or for none
    if (num < 0) span.empty = true;
    return;
  }
  const double t = num / denom;
  if (denom < 0) {
    if (t > span.t_enter) {
      span.t_enter = t;
      span.n_enter = unit_n;
    }
  } else if (t < span.t_exit) {
    span.t_exit = t;
    span.n_exit = unit_n;
  }
}

// The nearest of the span's two boundary hits in (t_min, t_max): the entry, or the exit when the
// entry lies at or before t_min (a ray starting inside the body).
std::optional<Hit> span_hit(const Span& span, double t_min, double t_max) {
  if (span.empty || !(span.t_enter <= span.t_exit)) return std::nullopt;
  if (span.t_enter > t_min && span.t_enter < t_max) return Hit{span.t_enter, span.n_enter};
  if (span.t_enter <= t_min && span.t_exit > t_min && span.t_exit < t_max) return Hit{span.t_exit, span.n_exit};
  return std::nullopt;
}

template <std::size_t N>
std::optional<Hit> intersect_polytope(const std::array<HalfSpace, N>& faces, const Vec3& o, double r, const Vec3& d,
                                      double t_min, double t_max) {
  Span span;
  for (const HalfSpace& f : faces) {
    clip(span, f.n, f.h * r, f.n * f.inv, o, d);
    if (span.empty) return std::nullopt;
  }
  return span_hit(span, t_min, t_max);
}

// ---- sphere ------------------------------------------------------------------------------------

std::optional<Hit> intersect_sphere(const Vec3& o, double r, const Vec3& d, double t_min, double t_max) {
  const double a = dot(d, d);
  const double bh = dot(o, d);
  const double c = dot(o, o) - r * r;
  // disc = bh^2 - a c = a (r^2 - |f|^2), f the offset of the closest approach from the centre: no
  // cancellation of two large squares for far rays (Haines et al., Ray Tracing Gems ch. 7).
  const Vec3 f = o - d * (bh / a);
  const double disc = a * (r * r - dot(f, f));
  double t[2];
  if (quadratic_roots(a, bh, c, disc, t) == 0) return std::nullopt;
  for (const double ti : t) {
    if (ti > t_min && ti < t_max) return Hit{ti, normalize(o + d * ti)};
  }
  return std::nullopt;
}

// ---- cylinder with caps --------------------------------------------------------------------------

std::optional<Hit> intersect_cylinder(const Vec3& o, double r, const Vec3& d, double t_min, double t_max) {
  const double rc = r * kInvSqrt2;  // radius and half height: the rims lie on the bounding sphere
  Span span;
  clip(span, {0, 0, +1}, rc, {0, 0, +1}, o, d);
  clip(span, {0, 0, -1}, rc, {0, 0, -1}, o, d);
  if (span.empty) return std::nullopt;
  // The infinite cylinder x^2 + y^2 <= rc^2 as the span between the two roots of a quadratic.
  const double a = d.x * d.x + d.y * d.y;
  const double c = o.x * o.x + o.y * o.y - rc * rc;
  if (a == 0) {  // parallel to the axis: inside the side wall for all t or for none
    if (c > 0) return std::nullopt;
  } else {
    const double bh = o.x * d.x + o.y * d.y;
    const double fx = o.x - d.x * (bh / a), fy = o.y - d.y * (bh / a);
    double t[2];
    if (quadratic_roots(a, bh, c, a * (rc * rc - (fx * fx + fy * fy)), t) == 0) return std::nullopt;
    // Ties at the rim keep the cap (clipped first), as in clip().
    if (t[0] > span.t_enter) {
      span.t_enter = t[0];
      const Vec3 p = o + d * t[0];
      span.n_enter = normalize(Vec3{p.x, p.y, 0});
    }
    if (t[1] < span.t_exit) {
      span.t_exit = t[1];
      const Vec3 p = o + d * t[1];
      span.n_exit = normalize(Vec3{p.x, p.y, 0});
    }
  }
  return span_hit(span, t_min, t_max);
}

// ---- torus ---------------------------------------------------------------------------------------

// The implicit torus (|x|^2 + R^2 - a^2)^2 - 4 R^2 (x^2 + y^2) in units of r: negative inside.
double torus_implicit(const Vec3& p) {
  const double rr = kTorusMajor * kTorusMajor;
  const double k = dot(p, p) + rr - kTorusMinor * kTorusMinor;
  return k * k - 4 * rr * (p.x * p.x + p.y * p.y);
}

// A root is accepted when the implicit function at its point is below this (units of r; the
// function's terms are of order 1 and |grad| ~ 8 R^2 a ~ 1.2 at the surface, so this is a distance
// of about 1e-9 r). Newton-polished true roots sit near 1e-15; Ferrari garbage lies far above.
constexpr double kTorusResidual = 1e-9;

std::optional<Hit> intersect_torus(const Vec3& o_world, double r, const Vec3& d_world, double t_min, double t_max) {
  // Work in units of r along a unit direction: the quartic's coefficients are then of order 1.
  const double dl = length(d_world);
  const Vec3 d = d_world / dl;
  const Vec3 o = o_world / r;
  // Move the origin to the bounding sphere's entry point (R + a = 1): the coefficients then come
  // from a point at distance ~1 from the centre instead of from a far-away origin, which limits
  // cancellation; the sphere also rejects most misses cheaply.
  const double bh = dot(o, d);
  const Vec3 f = o - d * bh;
  double s[2];
  if (quadratic_roots(1, bh, dot(o, o) - 1, 1 - dot(f, f), s) == 0) return std::nullopt;
  const double shift = s[0];
  const Vec3 p = o + d * shift;

  // |p + s d|^2 = dd s^2 + 2 n s + m, (x^2 + y^2)(s) = g s^2 + 2 h s + q; the quartic in s is
  // (dd s^2 + 2 n s + K)^2 - 4 R^2 (g s^2 + 2 h s + q) with K = m + R^2 - a^2, divided by dd^2.
  const double rr = kTorusMajor * kTorusMajor;
  const double dd = dot(d, d);
  const double n = dot(p, d);
  const double k = dot(p, p) + rr - kTorusMinor * kTorusMinor;
  const double g = d.x * d.x + d.y * d.y;
  const double h = p.x * d.x + p.y * d.y;
  const double q = p.x * p.x + p.y * p.y;
  const double a4 = dd * dd;
  const double c3 = 4 * dd * n / a4;
  const double c2 = (4 * n * n + 2 * dd * k - 4 * rr * g) / a4;
  const double c1 = (4 * n * k - 8 * rr * h) / a4;
  const double c0 = (k * k - 4 * rr * q) / a4;
  double roots[4];
  const int count = solve_quartic(c3, c2, c1, c0, roots);

  const double scale = r / dl;  // t in world units = (shift + s) r / |d|
  for (int i = 0; i < count; ++i) {
    const double t = (shift + roots[i]) * scale;
    if (!(t > t_min && t < t_max)) continue;
    const Vec3 x = p + d * roots[i];
    if (!(std::fabs(torus_implicit(x)) <= kTorusResidual)) continue;  // verify on the surface
    // The normal points from the nearest point of the core circle (radius R in the xy plane) to
    // the hit: more accurate than the normalised gradient, and outward by construction.
    const double rho = std::sqrt(x.x * x.x + x.y * x.y);
    const Vec3 core{kTorusMajor * x.x / rho, kTorusMajor * x.y / rho, 0};
    return Hit{t, normalize(x - core)};
  }
  return std::nullopt;
}

// Horner evaluation of the monic quartic and its derivative.
void quartic_eval(double c3, double c2, double c1, double c0, double x, double& f, double& df) {
  f = (((x + c3) * x + c2) * x + c1) * x + c0;
  df = ((4 * x + 3 * c3) * x + 2 * c2) * x + c1;
}

// Newton on the original quartic, accepting a step only while it lowers |f|: a step that does not
// is at the rounding floor (or near a double root, where Newton stalls), and the previous iterate
// is the better root.
double polish(double c3, double c2, double c1, double c0, double x) {
  double f, df;
  quartic_eval(c3, c2, c1, c0, x, f, df);
  for (int i = 0; i < kPolishSteps && f != 0 && df != 0; ++i) {
    const double xn = x - f / df;
    double fn, dfn;
    quartic_eval(c3, c2, c1, c0, xn, fn, dfn);
    if (!(std::fabs(fn) < std::fabs(f))) break;
    x = xn;
    f = fn;
    df = dfn;
  }
  return x;
}

// The largest real root of the monic cubic m^3 + a m^2 + b m + c (Cardano / trigonometric form),
// polished by Newton.
double largest_cubic_root(double a, double b, double c) {
  const double a3 = a / 3;
  const double Q = (a * a - 3 * b) / 9;
  const double R = (2 * a * a * a - 9 * a * b + 27 * c) / 54;
  double m;
  if (Q > 0 && R * R < Q * Q * Q) {  // three real roots: the largest is -2 sqrt(Q) cos((theta + 2 pi) / 3)
    const double ratio = std::clamp(R / (Q * std::sqrt(Q)), -1.0, 1.0);  // clamp: rounding may leave [-1, 1]
    const double theta = std::acos(ratio);
    m = -2 * std::sqrt(Q) * std::cos((theta + 2 * kPi) / 3) - a3;
  } else {  // one real root
    const double A = -std::copysign(std::cbrt(std::fabs(R) + std::sqrt(R * R - Q * Q * Q)), R);
    const double B = A == 0 ? 0 : Q / A;
    m = A + B - a3;
  }
  for (int i = 0; i < kPolishSteps; ++i) {
    const double f = ((m + a) * m + b) * m + c;
    const double df = (3 * m + 2 * a) * m + b;
    if (f == 0 || df == 0) break;
    const double mn = m - f / df;
    const double fn = ((mn + a) * mn + b) * mn + c;
    if (!(std::fabs(fn) < std::fabs(f))) break;  // same acceptance rule as polish()
    m = mn;
  }
  return m;
}

}  // namespace

// Ferrari: with x = y - c3/4 the quartic is y^4 + p y^2 + qq y + s = 0, rewritten as
// (y^2 + m)^2 = (2m - p) y^2 - qq y + (m^2 - s). The right side is a perfect square (alpha y - beta)^2
// when m solves the resolvent cubic m^3 - (p/2) m^2 - s m + (4 p s - qq^2)/8 = 0; its largest root
// has 2m - p >= 0 (the cubic is -qq^2/8 <= 0 at m = p/2). Then y^2 + m = +-(alpha y - beta) gives two
// quadratics. alpha beta = qq/2 fixes the sign of beta.
int solve_quartic(double c3, double c2, double c1, double c0, double roots[4]) {
  const double sh = c3 / 4;
  const double sh2 = sh * sh;
  const double p = c2 - 6 * sh2;
  const double qq = c1 - 2 * c2 * sh + 8 * sh2 * sh;
  const double s = c0 - c1 * sh + c2 * sh2 - 3 * sh2 * sh2;

  const double m = largest_cubic_root(-p / 2, -s, (4 * p * s - qq * qq) / 8);
  // Both squares are >= 0 in exact arithmetic; clamp the rounding. Take the square root of the
  // larger one and derive the other from alpha beta = qq / 2: the larger is the better-conditioned.
  const double A2 = std::max(2 * m - p, 0.0);
  const double B2 = std::max(m * m - s, 0.0);
  double alpha, beta;
  if (A2 >= B2) {
    alpha = std::sqrt(A2);
    beta = alpha == 0 ? 0 : qq / (2 * alpha);
  } else {
    beta = std::sqrt(B2);
    alpha = qq / (2 * beta);
  }

  int count = 0;
  // y^2 - alpha y + (m + beta) = 0 and y^2 + alpha y + (m - beta) = 0 as x^2 + 2 bh x + c with a = 1.
  for (const double sign : {-1.0, +1.0}) {
    const double bh = sign * alpha / 2;
    const double c = m - sign * beta;
    double y[2];
    if (quadratic_roots(1, bh, c, bh * bh - c, y) == 0) continue;
    for (const double yi : y) roots[count++] = polish(c3, c2, c1, c0, yi - sh);
  }
  std::sort(roots, roots + count);
  return count;
}

std::optional<Hit> intersect_shape(Shape shape, const Vec3& center, double r, const Ray& ray, double t_min, double t_max) {
  const Vec3 o = ray.o - center;
  switch (shape) {
    case Shape::kSphere:
      return intersect_sphere(o, r, ray.d, t_min, t_max);
    case Shape::kTorus:
      return intersect_torus(o, r, ray.d, t_min, t_max);
    case Shape::kTetrahedron:
      return intersect_polytope(kTetrahedron, o, r, ray.d, t_min, t_max);
    case Shape::kCube:
      return intersect_polytope(kCube, o, r, ray.d, t_min, t_max);
    case Shape::kOctahedron:
      return intersect_polytope(kOctahedron, o, r, ray.d, t_min, t_max);
    case Shape::kCylinder:
      return intersect_cylinder(o, r, ray.d, t_min, t_max);
  }
  return std::nullopt;  // not a Shape value: nothing to hit
}

std::optional<TubeHit> intersect_tube(const Vec3& a, const Vec3& b, double radius, const Ray& ray, double t_min,
                                      double t_max) {
  const Vec3 w = b - a;
  const double ww = dot(w, w);
  if (ww == 0) return std::nullopt;  // a degenerate segment has no side wall
  const Vec3 o = ray.o - a;
  // Components perpendicular to the axis: the wall is |o_perp + t d_perp| = radius.
  const Vec3 op = o - w * (dot(o, w) / ww);
  const Vec3 dp = ray.d - w * (dot(ray.d, w) / ww);
  const double qa = dot(dp, dp);
  if (qa == 0) return std::nullopt;  // parallel to the axis: never crosses the wall
  const double bh = dot(op, dp);
  const Vec3 f = op - dp * (bh / qa);
  double t[2];
  if (quadratic_roots(qa, bh, dot(op, op) - radius * radius, qa * (radius * radius - dot(f, f)), t) == 0) {
    return std::nullopt;
  }
  for (const double ti : t) {
    if (!(ti > t_min && ti < t_max)) continue;
    const Vec3 x = o + ray.d * ti;
    const double u = dot(x, w) / ww;
    if (!(u >= 0 && u <= 1)) continue;  // beyond an open end: the ray passes the wall's plane there
    // Away from the axis, also when the ray meets the wall from inside (the tube is open).
    return TubeHit{Hit{ti, normalize(x - w * u)}, u};
  }
  return std::nullopt;
}

}  // namespace r1::render
