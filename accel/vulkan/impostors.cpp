// The T1/T2 impostor pass as a Vulkan compute shader (spec/backends.md R1-BKD-065): one invocation
// per pixel casts the pixel's ray at the impostors binned into its 16-pixel tile, in list order,
// with the reference's fp64 ray-shape intersections written out operation for operation and every
// arithmetic value `precise` (no contraction into fma). GLSL has no fp64 acos, cos or cbrt: the
// torus's resolvent cubic starts from fp32 estimates of them and reaches its root by the
// reference's Newton steps in fp64.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include "r1/accel/vulkan.hpp"
#include "shader_common.hpp"

namespace r1::vk {

using render::Vec3;

namespace {

constexpr int kTile = 16;

// The compute pass's bindings: 0 geometry (8 doubles an impostor: centre, radius, colour, 0),
// 1 meta (8 ints: rectangle x0 y0 x1 y1, particle, shape, 0, 0), 2 tile offsets, 3 tile items,
// 4 t, 5 colour (3 doubles a pixel), 6 owner, 7 camera (position, right, up, forward, focal_px).
constexpr const char* kComputeHeader = R"(#version 460
layout(local_size_x = 8, local_size_y = 8) in;
layout(std430, binding = 0) readonly buffer G { double geo[]; };
layout(std430, binding = 1) readonly buffer M { int meta[]; };
layout(std430, binding = 2) readonly buffer TP { uint tile_ptr[]; };
layout(std430, binding = 3) readonly buffer TI { uint tile_item[]; };
layout(std430, binding = 4) writeonly buffer OT { double out_t[]; };
layout(std430, binding = 5) writeonly buffer OC { double out_c[]; };
layout(std430, binding = 6) writeonly buffer OO { int out_owner[]; };
layout(std430, binding = 7) readonly buffer CAM { double cam[]; };
layout(push_constant) uniform P { uint width; uint height; uint tiles_x; uint y0; uint rows; } p;
)";

// The raster pass's bindings: 0 geometry and 1 meta as above, 2 the instances (item indices in
// draw order), 7 camera. The vertex shader makes the quad of the item's rectangle; the fragment
// shader casts the pixel's ray at the item and writes (t, owner), colour r g, colour b as the
// words of doubles, and depth t / (2 t_far).
constexpr const char* kRasterBindings = R"(#version 460
layout(std430, binding = 0) readonly buffer G { double geo[]; };
layout(std430, binding = 1) readonly buffer M { int meta[]; };
layout(std430, binding = 2) readonly buffer L { uint instance_item[]; };
layout(std430, binding = 7) readonly buffer CAM { double cam[]; };
layout(push_constant) uniform P { uint width; uint height; float depth_scale; } p;
)";

constexpr const char* kVertexMain = R"(
layout(location = 0) flat out uint item;
void main() {
  uint i = instance_item[gl_InstanceIndex];
  int v = gl_VertexIndex;
  bool right = v == 1 || v == 3 || v == 4;
  bool below = v == 2 || v == 4 || v == 5;
  float x = float(right ? meta[i * 8u + 2u] : meta[i * 8u]);
  float y = float(below ? meta[i * 8u + 3u] : meta[i * 8u + 1u]);
  gl_Position = vec4(2.0 * x / float(p.width) - 1.0, 2.0 * y / float(p.height) - 1.0, 0.0, 1.0);
  item = i;
}
)";

// The draw fed by the cull (R1-BKD-077): the instance is a particle of a tier list, and the quad
// is its bounding cube's pixel rectangle, project_box (reference/render/cull.cpp) in fp64.
constexpr const char* kVertexCulled = R"(
layout(location = 0) flat out uint item;
void main() {
  uint i = instance_item[gl_InstanceIndex];
  int v = gl_VertexIndex;
  dvec3 c = dvec3(geo[i * 8u], geo[i * 8u + 1u], geo[i * 8u + 2u]);
  double r = geo[i * 8u + 3u];
  precise dvec3 lo = dvec3(c.x - r, c.y - r, c.z - r);
  precise dvec3 hi = dvec3(c.x + r, c.y + r, c.z + r);
  dvec3 pos = dvec3(cam[0], cam[1], cam[2]), right = dvec3(cam[3], cam[4], cam[5]), up = dvec3(cam[6], cam[7], cam[8]);
  dvec3 fwd = dvec3(cam[9], cam[10], cam[11]);
  double focal = cam[12];
  double w = double(p.width), h = double(p.height);
  double minx = 0.0LF, miny = 0.0LF, maxx = 0.0LF, maxy = 0.0LF;
  bool whole = false;
  for (int k = 0; k < 8; ++k) {
    dvec3 corner = dvec3((k & 1) != 0 ? hi.x : lo.x, (k & 2) != 0 ? hi.y : lo.y, (k & 4) != 0 ? hi.z : lo.z);
    precise dvec3 rel = corner - pos;
    double depth = dotp(rel, fwd);
    if (depth <= kNear) { whole = true; break; }
    precise double px = w * 0.5LF + dotp(rel, right) / depth * focal;
    precise double py = h * 0.5LF - dotp(rel, up) / depth * focal;
    minx = k == 0 ? px : min(minx, px); maxx = k == 0 ? px : max(maxx, px);
    miny = k == 0 ? py : min(miny, py); maxy = k == 0 ? py : max(maxy, py);
  }
  double x0 = 0.0LF, y0 = 0.0LF, x1 = w, y1 = h;
  if (!whole) {
    x0 = clamp(floor(minx), 0.0LF, w); y0 = clamp(floor(miny), 0.0LF, h);
    x1 = clamp(ceil(maxx) + 1.0LF, 0.0LF, w); y1 = clamp(ceil(maxy) + 1.0LF, 0.0LF, h);
  }
  bool right_side = v == 1 || v == 3 || v == 4;
  bool below = v == 2 || v == 4 || v == 5;
  float x = float(int(right_side ? x1 : x0));
  float y = float(int(below ? y1 : y0));
  gl_Position = vec4(2.0 * x / float(p.width) - 1.0, 2.0 * y / float(p.height) - 1.0, 0.0, 1.0);
  item = i;
}
)";

constexpr const char* kFragmentMain = R"(
layout(location = 0) flat in uint item;
layout(location = 0) out uvec4 out0;
layout(location = 1) out uvec4 out1;
layout(location = 2) out uvec4 out2;
void main() {
  uint x = uint(gl_FragCoord.x), y = uint(gl_FragCoord.y);
  dvec3 d = pixel_dir(x, y, p.width, p.height);
  uint i = item;
  precise dvec3 o = dvec3(cam[0] - geo[i * 8u], cam[1] - geo[i * 8u + 1u], cam[2] - geo[i * 8u + 2u]);
  double t; dvec3 n;
  if (!intersect(uint(meta[i * 8u + 5u]), o, geo[i * 8u + 3u], d, kNear, inf(), t, n)) discard;
  dvec3 c = shade(i, n, d);
  gl_FragDepth = float(t) * p.depth_scale;
  out0 = uvec4(unpackDouble2x32(t), uint(meta[i * 8u + 4u]), 0u);
  out1 = uvec4(unpackDouble2x32(c.x), unpackDouble2x32(c.y));
  out2 = uvec4(unpackDouble2x32(c.z), 0u, 0u);
}
)";

// The reference's ray-shape intersections (shapes.cpp) and the headlight, shared by the compute
// and raster passes (after kPixelRay and kRayRoots).
constexpr const char* kShapes = R"(
const double kInvSqrt3 = 0.57735026918962576450914878050196LF;
const double kInvSqrt2 = 0.70710678118654752440084436210485LF;
const double kTorusMajor = 0.65LF;
const double kTorusMinor = 0.35LF;
const double kTorusResidual = 1e-9LF;
const int kPolishSteps = 8;

struct Span { double te; double tx; dvec3 ne; dvec3 nx; bool empty; };

void clip(inout Span sp, dvec3 n, double h, dvec3 unit_n, dvec3 o, dvec3 d) {
  double denom = dotp(n, d);
  precise double num = h - dotp(n, o);
  if (denom == 0.0LF) { if (num < 0.0LF) sp.empty = true; return; }
  precise double t = num / denom;
  if (denom < 0.0LF) { if (t > sp.te) { sp.te = t; sp.ne = unit_n; } }
  else if (t < sp.tx) { sp.tx = t; sp.nx = unit_n; }
}

bool span_hit(Span sp, double tmin, double tmax, out double t, out dvec3 n) {
  t = 0.0LF; n = dvec3(0.0LF);
  if (sp.empty || !(sp.te <= sp.tx)) return false;
  if (sp.te > tmin && sp.te < tmax) { t = sp.te; n = sp.ne; return true; }
  if (sp.te <= tmin && sp.tx > tmin && sp.tx < tmax) { t = sp.tx; n = sp.nx; return true; }
  return false;
}

Span new_span() { return Span(-inf(), inf(), dvec3(0.0LF), dvec3(0.0LF), false); }

bool face(inout Span sp, dvec3 n, double h, double inv, dvec3 o, double r, dvec3 d) {
  precise double hr = h * r;
  precise dvec3 un = dvec3(n.x * inv, n.y * inv, n.z * inv);
  clip(sp, n, hr, un, o, d);
  return !sp.empty;
}

bool polytope(uint shape, dvec3 o, double r, dvec3 d, double tmin, double tmax, out double t, out dvec3 n) {
  Span sp = new_span();
  t = 0.0LF; n = dvec3(0.0LF);
  if (shape == 2u) {  // tetrahedron
    if (!face(sp, dvec3(-1, -1, -1), kInvSqrt3, kInvSqrt3, o, r, d)) return false;
    if (!face(sp, dvec3(-1, +1, +1), kInvSqrt3, kInvSqrt3, o, r, d)) return false;
    if (!face(sp, dvec3(+1, -1, +1), kInvSqrt3, kInvSqrt3, o, r, d)) return false;
    if (!face(sp, dvec3(+1, +1, -1), kInvSqrt3, kInvSqrt3, o, r, d)) return false;
  } else if (shape == 3u) {  // cube
    if (!face(sp, dvec3(+1, 0, 0), kInvSqrt3, 1.0LF, o, r, d)) return false;
    if (!face(sp, dvec3(-1, 0, 0), kInvSqrt3, 1.0LF, o, r, d)) return false;
    if (!face(sp, dvec3(0, +1, 0), kInvSqrt3, 1.0LF, o, r, d)) return false;
    if (!face(sp, dvec3(0, -1, 0), kInvSqrt3, 1.0LF, o, r, d)) return false;
    if (!face(sp, dvec3(0, 0, +1), kInvSqrt3, 1.0LF, o, r, d)) return false;
    if (!face(sp, dvec3(0, 0, -1), kInvSqrt3, 1.0LF, o, r, d)) return false;
  } else {  // octahedron
    for (int k = 0; k < 8; ++k) {
      dvec3 s = dvec3((k & 4) != 0 ? -1 : 1, (k & 2) != 0 ? -1 : 1, (k & 1) != 0 ? -1 : 1);
      if (!face(sp, s, 1.0LF, kInvSqrt3, o, r, d)) return false;
    }
  }
  return span_hit(sp, tmin, tmax, t, n);
}

bool sphere(dvec3 o, double r, dvec3 d, double tmin, double tmax, out double t, out dvec3 n) {
  t = 0.0LF; n = dvec3(0.0LF);
  double a = dotp(d, d);
  double bh = dotp(o, d);
  precise double c = dotp(o, o) - r * r;
  precise double s = bh / a;
  precise dvec3 f = dvec3(o.x - d.x * s, o.y - d.y * s, o.z - d.z * s);
  precise double disc = a * (r * r - dotp(f, f));
  double t0, t1;
  if (quadratic_roots(a, bh, c, disc, t0, t1) == 0) return false;
  for (int i = 0; i < 2; ++i) {
    double ti = i == 0 ? t0 : t1;
    if (ti > tmin && ti < tmax) {
      precise dvec3 x = dvec3(o.x + d.x * ti, o.y + d.y * ti, o.z + d.z * ti);
      t = ti; n = nrm(x);
      return true;
    }
  }
  return false;
}

bool cylinder(dvec3 o, double r, dvec3 d, double tmin, double tmax, out double t, out dvec3 n) {
  t = 0.0LF; n = dvec3(0.0LF);
  precise double rc = r * kInvSqrt2;
  Span sp = new_span();
  clip(sp, dvec3(0, 0, 1), rc, dvec3(0, 0, 1), o, d);
  clip(sp, dvec3(0, 0, -1), rc, dvec3(0, 0, -1), o, d);
  if (sp.empty) return false;
  precise double a = d.x * d.x + d.y * d.y;
  precise double c = o.x * o.x + o.y * o.y - rc * rc;
  if (a == 0.0LF) {
    if (c > 0.0LF) return false;
  } else {
    precise double bh = o.x * d.x + o.y * d.y;
    precise double fx = o.x - d.x * (bh / a);
    precise double fy = o.y - d.y * (bh / a);
    precise double disc = a * (rc * rc - (fx * fx + fy * fy));
    double t0, t1;
    if (quadratic_roots(a, bh, c, disc, t0, t1) == 0) return false;
    if (t0 > sp.te) {
      sp.te = t0;
      precise dvec3 q = dvec3(o.x + d.x * t0, o.y + d.y * t0, 0.0LF);
      sp.ne = nrm(q);
    }
    if (t1 < sp.tx) {
      sp.tx = t1;
      precise dvec3 q = dvec3(o.x + d.x * t1, o.y + d.y * t1, 0.0LF);
      sp.nx = nrm(q);
    }
  }
  return span_hit(sp, tmin, tmax, t, n);
}

double torus_implicit(dvec3 q) {
  precise double rr = kTorusMajor * kTorusMajor;
  precise double k = dotp(q, q) + rr - kTorusMinor * kTorusMinor;
  precise double v = k * k - 4.0LF * rr * (q.x * q.x + q.y * q.y);
  return v;
}

void quartic_eval(double c3, double c2, double c1, double c0, double x, out double f, out double df) {
  precise double ff = (((x + c3) * x + c2) * x + c1) * x + c0;
  precise double dd = ((4.0LF * x + 3.0LF * c3) * x + 2.0LF * c2) * x + c1;
  f = ff; df = dd;
}

double polish(double c3, double c2, double c1, double c0, double x) {
  double f, df;
  quartic_eval(c3, c2, c1, c0, x, f, df);
  for (int i = 0; i < kPolishSteps && f != 0.0LF && df != 0.0LF; ++i) {
    precise double xn = x - f / df;
    double fn, dfn;
    quartic_eval(c3, c2, c1, c0, xn, fn, dfn);
    if (!(abs(fn) < abs(f))) break;
    x = xn; f = fn; df = dfn;
  }
  return x;
}

double largest_cubic_root(double a, double b, double c) {
  precise double a3 = a / 3.0LF;
  precise double Q = (a * a - 3.0LF * b) / 9.0LF;
  precise double R = (2.0LF * a * a * a - 9.0LF * a * b + 27.0LF * c) / 54.0LF;
  precise double m;
  if (Q > 0.0LF && R * R < Q * Q * Q) {
    precise double ratio = clamp(R / (Q * sqrt(Q)), -1.0LF, 1.0LF);
    float theta = acos(float(ratio));
    m = -2.0LF * sqrt(Q) * double(cos((theta + 2.0 * float(kPi)) / 3.0)) - a3;
  } else {
    precise double w = abs(R) + sqrt(R * R - Q * Q * Q);
    double cb = double(pow(float(w), 1.0 / 3.0));
    double A = -copysign_of(cb, R);
    precise double B = A == 0.0LF ? 0.0LF : Q / A;
    m = A + B - a3;
  }
  for (int i = 0; i < kPolishSteps; ++i) {
    precise double f = ((m + a) * m + b) * m + c;
    precise double df = (3.0LF * m + 2.0LF * a) * m + b;
    if (f == 0.0LF || df == 0.0LF) break;
    precise double mn = m - f / df;
    precise double fn = ((mn + a) * mn + b) * mn + c;
    if (!(abs(fn) < abs(f))) break;
    m = mn;
  }
  return m;
}

int solve_quartic(double c3, double c2, double c1, double c0, out double roots[4]) {
  roots[0] = 0.0LF; roots[1] = 0.0LF; roots[2] = 0.0LF; roots[3] = 0.0LF;
  precise double sh = c3 / 4.0LF;
  precise double sh2 = sh * sh;
  precise double pp = c2 - 6.0LF * sh2;
  precise double qq = c1 - 2.0LF * c2 * sh + 8.0LF * sh2 * sh;
  precise double s = c0 - c1 * sh + c2 * sh2 - 3.0LF * sh2 * sh2;
  precise double m = largest_cubic_root(-pp / 2.0LF, -s, (4.0LF * pp * s - qq * qq) / 8.0LF);
  precise double A2 = max(2.0LF * m - pp, 0.0LF);
  precise double B2 = max(m * m - s, 0.0LF);
  precise double alpha, beta;
  if (A2 >= B2) {
    alpha = sqrt(A2);
    beta = alpha == 0.0LF ? 0.0LF : qq / (2.0LF * alpha);
  } else {
    beta = sqrt(B2);
    alpha = qq / (2.0LF * beta);
  }
  int count = 0;
  for (int k = 0; k < 2; ++k) {
    double sgn = k == 0 ? -1.0LF : 1.0LF;
    precise double bh = sgn * alpha / 2.0LF;
    precise double c = m - sgn * beta;
    precise double disc = bh * bh - c;
    double y0, y1;
    if (quadratic_roots(1.0LF, bh, c, disc, y0, y1) == 0) continue;
    precise double z0 = y0 - sh;
    precise double z1 = y1 - sh;
    roots[count++] = polish(c3, c2, c1, c0, z0);
    roots[count++] = polish(c3, c2, c1, c0, z1);
  }
  for (int i = 1; i < count; ++i)
    for (int j = i; j > 0 && roots[j - 1] > roots[j]; --j) { double w = roots[j]; roots[j] = roots[j - 1]; roots[j - 1] = w; }
  return count;
}

bool torus(dvec3 ow, double r, dvec3 dw, double tmin, double tmax, out double t, out dvec3 n) {
  t = 0.0LF; n = dvec3(0.0LF);
  double dl = len(dw);
  precise dvec3 d = dvec3(dw.x / dl, dw.y / dl, dw.z / dl);
  precise dvec3 o = dvec3(ow.x / r, ow.y / r, ow.z / r);
  double bh = dotp(o, d);
  precise dvec3 f = dvec3(o.x - d.x * bh, o.y - d.y * bh, o.z - d.z * bh);
  precise double cc = dotp(o, o) - 1.0LF;
  precise double disc = 1.0LF - dotp(f, f);
  double s0, s1;
  if (quadratic_roots(1.0LF, bh, cc, disc, s0, s1) == 0) return false;
  double shift = s0;
  precise dvec3 q = dvec3(o.x + d.x * shift, o.y + d.y * shift, o.z + d.z * shift);
  precise double rr = kTorusMajor * kTorusMajor;
  double dd = dotp(d, d);
  double nn = dotp(q, d);
  precise double k = dotp(q, q) + rr - kTorusMinor * kTorusMinor;
  precise double g = d.x * d.x + d.y * d.y;
  precise double h = q.x * d.x + q.y * d.y;
  precise double qx = q.x * q.x + q.y * q.y;
  precise double a4 = dd * dd;
  precise double c3 = 4.0LF * dd * nn / a4;
  precise double c2 = (4.0LF * nn * nn + 2.0LF * dd * k - 4.0LF * rr * g) / a4;
  precise double c1 = (4.0LF * nn * k - 8.0LF * rr * h) / a4;
  precise double c0 = (k * k - 4.0LF * rr * qx) / a4;
  double roots[4];
  int count = solve_quartic(c3, c2, c1, c0, roots);
  precise double scale = r / dl;
  for (int i = 0; i < count; ++i) {
    precise double ti = (shift + roots[i]) * scale;
    if (!(ti > tmin && ti < tmax)) continue;
    precise dvec3 x = dvec3(q.x + d.x * roots[i], q.y + d.y * roots[i], q.z + d.z * roots[i]);
    if (!(abs(torus_implicit(x)) <= kTorusResidual)) continue;
    precise double rho = sqrt(x.x * x.x + x.y * x.y);
    precise dvec3 core = dvec3(kTorusMajor * x.x / rho, kTorusMajor * x.y / rho, 0.0LF);
    precise dvec3 w = dvec3(x.x - core.x, x.y - core.y, x.z - core.z);
    t = ti; n = nrm(w);
    return true;
  }
  return false;
}

bool intersect(uint shape, dvec3 o, double r, dvec3 d, double tmin, double tmax, out double t, out dvec3 n) {
  t = 0.0LF; n = dvec3(0.0LF);
  if (shape == 0u) return sphere(o, r, d, tmin, tmax, t, n);
  if (shape == 1u) return torus(o, r, d, tmin, tmax, t, n);
  if (shape >= 2u && shape <= 4u) return polytope(shape, o, r, d, tmin, tmax, t, n);
  if (shape == 5u) return cylinder(o, r, d, tmin, tmax, t, n);
  return false;
}



dvec3 shade(uint i, dvec3 n, dvec3 d) {
  precise double l = -dotp(n, d);
  precise double lit = 0.25LF + 0.75LF * (0.0LF < l ? l : 0.0LF);
  precise dvec3 c = dvec3(geo[i * 8u + 4u] * lit, geo[i * 8u + 5u] * lit, geo[i * 8u + 6u] * lit);
  return c;
}
)";

constexpr const char* kComputeMain = R"(
void main() {
  uint x = gl_GlobalInvocationID.x, y = p.y0 + gl_GlobalInvocationID.y;
  if (x >= p.width || gl_GlobalInvocationID.y >= p.rows) return;
  dvec3 pos = dvec3(cam[0], cam[1], cam[2]);
  dvec3 d = pixel_dir(x, y, p.width, p.height);
  double best = inf();
  dvec3 color = dvec3(0.0LF);
  int owner = -1;
  uint tile = (y / 16u) * p.tiles_x + x / 16u;
  for (uint k = tile_ptr[tile]; k < tile_ptr[tile + 1u]; ++k) {
    uint i = tile_item[k];
    int x0 = meta[i * 8u], y0 = meta[i * 8u + 1u], x1 = meta[i * 8u + 2u], y1 = meta[i * 8u + 3u];
    if (int(x) < x0 || int(x) >= x1 || int(y) < y0 || int(y) >= y1) continue;
    precise dvec3 o = dvec3(pos.x - geo[i * 8u], pos.y - geo[i * 8u + 1u], pos.z - geo[i * 8u + 2u]);
    double t; dvec3 n;
    if (!intersect(uint(meta[i * 8u + 5u]), o, geo[i * 8u + 3u], d, kNear, best, t, n)) continue;
    best = t;
    color = shade(i, n, d);
    owner = meta[i * 8u + 4u];
  }
  uint px = gl_GlobalInvocationID.y * p.width + x;  // within the band
  out_t[px] = best;
  out_c[px * 3u] = color.x; out_c[px * 3u + 1u] = color.y; out_c[px * 3u + 2u] = color.z;
  out_owner[px] = owner;
}
)";

}  // namespace

Result<ImpostorPass> ImpostorPass::build(Context& ctx, Mode mode) {
  ImpostorPass pass;
  pass.ctx_ = &ctx;
  pass.mode_ = mode;
  if (mode == Mode::kCompute) {
    R1_ASSIGN(pass.pipeline_, ctx.compute_compile(std::string(kComputeHeader) + "#define CAMERA cam\n" + detail::kPixelRay + detail::kRayRoots + kShapes + kComputeMain, "impostors"));
  } else {
    const std::string fragment = std::string(kRasterBindings) + "#define CAMERA cam\n" + detail::kPixelRay + detail::kRayRoots + kShapes + kFragmentMain;
    R1_ASSIGN(pass.pipeline_, ctx.graphics_compile(std::string(kRasterBindings) + kVertexMain, fragment, "impostors"));
    const std::string culled = std::string(kRasterBindings) + "#define CAMERA cam\n" + detail::kPixelRay + detail::kRayRoots + kVertexCulled;
    R1_ASSIGN(pass.culled_pipeline_, ctx.graphics_compile(culled, fragment, "impostors_culled"));
  }
  return pass;
}

Status ImpostorPass::reserve(std::size_t which, std::size_t bytes) { return ctx_->buffer_ensure(buffers_[which], bytes); }

Status ImpostorPass::upload(std::size_t which, std::span<const std::uint8_t> bytes) {
  R1_TRY(reserve(which, bytes.size()));
  return ctx_->buffer_write(buffers_[which], bytes, 0);
}

Status ImpostorPass::draw(const ImpostorCamera& cam, std::span<const ImpostorItem> items, std::span<double> t,
                          std::span<Vec3> color, std::span<std::int64_t> owner) {
  const std::size_t pixels = std::size_t{cam.width} * cam.height;
  if (cam.width == 0 || cam.height == 0 || t.size() != pixels || color.size() != pixels || owner.size() != pixels)
    return Status::input("vulkan impostors: the layer is not " + std::to_string(cam.width) + " x " + std::to_string(cam.height));
  if (items.size() >= 0x7fffffffu) return Status::input("vulkan impostors: " + std::to_string(items.size()) + " impostors: 2^31 - 1 at most");
  std::fill(t.begin(), t.end(), std::numeric_limits<double>::infinity());
  std::fill(color.begin(), color.end(), Vec3{});
  std::fill(owner.begin(), owner.end(), -1);
  if (items.empty()) return Status::ok();
  std::vector<double> geo(items.size() * 8, 0.0);
  std::vector<std::int32_t> meta(items.size() * 8, 0);
  for (std::size_t i = 0; i < items.size(); ++i) {
    const ImpostorItem& it = items[i];
    const double g[8] = {it.center.x, it.center.y, it.center.z, it.radius, it.color.x, it.color.y, it.color.z, 0.0};
    std::copy(g, g + 8, geo.begin() + static_cast<std::ptrdiff_t>(i * 8));
    const std::int32_t m[8] = {it.x0, it.y0, it.x1, it.y1, static_cast<std::int32_t>(it.particle), static_cast<std::int32_t>(it.shape), 0, 0};
    std::copy(m, m + 8, meta.begin() + static_cast<std::ptrdiff_t>(i * 8));
  }
  const double camera[16] = {cam.position.x, cam.position.y, cam.position.z, cam.right.x, cam.right.y, cam.right.z,
                             cam.up.x,       cam.up.y,       cam.up.z,       cam.forward.x, cam.forward.y, cam.forward.z,
                             cam.focal_px,   0,              0,              0};
  R1_TRY(upload(0, detail::bytes_of(std::span<const double>(geo))));
  R1_TRY(upload(1, detail::bytes_of(std::span<const std::int32_t>(meta))));
  R1_TRY(upload(7, detail::bytes_of(std::span<const double>(camera))));
  return mode_ == Mode::kCompute ? draw_compute(cam, items, t, color, owner) : draw_raster(cam, items, t, color, owner);
}

Status ImpostorPass::draw_compute(const ImpostorCamera& cam, std::span<const ImpostorItem> items, std::span<double> t,
                                  std::span<Vec3> color, std::span<std::int64_t> owner) {
  // Bin the impostors into 16-pixel tiles by their rectangles, each tile's list in item order.
  const std::uint32_t tiles_x = (cam.width + kTile - 1) / kTile, tiles_y = (cam.height + kTile - 1) / kTile;
  std::vector<std::uint32_t> ptr(std::size_t{tiles_x} * tiles_y + 1, 0);
  const auto tiles_of = [&](const ImpostorItem& it, auto&& fn) {
    const int x0 = std::max(it.x0, 0), y0 = std::max(it.y0, 0);
    const int x1 = std::min<int>(it.x1, static_cast<int>(cam.width)), y1 = std::min<int>(it.y1, static_cast<int>(cam.height));
    if (x0 >= x1 || y0 >= y1) return;
    for (int ty = y0 / kTile; ty <= (y1 - 1) / kTile; ++ty)
      for (int tx = x0 / kTile; tx <= (x1 - 1) / kTile; ++tx) fn(static_cast<std::size_t>(ty) * tiles_x + static_cast<std::size_t>(tx));
  };
  std::uint64_t entries = 0;
  for (const ImpostorItem& it : items) tiles_of(it, [&](std::size_t k) { ++ptr[k + 1], ++entries; });
  if (entries >= 0xffffffffu) return Status::input("vulkan impostors: " + std::to_string(entries) + " tile entries: 2^32 - 1 at most");
  for (std::size_t k = 1; k < ptr.size(); ++k) ptr[k] += ptr[k - 1];
  std::vector<std::uint32_t> list(entries), fill(ptr.begin(), ptr.end() - 1);
  for (std::size_t i = 0; i < items.size(); ++i) tiles_of(items[i], [&](std::size_t k) { list[fill[k]++] = static_cast<std::uint32_t>(i); });
  R1_TRY(upload(2, detail::bytes_of(std::span<const std::uint32_t>(ptr))));
  R1_TRY(upload(3, detail::bytes_of(std::span<const std::uint32_t>(list))));
  // The image in bands of rows whose colour output fits one storage buffer.
  const std::size_t max_rows = std::max<std::size_t>(1, ctx_->info().max_buffer / (std::size_t{cam.width} * 3 * sizeof(double)));
  const std::size_t band_rows = std::min<std::size_t>(cam.height, max_rows);
  const std::size_t band_pixels = band_rows * cam.width;
  R1_TRY(reserve(4, band_pixels * sizeof(double)));
  R1_TRY(reserve(5, band_pixels * 3 * sizeof(double)));
  R1_TRY(reserve(6, band_pixels * sizeof(std::int32_t)));
  Slot slots[8];
  for (std::uint32_t b = 0; b < 8; ++b) slots[b] = {b, buffers_[b]};
  for (std::size_t y0 = 0; y0 < cam.height; y0 += band_rows) {
    const std::size_t rows = std::min<std::size_t>(band_rows, cam.height - y0);
    R1_TRY(detail::layer_band(*ctx_, pipeline_, slots, cam.width, cam.height, tiles_x, y0, rows, {buffers_[4], buffers_[5], buffers_[6]}, t,
                              color, owner));
  }
  return Status::ok();
}

Status ImpostorPass::draw_raster(const ImpostorCamera& cam, std::span<const ImpostorItem> items, std::span<double> t,
                                 std::span<Vec3> color, std::span<std::int64_t> owner) {
  // One instance (a quad, six vertices) per item, in item order: one indirect draw.
  std::vector<std::uint32_t> instances(items.size());
  for (std::size_t i = 0; i < items.size(); ++i) instances[i] = static_cast<std::uint32_t>(i);
  const DrawArgs args{6, static_cast<std::uint32_t>(items.size()), 0, 0};
  R1_TRY(upload(2, detail::bytes_of(std::span<const std::uint32_t>(instances))));
  R1_TRY(upload(3, detail::bytes_of(std::span<const DrawArgs>(&args, 1))));
  // Depth t / (2 t_far): every hit lies within the items' bounding spheres, so below 1/2.
  double far = 1;
  for (const ImpostorItem& it : items) {
    const Vec3 r = it.center - cam.position;
    far = std::max(far, std::sqrt(r.x * r.x + r.y * r.y + r.z * r.z) + it.radius);
  }
  const Slot slots[] = {{0, buffers_[0]}, {1, buffers_[1]}, {2, buffers_[2]}, {7, buffers_[7]}};
  return raster(pipeline_, slots, buffers_[3], 1, far, cam, t, color, owner);
}

Status ImpostorPass::draw_culled(const ImpostorCamera& cam, const CullPass& cull, double far, std::span<double> t,
                                 std::span<Vec3> color, std::span<std::int64_t> owner) {
  if (mode_ != Mode::kRaster) return Status::input("vulkan impostors: the draw fed by the cull is a raster draw");
  if (!cull.holds_impostors()) return Status::input("vulkan impostors: the cull holds no colours and shapes to draw");
  const std::size_t pixels = std::size_t{cam.width} * cam.height;
  if (cam.width == 0 || cam.height == 0 || t.size() != pixels || color.size() != pixels || owner.size() != pixels)
    return Status::input("vulkan impostors: the layer is not " + std::to_string(cam.width) + " x " + std::to_string(cam.height));
  std::fill(t.begin(), t.end(), std::numeric_limits<double>::infinity());
  std::fill(color.begin(), color.end(), Vec3{});
  std::fill(owner.begin(), owner.end(), -1);
  const auto& args = cull.last_args();
  if (args[0].instance_count + args[1].instance_count + args[2].instance_count == 0) return Status::ok();
  const double camera[16] = {cam.position.x, cam.position.y, cam.position.z, cam.right.x, cam.right.y, cam.right.z,
                             cam.up.x,       cam.up.y,       cam.up.z,       cam.forward.x, cam.forward.y, cam.forward.z,
                             cam.focal_px,   0,              0,              0};
  R1_TRY(upload(7, detail::bytes_of(std::span<const double>(camera))));
  // The T0, T1 and T2 records of the cull: three draws over its tier lists.
  const Slot slots[] = {{0, cull.geometry_buffer()}, {1, cull.meta_buffer()}, {2, cull.tier_list_buffer()}, {7, buffers_[7]}};
  return raster(culled_pipeline_, slots, cull.args_buffer(), 3, far, cam, t, color, owner);
}

Status ImpostorPass::raster(std::uint32_t pipeline, std::span<const Slot> slots, std::uint32_t indirect, std::uint32_t draws, double far,
                            const ImpostorCamera& cam, std::span<double> t, std::span<Vec3> color, std::span<std::int64_t> owner) {
  const float depth_scale = static_cast<float>(0.5 / (far * 1.0001));
  if (target_ == kNoTarget || target_size_ != std::array<std::uint32_t, 2>{cam.width, cam.height}) {
    if (target_ != kNoTarget) ctx_->target_release(target_);
    target_ = kNoTarget;
    R1_ASSIGN(target_, ctx_->target_create(cam.width, cam.height));
    target_size_ = {cam.width, cam.height};
  }
  std::uint32_t push_words[3] = {cam.width, cam.height, 0};
  std::memcpy(&push_words[2], &depth_scale, 4);
  std::uint8_t push_bytes[sizeof push_words];
  std::memcpy(push_bytes, push_words, sizeof push_words);
  // Cleared: t = +infinity, owner -1, colour 0.
  const Context::Clear clear{{{0u, 0x7ff00000u, 0xffffffffu, 0u}, {0u, 0u, 0u, 0u}, {0u, 0u, 0u, 0u}}};
  R1_TRY(ctx_->draw_indirect(pipeline, target_, slots, indirect, draws, clear, push_bytes));
  std::array<std::vector<std::uint32_t>, Context::kTargetColors> words;
  for (std::uint32_t i = 0; i < Context::kTargetColors; ++i) {
    R1_ASSIGN(words[i], ctx_->target_read(target_, i));
  }
  const auto as_double = [](std::uint32_t lo, std::uint32_t hi) {
    const std::uint64_t bits = (std::uint64_t{hi} << 32) | lo;
    double d;
    std::memcpy(&d, &bits, 8);
    return d;
  };
  for (std::size_t k = 0; k < t.size(); ++k) {
    const std::uint32_t* a = &words[0][k * 4];
    const std::uint32_t* b = &words[1][k * 4];
    const std::uint32_t* c = &words[2][k * 4];
    t[k] = as_double(a[0], a[1]);
    owner[k] = static_cast<std::int32_t>(a[2]);
    color[k] = {as_double(b[0], b[1]), as_double(b[2], b[3]), as_double(c[0], c[1])};
  }
  return Status::ok();
}

}  // namespace r1::vk
