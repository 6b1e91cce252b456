// The field and composite pass as a Vulkan compute shader (spec/backends.md R1-BKD-070): per
// pixel, the reference's T-infinity march through the hierarchy (R1-RND-050..058) and its
// front-to-back composite with the splats and the opaque layer (R1-RND-070), in fp64 with the
// reference's order of operations; exp is det_exp (the Clifford primitives' Cody-Waite and Taylor
// form) where the reference calls libm's.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "r1/accel/vulkan.hpp"
#include "shader_common.hpp"

namespace r1::vk {

namespace {

// det_exp (the reference's Cody-Waite reduction and degree-13 Taylor polynomial) with the Horner
// steps written out and one return: lavapipe (Mesa 22.3) miscompiled the looped form when it was
// called inside the sample loop, returning 0 for arguments near 0. EXPC[i] stands for the
// shader's constant i: log2(e), the two parts of ln 2, then the 14 Taylor coefficients.
constexpr const char* kDetExp = R"(
double inf() { return packDouble2x32(uvec2(0u, 0x7ff00000u)); }
double pow2(int k) { return packDouble2x32(uvec2(0u, uint(k + 1023) << 20)); }

double det_exp(double x) {
  precise double t = x * EXPC[0];
  double tc = clamp(t, -2000.0LF, 2000.0LF);
  int k = int(tc >= 0.0LF ? tc + 0.5LF : tc - 0.5LF);
  double kd = double(k);
  precise double r = (x - kd * EXPC[1]) - kd * EXPC[2];
  // Horner from the degree-13 coefficient down, written out (no loop).
  precise double q = ((((((((((((EXPC[16] * r + EXPC[15]) * r + EXPC[14]) * r + EXPC[13]) * r + EXPC[12]) * r + EXPC[11]) * r +
                         EXPC[10]) * r + EXPC[9]) * r + EXPC[8]) * r + EXPC[7]) * r + EXPC[6]) * r + EXPC[5]) * r + EXPC[4]) * r + EXPC[3];
  int k1 = k >= 0 ? k / 2 : -((-k) / 2);
  int k2 = clamp(k - k1, -1022, 1023);
  k1 = clamp(k1, -1022, 1023);
  precise double a = q * pow2(k1);
  precise double b = a * pow2(k2);
  precise double direct = q * pow2(clamp(k, -1022, 1023));
  double y = (k >= -1022 && k <= 1023) ? direct : b;
  y = x < -746.0LF ? 0.0LF : y;
  y = x > 710.0LF ? inf() : y;
  y = isnan(x) ? x : y;
  return y;
}

)";

// The shader source with det_exp in place of R1_DET_EXP, its constants read from `constants`
// (a buffer's name and the index of the first, as "prm[20 + ").
std::string with_det_exp(std::string source, const std::string& constants) {
  std::string det = kDetExp;
  for (std::size_t at = det.find("EXPC["); at != std::string::npos; at = det.find("EXPC[", at)) det.replace(at, 5, constants);
  source.replace(source.find("R1_DET_EXP"), 10, det);
  return source;
}

constexpr const char* kComposite = R"(#version 460
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
layout(local_size_x = 8, local_size_y = 8) in;
layout(std430, binding = 0) readonly buffer N { double node[]; };
layout(std430, binding = 1) readonly buffer I { uint idx[]; };
layout(std430, binding = 2) readonly buffer M { double member[]; };
layout(std430, binding = 3) readonly buffer S { double splat[]; };
layout(std430, binding = 4) readonly buffer O { double opaque[]; };
layout(std430, binding = 5) writeonly buffer R { float result[]; };
layout(std430, binding = 6) readonly buffer PR { double prm[]; };
layout(std430, binding = 7) buffer F { uint flag[]; };
// The neural field's passes (R1-BKD-076): the samples it is asked at (x, sigma), how many a pixel
// has, and the network's raw outputs at them.
layout(std430, binding = 8) buffer E { double entry[]; };
layout(std430, binding = 9) buffer EC { uint entry_count[]; };
layout(std430, binding = 10) readonly buffer NO { float nout[]; };
layout(push_constant) uniform P {
  uint width; uint height; uint y0; uint rows;
  uint child_ptr; uint child; uint member_ptr; uint top_ptr; uint top; uint splat_ptr; uint splat_list;
  uint level0; uint level1; uint level2; uint level3; uint level4;
  uint tiles_x; uint samples; uint field_on; uint tiles; uint seed_lo; uint seed_hi; uint next; uint parent;
  uint mode;  // 0 the analytic field; 1 list the neural field's samples; 2 composite with their outputs
} p;

const int kMaxCand = R1_MAX_CANDIDATES;  // build() substitutes the cap
const double kNear = 1e-3LF;

R1_DET_EXP
// Philox4x32-10 (r1::rng::bits) and uniform_double.
uint64_t rng_bits(uint64_t item, uint64_t dim) {
  uvec4 c = uvec4(uint(item), uint(item >> 32), uint(dim), uint(dim >> 32));
  uvec2 k = uvec2(p.seed_lo, p.seed_hi);
  for (int r = 0; r < 10; ++r) {
    if (r > 0) { k.x += 0x9E3779B9u; k.y += 0xBB67AE85u; }
    uint h0, l0, h1, l1;
    umulExtended(0xD2511F53u, c.x, h0, l0);
    umulExtended(0xCD9E8D57u, c.z, h1, l1);
    c = uvec4(h1 ^ c.y ^ k.x, l1, h0 ^ c.w ^ k.y, l0);
  }
  return (uint64_t(c.y) << 32) | uint64_t(c.x);
}
double uniform01(uint64_t item, uint64_t dim) { return double(rng_bits(item, dim) >> 11) * pow2(-53); }

#define CAMERA prm
R1_PIXEL_RAY

double field_sigma(double t) {
  precise double tm = max(t, 0.0LF);
  precise double tau = prm[13] * tm / prm[14];
  precise double px = 0.5LF * tm / prm[12] + 1e-9LF;
  return max(sqrt(tau), px);
}

uint level_of(uint g) { return g < p.level1 ? 0u : (g < p.level2 ? 1u : (g < p.level3 ? 2u : 3u)); }

// A node's row (FieldData::nodes): weight, centroid, colour, extent, then its colour spread
// (R1-RND-055): the gradient row-major, the colour's low and high ends.
const uint kNodeStride = 24u;
dvec3 nvec(uint g, uint o) { return dvec3(node[g * kNodeStride + o], node[g * kNodeStride + o + 1u], node[g * kNodeStride + o + 2u]); }

// The field accumulator of R1-RND-051..053.
double acc_w; dvec3 acc_c; dvec3 acc_f;
void acc_add(double weight, dvec3 center, dvec3 color, dvec3 x, double inv2s2, double max_q) {
  precise dvec3 d = dvec3(center.x - x.x, center.y - x.y, center.z - x.z);
  precise double q = dotp(d, d) * inv2s2;
  if (q > max_q) return;
  precise double kk = weight * det_exp(-q);
  acc_w += kk;
  acc_c = dvec3(acc_c.x + color.x * kk, acc_c.y + color.y * kk, acc_c.z + color.z * kk);
  acc_f = dvec3(acc_f.x + d.x * kk, acc_f.y + d.y * kk, acc_f.z + d.z * kk);
}

// A node taken whole (R1-RND-055): its colour at x is its mean plus its gradient times
// (x - centroid) / sigma^2 (inv2s2 = 1 / (2 sigma^2)), clamped into its colour range, in the
// reference's order of operations.
void acc_add_node(uint g, dvec3 x, double inv2s2) {
  uint b = g * kNodeStride;
  dvec3 c = nvec(g, 1u);
  precise double two = 2.0LF * inv2s2;
  precise double u[3] = double[3]((x.x - c.x) * two, (x.y - c.y) * two, (x.z - c.z) * two);
  double col[3];
  for (uint j = 0u; j < 3u; ++j) {
    precise double sum = node[b + 4u + j];
    for (uint k = 0u; k < 3u; ++k) sum = sum + node[b + 8u + 3u * j + k] * u[k];
    col[j] = min(max(sum, node[b + 17u + j]), node[b + 20u + j]);
  }
  acc_add(node[b], c, dvec3(col[0], col[1], col[2]), x, inv2s2, inf());
}

bool within_reach(dvec3 x, dvec3 c, double extent, double reach) {
  precise dvec3 d = dvec3(x.x - c.x, x.y - c.y, x.z - c.z);
  precise double r = (extent + reach) * (extent + reach);
  return dotp(d, d) <= r;
}

uint cand_node[kMaxCand];
double cand_t0[kMaxCand];
double cand_t1[kMaxCand];
bool cand_agg[kMaxCand];

// The candidate walk (R1-RND-057): a depth-first walk of each root's subtree without a stack (down
// to the first child, else on to the next sibling, climbing to a parent's next sibling when a
// child list ends). A node whose ball, grown by `grow`, the ray crosses within [kNear, t_end] is a
// candidate where it aggregates (extent <= theta sigma(t0)) or is a leaf, else it is opened.
// op 0 lists the candidates and their span [a, b]; past the cap it sets `over` and, for the
// neural field, walks on for the span alone. op 1 returns whether some candidate spans ts and
// reaches xs within `reach`: the neural field's test of a sample on a ray past the cap, the same
// answer as the listed candidates give, walked again instead of stored.
bool walk(uint op, dvec3 pos, dvec3 d, double t_end, double grow, double theta, uint r_begin, uint r_end, bool from_tile,
          double ts, dvec3 xs, double reach, inout int nc, inout double a, inout double b, inout bool over) {
  for (uint rk = r_begin; rk < r_end && !(over && p.mode == 0u); ++rk) {
    uint root = from_tile ? p.level3 + idx[p.top + rk] : rk;
    uint g = root;
    while (true) {
      bool descend = false;
      double w = node[g * kNodeStride];
      if (w > 0.0LF) {
        dvec3 c = nvec(g, 1u);
        double extent = node[g * kNodeStride + 7u];
        // ray_ball within [kNear, t_end]
        precise dvec3 oc = dvec3(pos.x - c.x, pos.y - c.y, pos.z - c.z);
        precise double rr = extent + grow;
        precise double bb = dotp(d, oc);
        precise double disc = bb * bb - (dotp(oc, oc) - rr * rr);
        if (disc >= 0.0LF) {
          precise double q = sqrt(disc);
          double t0 = max(kNear, -bb - q), t1 = min(t_end, -bb + q);
          if (t0 <= t1) {
            uint lv = level_of(g);
            bool agg = extent <= theta * field_sigma(t0);
            if (agg || lv == 0u) {
              if (op == 1u) {
                if (t0 <= ts && t1 >= ts && within_reach(xs, c, extent, reach)) return true;
              } else {
                if (nc == kMaxCand) {
                  over = true;
                  if (p.mode == 0u) break;
                } else {
                  cand_node[nc] = g; cand_t0[nc] = t0; cand_t1[nc] = t1; cand_agg[nc] = agg; ++nc;
                }
                a = min(a, t0); b = max(b, t1);
              }
            } else {
              descend = idx[p.child_ptr + g - p.level1] < idx[p.child_ptr + g - p.level1 + 1u];
            }
          }
        }
      }
      if (descend) {
        g = idx[p.child + idx[p.child_ptr + g - p.level1]];
        continue;
      }
      while (g != root && idx[p.next + g] == 0xffffffffu) g = idx[p.parent + g];
      if (g == root) break;
      g = idx[p.next + g];
    }
  }
  return false;
}

void main() {
  uint x = gl_GlobalInvocationID.x, row = gl_GlobalInvocationID.y, y = p.y0 + row;
  if (x >= p.width || row >= p.rows) return;
  uint px = row * p.width + x;
  uint64_t pixel = uint64_t(y) * uint64_t(p.width) + uint64_t(x);
  uint n_entries = 0u;
  if (p.mode == 1u) entry_count[px] = 0u;
  dvec3 pos = dvec3(prm[0], prm[1], prm[2]);
  dvec3 fwd = dvec3(prm[9], prm[10], prm[11]);
  dvec3 d = pixel_dir(x, y, p.width, p.height);
  double t_op = opaque[px * 4u];
  double kappa = prm[15], cutoff = prm[16], theta = prm[17], stop = prm[18];

  // ---- the candidate walk (R1-RND-057) ----
  int nc = 0;
  double a = 0.0LF, b = 0.0LF, delta = 0.0LF;
  bool over = false;
  double t_end = min(t_op, prm[14]);
  bool march = p.field_on != 0u && t_end > kNear;
  double grow = cutoff * field_sigma(t_end);
  uint tile = (y / 16u) * p.tiles_x + x / 16u;
  bool from_tile = p.tiles != 0u && tile < p.tiles;
  uint r_begin = from_tile ? idx[p.top_ptr + tile] : p.level3;
  uint r_end = from_tile ? idx[p.top_ptr + tile + 1u] : p.level4;
  if (march) {
    a = t_end; b = kNear;
    walk(0u, pos, d, t_end, grow, theta, r_begin, r_end, from_tile, 0.0LF, dvec3(0.0LF), 0.0LF, nc, a, b, over);
    if (over && p.mode == 2u) atomicAdd(flag[3], 1u);
    if (over && p.mode == 0u) {
      atomicAdd(flag[0], 1u);
      result[px * 7u + 3u] = uintBitsToFloat(0x7fc00000u);  // the host draws this pixel
      return;
    }
    // Entry order, ties by level and id (global index): the analytic field sums in it; the neural
    // field's test of a sample does not depend on it.
    for (int i = 1; i < nc && p.mode == 0u; ++i)
      for (int j = i; j > 0 && (cand_t0[j - 1] > cand_t0[j] || (cand_t0[j - 1] == cand_t0[j] && cand_node[j - 1] > cand_node[j])); --j) {
        uint tn = cand_node[j]; cand_node[j] = cand_node[j - 1]; cand_node[j - 1] = tn;
        double ta = cand_t0[j]; cand_t0[j] = cand_t0[j - 1]; cand_t0[j - 1] = ta;
        double tb = cand_t1[j]; cand_t1[j] = cand_t1[j - 1]; cand_t1[j - 1] = tb;
        bool tg = cand_agg[j]; cand_agg[j] = cand_agg[j - 1]; cand_agg[j - 1] = tg;
      }
    march = nc > 0 && b > a;
    if (march) delta = (b - a) / double(p.samples);
  }

  // ---- splats and samples, merged front to back (R1-RND-070) ----
  double cos_fwd = dotp(d, fwd);
  uint tile_s = (y / 16u) * p.tiles_x + x / 16u;
  uint sj = idx[p.splat_ptr + tile_s], sj_end = idx[p.splat_ptr + tile_s + 1u];
  double max_q = 0.5LF * cutoff * cutoff;
  int si = 0;
  double field_t = 1.0LF;
  bool have_s = false, have_h = false;
  double s_t = 0.0LF, s_alpha = 0.0LF, h_t = 0.0LF, h_alpha = 0.0LF;
  dvec3 s_color = dvec3(0.0LF), s_flow = dvec3(0.0LF), h_color = dvec3(0.0LF);
  dvec3 color = dvec3(0.0LF), fl = dvec3(0.0LF);
  double T = 1.0LF;
  while (T > 1e-4LF) {
    // The next field sample, when none is pending.
    while (!have_s && march && si < int(p.samples) && field_t >= stop) {
      int i = si++;
      precise double t = a + (double(i) + uniform01(pixel, uint64_t(i))) * delta;
      if (t > b) { si = int(p.samples); break; }
      double sigma = field_sigma(t);
      precise double inv = 1.0LF / (2.0LF * sigma * sigma);
      precise double reach = cutoff * sigma;
      precise dvec3 xs = dvec3(pos.x + d.x * t, pos.y + d.y * t, pos.z + d.z * t);
      if (p.mode != 0u) {
        // The neural field (R1-NRF-031) at the samples some candidate reaches.
        bool near = false;
        if (over) {
          int n0 = 0;
          double a0 = 0.0LF, b0 = 0.0LF;
          bool o0 = false;
          near = walk(1u, pos, d, t_end, grow, theta, r_begin, r_end, from_tile, t, xs, reach, n0, a0, b0, o0);
        } else {
          for (int c = 0; c < nc && !near; ++c) {
            if (cand_t0[c] > t || cand_t1[c] < t) continue;
            near = within_reach(xs, nvec(cand_node[c], 1u), node[cand_node[c] * kNodeStride + 7u], reach);
          }
        }
        if (!near) continue;
        uint e = px * p.samples + n_entries;
        n_entries += 1u;
        if (p.mode == 1u) {
          entry[e * 4u] = xs.x; entry[e * 4u + 1u] = xs.y; entry[e * 4u + 2u] = xs.z; entry[e * 4u + 3u] = sigma;
          continue;
        }
        // The heads (R1-NRF-004): kernel sum exp(o0) times the Gaussian prior (R1-NRF-007), density
        // kappa / sigma times it, colour 3 sigmoid(o + logit(q)) for the prior's colour q, as
        // 3 q / (q + (1 - q) e^-o) (R1-NRF-008), flow sigma o4..6. Without the priors (files before
        // version 3): expm1(softplus(o0)) and 3 sigmoid(o1..3).
        double o0 = double(nout[e * 7u]);
        precise double w;
        precise dvec3 col;
        uint parts = uint(prm[38]);
        if (parts > 0u) {
          // The prior's parts in order, one exp each (NeuralField::prior_at): kernel sum and
          // colour, the nearest part's colour where every part's sum underflows.
          precise double s2 = sigma * sigma;
          precise double sum = 0.0LF;
          precise dvec3 num = dvec3(0.0LF);
          dvec3 nearest = dvec3(0.0LF);
          double q_min = inf();
          for (uint k = 0u; k < parts; ++k) {
            uint pb = 56u + 17u * k;
            precise double v = s2 + prm[pb + 1u];
            precise double r = s2 / v;
            precise double dx = xs.x - prm[pb + 2u];
            precise double dy = xs.y - prm[pb + 3u];
            precise double dz = xs.z - prm[pb + 4u];
            precise double q = (dx * dx + dy * dy + dz * dz) / (2.0LF * v);
            // Past q = 500 the part adds 0 (R1-NRF-007's limit, as the host's prior_at).
            precise double ek = prm[pb] * r * sqrt(r) * (det_exp(-min(q, 500.0LF)) * (q <= 500.0LF ? 1.0LF : 0.0LF));
            sum += ek;
            double ck[3];
            for (uint c = 0u; c < 3u; ++c) {
              precise double g = (prm[pb + 8u + 3u * c] * dx + prm[pb + 9u + 3u * c] * dy) + prm[pb + 10u + 3u * c] * dz;
              precise double m = prm[pb + 5u + c] + g / v;
              ck[c] = m;
            }
            precise dvec3 cv = dvec3(ck[0], ck[1], ck[2]);
            num = dvec3(num.x + ek * cv.x, num.y + ek * cv.y, num.z + ek * cv.z);
            if (q < q_min) { q_min = q; nearest = cv; }
          }
          w = det_exp(o0) * sum;
          double cq[3];
          for (int k = 0; k < 3; ++k) {
            precise double q0 = (sum > 0.0LF ? num[k] / sum : nearest[k]) / 3.0LF;
            double qk = clamp(q0, 1e-3LF, 1.0LF - 1e-3LF);
            precise double ck = 3.0LF * qk / (qk + (1.0LF - qk) * det_exp(-double(nout[e * 7u + 1u + uint(k)])));
            cq[k] = ck;
          }
          col = dvec3(cq[0], cq[1], cq[2]);
        } else {
          w = o0 > 30.0LF ? det_exp(o0) - 1.0LF : det_exp(o0);
          col = dvec3(3.0LF * (1.0LF / (1.0LF + det_exp(-double(nout[e * 7u + 1u])))),
                      3.0LF * (1.0LF / (1.0LF + det_exp(-double(nout[e * 7u + 2u])))),
                      3.0LF * (1.0LF / (1.0LF + det_exp(-double(nout[e * 7u + 3u])))));
        }
        if (!(w > 0.0LF)) continue;
        precise double density = prm[37] / sigma * w;
        precise double alpha = 1.0LF - det_exp(-density * delta);
        precise dvec3 fw = dvec3(double(nout[e * 7u + 4u]) * sigma, double(nout[e * 7u + 5u]) * sigma,
                                 double(nout[e * 7u + 6u]) * sigma);
        s_t = t; s_alpha = alpha;
        s_color = col;
        s_flow = fw;
        have_s = true;
        field_t *= 1.0LF - alpha;
        continue;
      }
      acc_w = 0.0LF; acc_c = dvec3(0.0LF); acc_f = dvec3(0.0LF);
      bool any = false;
      for (int c = 0; c < nc; ++c) {
        if (cand_t0[c] > t || cand_t1[c] < t) continue;
        any = true;
        uint g = cand_node[c];
        if (!within_reach(xs, nvec(g, 1u), node[g * kNodeStride + 7u], reach)) continue;
        if (cand_agg[c]) {
          acc_add_node(g, xs, inv);
          continue;
        }
        uint m0 = idx[p.member_ptr + g], m1 = idx[p.member_ptr + g + 1u];
        for (uint m = m0; m < m1; ++m)
          acc_add(member[m * 8u], dvec3(member[m * 8u + 1u], member[m * 8u + 2u], member[m * 8u + 3u]),
                  dvec3(member[m * 8u + 4u], member[m * 8u + 5u], member[m * 8u + 6u]), xs, inv, max_q);
      }
      if (!any || acc_w <= 0.0LF) continue;
      precise double density = kappa / sigma * acc_w;
      precise double alpha = 1.0LF - det_exp(-density * delta);
      s_t = t; s_alpha = alpha;
      s_color = dvec3(acc_c.x / acc_w, acc_c.y / acc_w, acc_c.z / acc_w);
      s_flow = dvec3(acc_f.x / acc_w, acc_f.y / acc_w, acc_f.z / acc_w);
      have_s = true;
      field_t *= 1.0LF - alpha;
    }
    // The next splat in front of the opaque hit.
    while (!have_h && sj < sj_end) {
      uint k = idx[p.splat_list + sj++] * 12u;
      precise double t = splat[k] / cos_fwd;
      if (t >= t_op) continue;
      precise double dx = (double(x) + 0.5LF) - splat[k + 1u], dy = (double(y) + 0.5LF) - splat[k + 2u];
      precise double q = splat[k + 3u] * dx * dx + 2.0LF * splat[k + 4u] * dx * dy + splat[k + 5u] * dy * dy;
      double al = min(0.99LF, splat[k + 6u] * det_exp(-0.5LF * q));
      if (!(al >= 1.0LF / 255.0LF)) continue;
      h_t = t; h_alpha = al; h_color = dvec3(splat[k + 7u], splat[k + 8u], splat[k + 9u]);
      have_h = true;
    }
    if (!have_s && !have_h) break;
    if (have_h && (!have_s || h_t <= s_t)) {
      color = dvec3(color.x + h_color.x * (T * h_alpha), color.y + h_color.y * (T * h_alpha), color.z + h_color.z * (T * h_alpha));
      T *= 1.0LF - h_alpha;
      have_h = false;
    } else {
      color = dvec3(color.x + s_color.x * (T * s_alpha), color.y + s_color.y * (T * s_alpha), color.z + s_color.z * (T * s_alpha));
      fl = dvec3(fl.x + s_flow.x * (T * s_alpha), fl.y + s_flow.y * (T * s_alpha), fl.z + s_flow.z * (T * s_alpha));
      T *= 1.0LF - s_alpha;
      have_s = false;
    }
  }
  if (p.mode == 1u) {
    entry_count[px] = n_entries;
    if (n_entries > 0u) atomicAdd(flag[2], n_entries);
    return;
  }
  if (t_op < inf()) {
    color = dvec3(color.x + opaque[px * 4u + 1u] * T, color.y + opaque[px * 4u + 2u] * T, color.z + opaque[px * 4u + 3u] * T);
    T = 0.0LF;
  }
  result[px * 7u] = float(color.x);
  result[px * 7u + 1u] = float(color.y);
  result[px * 7u + 2u] = float(color.z);
  result[px * 7u + 3u] = float(1.0LF - T);
  result[px * 7u + 4u] = float(fl.x);
  result[px * 7u + 5u] = float(fl.y);
  result[px * 7u + 6u] = float(fl.z);
  if (fl.x != 0.0LF || fl.y != 0.0LF || fl.z != 0.0LF) flag[1] = 1u;
}
)";

// The neural field's network at the listed samples (R1-BKD-076, R1-NRF-002..006): one invocation
// a sample, the reference's query (the similarity beyond tau_hi, the cube, the tau feature), hash
// grid features and the three layers in float, summed in the reference's order (infer_layer),
// every expression `precise`. log2 is det_log2 (a frexp and the atanh series); the host's libm
// log2 may differ in the last bit, which the float tau feature almost never keeps.
constexpr const char* kInfer = R"(#version 460
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer E { double entry[]; };
layout(std430, binding = 1) readonly buffer C { uint entry_count[]; };
layout(std430, binding = 2) readonly buffer W { float wt[]; };
layout(std430, binding = 3) writeonly buffer O { float nout[]; };
// lo, size, centroid, tau_lo, tau_hi, log2(tau_hi / tau_lo), fade power, then det_exp's constants
layout(std430, binding = 4) readonly buffer NP { double np[]; };
layout(std430, binding = 5) readonly buffer RS { uint res[]; };
layout(push_constant) uniform P {
  uint pixels; uint slots; uint levels; uint table; uint hidden; uint inputs; uint w1; uint b1; uint w2; uint b2; uint w3; uint b3;
  uint block; uint wc; uint bc; uint wg; uint bg; uint gamma;  // the Clifford block (R1-NRF-003): width d (0: none), offsets
} p;

R1_DET_EXP
// The block's SiLU and sigmoid: r1's (R1-RND-101) in double on det_exp, rounded to float.
float silu_f(float x) {
  precise double r = double(x) / (1.0LF + det_exp(-double(x)));
  return float(r);
}
float sigmoid_f(float x) {
  precise double r = 1.0LF / (1.0LF + det_exp(-double(x)));
  return float(r);
}
const uint kShifts[5] = uint[5](1u, 2u, 4u, 8u, 16u);

const uint kPrime1 = 2654435761u, kPrime2 = 805459861u;
uint invocation() { return gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 64u; }

// log2 v for positive finite v: v = m 2^e with m in [sqrt(1/2), sqrt(2)), ln m = 2 atanh(s),
// s = (m - 1) / (m + 1), |s| <= 0.172, the series to s^23.
double det_log2(double v) {
  int e;
  double m = frexp(v, e);
  if (m < 0.70710678118654752440LF) { m = m * 2.0LF; e -= 1; }
  precise double s = (m - 1.0LF) / (m + 1.0LF);
  precise double s2 = s * s;
  precise double series = 1.0LF + s2 * (1.0LF / 3.0LF + s2 * (1.0LF / 5.0LF + s2 * (1.0LF / 7.0LF + s2 * (1.0LF / 9.0LF
      + s2 * (1.0LF / 11.0LF + s2 * (1.0LF / 13.0LF + s2 * (1.0LF / 15.0LF + s2 * (1.0LF / 17.0LF + s2 * (1.0LF / 19.0LF
      + s2 * (1.0LF / 21.0LF + s2 * (1.0LF / 23.0LF)))))))))));
  precise double ln = 2.0LF * s * series;
  precise double r = double(e) + ln * 1.44269504088896340736LF;
  return r;
}

uint corner_index(uint x, uint y, uint z, uint r) {
  uint64_t side = uint64_t(r) + 1ul;
  if (side * side * side <= uint64_t(p.table)) return uint(uint64_t(x) + side * (uint64_t(y) + side * uint64_t(z)));
  return (x ^ (y * kPrime1) ^ (z * kPrime2)) & (p.table - 1u);
}

float features[65];
float h1[256];
float h2[256];
float cf[320];  // the block's features, 2 |S| d (d <= 32)
float hg[64];   // [H | G]

void main() {
  uint e = invocation();
  uint pxl = e / p.slots, j = e - pxl * p.slots;
  if (pxl >= p.pixels || j >= entry_count[pxl]) return;
  dvec3 x = dvec3(entry[e * 4u], entry[e * 4u + 1u], entry[e * 4u + 2u]);
  double sigma = entry[e * 4u + 3u];
  double tau_lo = np[7], tau_hi = np[8];
  precise double s2 = sigma * sigma;
  if (s2 > tau_hi) {
    precise double k = sqrt(tau_hi) / sigma;
    precise dvec3 r = dvec3(x.x - np[4], x.y - np[5], x.z - np[6]);
    precise dvec3 y = dvec3(np[4] + r.x * k, np[5] + r.y * k, np[6] + r.z * k);
    x = y;
  }
  precise double ux = (x.x - np[0]) / np[3];
  precise double uy = (x.y - np[1]) / np[3];
  precise double uz = (x.z - np[2]) / np[3];
  double u[3] = double[3](clamp(ux, 0.0LF, 1.0LF), clamp(uy, 0.0LF, 1.0LF), clamp(uz, 0.0LF, 1.0LF));
  double tau = clamp(s2, tau_lo, tau_hi);
  precise double tq = tau_hi > tau_lo ? det_log2(tau / tau_lo) / np[9] : 0.0LF;
  precise double qsigma = sqrt(tau) / np[3];
  for (uint l = 0u; l < p.levels; ++l) {
    uint r = res[l];
    uint i0[3];
    double fr[3];
    for (int k = 0; k < 3; ++k) {
      precise double pk = u[k] * double(r);
      double fl = min(floor(pk), double(r - 1u));
      i0[k] = uint(fl);
      precise double f = pk - fl;
      fr[k] = f;
    }
    precise float a = 0.0, b = 0.0;
    for (uint c = 0u; c < 8u; ++c) {
      uint dx = c & 1u, dy = (c >> 1) & 1u, dz = (c >> 2) & 1u;
      precise double w = (dx != 0u ? fr[0] : 1.0LF - fr[0]) * (dy != 0u ? fr[1] : 1.0LF - fr[1]) * (dz != 0u ? fr[2] : 1.0LF - fr[2]);
      float wf = float(w);
      uint idx = (l * p.table + corner_index(i0[0] + dx, i0[1] + dy, i0[2] + dz, r)) * 2u;
      a += wf * wt[idx];
      b += wf * wt[idx + 1u];
    }
    precise double fade = 2.0LF / (double(r) * qsigma);
    precise double fade2 = fade * fade;
    precise double fade4 = fade2 * fade2;
    float mask = float(min(1.0LF, np[10] == 2.0LF ? fade2 : fade4));
    precise float fa = mask * a;
    precise float fb = mask * b;
    features[2u * l] = fa;
    features[2u * l + 1u] = fb;
  }
  features[2u * p.levels] = float(tq);
  for (uint jj = 0u; jj < p.hidden; ++jj) {
    precise float acc = 0.0;
    uint row = p.w1 + jj * p.inputs;
    for (uint i = 0u; i < p.inputs; ++i) acc += features[i] * wt[row + i];
    acc += wt[p.b1 + jj];
    h1[jj] = max(acc, 0.0);
  }
  if (p.block > 0u) {
    // The Clifford render block (NeuralInference's block_row): H and C the halves of h1, the
    // shifted inner and wedge products, G = Wc F + bc, the gate Wg [H | G] + bg, and h1 becomes
    // [B | C].
    uint d = p.block, nf = 10u * d;
    for (uint k = 0u; k < 5u; ++k) {
      uint s = kShifts[k] % d;
      for (uint ch = 0u; ch < d; ++ch) {
        uint j = ch + s < d ? ch + s : ch + s - d;
        precise float pr = h1[ch] * h1[d + j];
        precise float q = h1[j] * h1[d + ch];
        cf[2u * k * d + ch] = silu_f(pr);
        precise float wedge = pr - q;
        cf[2u * k * d + d + ch] = wedge;
      }
    }
    for (uint jj = 0u; jj < d; ++jj) {
      precise float acc = 0.0;
      uint row = p.wc + jj * nf;
      for (uint i = 0u; i < nf; ++i) acc += cf[i] * wt[row + i];
      acc += wt[p.bc + jj];
      hg[d + jj] = acc;
      hg[jj] = h1[jj];
    }
    for (uint jj = 0u; jj < d; ++jj) {
      precise float acc = 0.0;
      uint row = p.wg + jj * 2u * d;
      for (uint i = 0u; i < 2u * d; ++i) acc += hg[i] * wt[row + i];
      acc += wt[p.bg + jj];
      precise float inner = silu_f(h1[jj]) + sigmoid_f(acc) * hg[d + jj];
      precise float b = h1[jj] + wt[p.gamma + jj] * inner;
      h1[jj] = b;
    }
  }
  for (uint jj = 0u; jj < p.hidden; ++jj) {
    precise float acc = 0.0;
    uint row = p.w2 + jj * p.hidden;
    for (uint i = 0u; i < p.hidden; ++i) acc += h1[i] * wt[row + i];
    acc += wt[p.b2 + jj];
    h2[jj] = max(acc, 0.0);
  }
  for (uint jj = 0u; jj < 7u; ++jj) {
    precise float acc = 0.0;
    uint row = p.w3 + jj * p.hidden;
    for (uint i = 0u; i < p.hidden; ++i) acc += h2[i] * wt[row + i];
    acc += wt[p.b3 + jj];
    nout[e * 7u + jj] = acc;
  }
}
)";

}  // namespace

bool CompositePass::infers(const NeuralData& n) {
  const std::uint64_t in = n.inputs(), h = n.hidden;
  // Loop iterations an invocation runs (a level's 3 + 8, then the layers) below lavapipe's 65,535.
  const std::uint64_t d = n.block, block_iterations = 5 * d + d * 10 * d + d * 2 * d;
  const std::uint64_t iterations = std::uint64_t{n.levels} * 11 + in * h + h * h + 7 * h + 2 * h + 7 + block_iterations;
  return n.levels >= 1 && n.levels <= 32 && h >= 1 && h <= 256 && n.log2_table >= 1 && n.log2_table <= 24 &&
         n.resolution.size() == n.levels && iterations <= 60000 && (d == 0 || (d <= 32 && h == 2 * d));
}

Result<CompositePass> CompositePass::build(Context& ctx, const ExpConstants& constants, std::uint32_t max_candidates) {
  if (constants.taylor.size() != 14) return Status::input("vulkan composite: det_exp needs 14 Taylor coefficients");
  if (max_candidates < 1 || max_candidates > 4096) return Status::input("vulkan composite: candidates per ray must be 1..4096");
  CompositePass pass;
  pass.ctx_ = &ctx;
  pass.exp_ = constants;
  std::string source = kComposite;
  const std::string key = "R1_MAX_CANDIDATES", ray = "R1_PIXEL_RAY";
  source.replace(source.find(key), key.size(), std::to_string(max_candidates));
  source.replace(source.find(ray), ray.size(), detail::kPixelRay);
  R1_ASSIGN(pass.pipeline_, ctx.compute_compile(with_det_exp(source, "prm[20 + "), "composite"));
  R1_ASSIGN(pass.infer_, ctx.compute_compile(with_det_exp(kInfer, "np[11 + "), "neural_infer"));
  return pass;
}

Result<std::array<std::uint32_t, 18>> CompositePass::upload_neural(const NeuralData& n, std::uint32_t slots) {
  if (!infers(n)) return Status::input("vulkan composite: the neural field's architecture is not inferred on the device");
  const std::size_t table = std::size_t{1} << n.log2_table, ni = n.inputs(), h = n.hidden;
  const std::size_t w1 = std::size_t{n.levels} * table * 2, b1 = w1 + h * ni, w2 = b1 + h, b2 = w2 + h * h, w3 = b2 + h,
                    b3 = w3 + 7 * h;
  const std::size_t d = n.block, wc = b3 + 7, bc = wc + d * 10 * d, wg = bc + d, bg = wg + d * 2 * d, gamma = bg + d;
  if (n.params.size() != gamma + d) return Status::input("vulkan composite: the neural field's parameters do not match its architecture");
  std::vector<double> np = {n.lo.x,       n.lo.y,       n.lo.z,   n.size,   n.centroid.x, n.centroid.y,
                            n.centroid.z, n.tau_lo,     n.tau_hi, n.log2_range, static_cast<double>(n.fade_power),
                            exp_.log2e,   exp_.ln2_hi,  exp_.ln2_lo};
  np.insert(np.end(), exp_.taylor.begin(), exp_.taylor.end());
  const auto put = [&](std::size_t which, auto span) -> Status {
    R1_TRY(ctx_->buffer_ensure(buffers_[which], std::max<std::size_t>(span.size_bytes(), 16), Residence::kUpload));
    return ctx_->buffer_write(buffers_[which], detail::bytes_of(span), 0);
  };
  R1_TRY(put(11, std::span<const float>(n.params)));
  R1_TRY(put(12, std::span<const double>(np)));
  R1_TRY(put(13, std::span<const std::uint32_t>(n.resolution)));
  const auto u32 = [](std::size_t v) { return static_cast<std::uint32_t>(v); };
  return std::array<std::uint32_t, 18>{0,       slots,   n.levels, u32(table), n.hidden, u32(ni),  u32(w1), u32(b1), u32(w2),
                                       u32(b2), u32(w3), u32(b3),  n.block,    u32(wc),  u32(bc),  u32(wg), u32(bg), u32(gamma)};
}

Result<std::vector<float>> CompositePass::infer(const NeuralData& n, std::span<const double> queries) {
  const std::size_t count = queries.size() / 4;
  if (queries.size() != count * 4) return Status::input("vulkan neural inference: queries are 4 doubles each");
  if (count * 32 > ctx_->info().max_buffer || count >= 0xffffffffu) return Status::input("vulkan neural inference: too many queries");
  R1_ASSIGN(auto push, upload_neural(n, 1));
  push[0] = static_cast<std::uint32_t>(count);
  const std::vector<std::uint32_t> ones(std::max<std::size_t>(count, 1), 1u);
  R1_TRY(ctx_->buffer_ensure(buffers_[8], std::max<std::size_t>(queries.size_bytes(), 16)));
  R1_TRY(ctx_->buffer_write(buffers_[8], detail::bytes_of(queries), 0));
  R1_TRY(ctx_->buffer_ensure(buffers_[9], ones.size() * 4));
  R1_TRY(ctx_->buffer_write(buffers_[9], detail::bytes_of(std::span<const std::uint32_t>(ones)), 0));
  R1_TRY(ctx_->buffer_ensure(buffers_[10], std::max<std::size_t>(count * 28, 16)));
  const Slot slots[] = {{0, buffers_[8]}, {1, buffers_[9]}, {2, buffers_[11]}, {3, buffers_[10]}, {4, buffers_[12]}, {5, buffers_[13]}};
  std::array<std::uint8_t, sizeof push> bytes;
  std::memcpy(bytes.data(), push.data(), sizeof push);
  R1_TRY(ctx_->dispatch(infer_, slots, detail::groups_for(count), bytes));
  R1_ASSIGN(const auto out, ctx_->buffer_read(buffers_[10], 0, count * 28));
  std::vector<float> result(count * 7);
  std::memcpy(result.data(), out.data(), out.size());
  return result;
}

Status CompositePass::draw(const ImpostorCamera& cam, const FieldData& field, const SplatData& splats,
                           std::span<const double> opaque, std::span<float> rgba, std::vector<float>& flow,
                           std::vector<std::uint32_t>& host_pixels) {
  const std::size_t pixels = std::size_t{cam.width} * cam.height;
  if (cam.width == 0 || cam.height == 0 || opaque.size() != pixels * 4 || rgba.size() != pixels * 4)
    return Status::input("vulkan composite: the layers are not " + std::to_string(cam.width) + " x " + std::to_string(cam.height));
  const std::size_t nodes = field.nodes.size() / kFieldNodeDoubles;
  if (field.nodes.size() % kFieldNodeDoubles != 0 || field.level_offset[kLevels] != nodes || field.child_ptr.size() != nodes - field.level_offset[1] + 1 ||
      field.member_ptr.size() != field.level_offset[1] + 1 || field.next.size() != nodes || field.parent.size() != nodes)
    return Status::input("vulkan composite: the field's node tables do not match");
  // Every index table in one buffer, at the offsets the push constants give.
  std::vector<std::uint32_t> idx;
  const auto append = [&idx](const std::vector<std::uint32_t>& v) {
    const auto at = static_cast<std::uint32_t>(idx.size());
    idx.insert(idx.end(), v.begin(), v.end());
    return at;
  };
  const std::uint32_t child_ptr = append(field.child_ptr), child = append(field.child), member_ptr = append(field.member_ptr),
                      top_ptr = append(field.top_ptr), top = append(field.top), splat_ptr = append(splats.tile_ptr),
                      splat_list = append(splats.tile), next = append(field.next), parent = append(field.parent);
  if (idx.empty()) idx.push_back(0);
  std::vector<double> prm(56, 0.0);
  const double camera[13] = {cam.position.x, cam.position.y, cam.position.z, cam.right.x, cam.right.y, cam.right.z, cam.up.x,
                             cam.up.y,       cam.up.z,       cam.forward.x, cam.forward.y, cam.forward.z, cam.focal_px};
  std::copy(camera, camera + 13, prm.begin());
  prm[13] = field.tau_cam, prm[14] = field.t_far, prm[15] = field.kappa, prm[16] = field.cutoff, prm[17] = field.theta;
  prm[18] = field.stop;
  prm[20] = exp_.log2e, prm[21] = exp_.ln2_hi, prm[22] = exp_.ln2_lo;
  std::copy(exp_.taylor.begin(), exp_.taylor.end(), prm.begin() + 23);
  // What the host writes once a frame and every ray reads lives on the device where it can
  // (R1-BKD-061); the samples and the network's outputs at them never leave it.
  const auto ensure_write = [&](std::size_t which, auto span) -> Status {
    R1_TRY(ctx_->buffer_ensure(buffers_[which], std::max<std::size_t>(span.size_bytes(), 16), Residence::kUpload));
    return ctx_->buffer_write(buffers_[which], detail::bytes_of(span), 0);
  };
  const std::vector<double> one(8, 0.0);
  R1_TRY(ensure_write(0, std::span<const double>(field.nodes.empty() ? one : field.nodes)));
  R1_TRY(ensure_write(1, std::span<const std::uint32_t>(idx)));
  R1_TRY(ensure_write(2, std::span<const double>(field.members.empty() ? one : field.members)));
  R1_TRY(ensure_write(3, std::span<const double>(splats.splats.empty() ? one : splats.splats)));
  // The neural field (R1-BKD-076): its parameters, query constants and resolutions.
  const NeuralData* nd = field.enabled ? field.neural : nullptr;
  std::array<std::uint32_t, 18> infer_push{};
  if (nd != nullptr) {
    R1_ASSIGN(infer_push, upload_neural(*nd, std::max<std::uint32_t>(field.samples, 1)));
    prm[37] = nd->kappa;
    // The prior's parts from prm[56], 17 doubles each (R1-NRF-007, 008).
    prm[38] = static_cast<double>(nd->prior.size() / 17);
    prm.insert(prm.end(), nd->prior.begin(), nd->prior.end());
  }
  R1_TRY(ensure_write(6, std::span<const double>(prm)));
  // Bands of rows whose opaque layer and results fit one storage buffer each, and with the neural
  // field, whose listed samples do too.
  std::size_t per_row = std::size_t{cam.width} * 32;
  if (nd != nullptr) per_row = std::max(per_row, std::size_t{cam.width} * std::max<std::uint32_t>(field.samples, 1) * 32);
  const std::size_t band = std::max<std::size_t>(1, std::min<std::size_t>(cam.height, ctx_->info().max_buffer / per_row));
  if (nd != nullptr) {
    const std::size_t slots = band * cam.width * std::max<std::uint32_t>(field.samples, 1);
    R1_TRY(ctx_->buffer_ensure(buffers_[8], slots * 32, Residence::kScratch));
    R1_TRY(ctx_->buffer_ensure(buffers_[9], band * cam.width * 4, Residence::kScratch));
    R1_TRY(ctx_->buffer_ensure(buffers_[10], slots * 28, Residence::kScratch));
  }
  R1_TRY(ctx_->buffer_ensure(buffers_[4], band * cam.width * 32, Residence::kUpload));
  R1_TRY(ctx_->buffer_ensure(buffers_[5], band * cam.width * 28));
  R1_TRY(ctx_->buffer_ensure(buffers_[7], 16));
  const std::uint32_t zero[4] = {0, 0, 0, 0};
  R1_TRY(ctx_->buffer_write(buffers_[7], detail::bytes_of(std::span<const std::uint32_t>(zero)), 0));
  Slot slots[11];
  for (std::uint32_t s = 0; s < (nd != nullptr ? 11u : 8u); ++s) slots[s] = {s, buffers_[s]};
  const std::span<const Slot> bound(slots, nd != nullptr ? 11 : 8);
  const Slot infer_slots[] = {{0, buffers_[8]}, {1, buffers_[9]}, {2, buffers_[11]}, {3, buffers_[10]}, {4, buffers_[12]}, {5, buffers_[13]}};
  std::vector<float> flows(pixels * 3, 0.0f);
  host_pixels.clear();
  for (std::size_t y0 = 0; y0 < cam.height; y0 += band) {
    const std::size_t rows = std::min<std::size_t>(band, cam.height - y0), n = rows * cam.width, at = y0 * cam.width;
    R1_TRY(ctx_->buffer_write(buffers_[4], detail::bytes_of(opaque.subspan(at * 4, n * 4)), 0));
    std::array<std::uint32_t, 25> push{cam.width, cam.height, static_cast<std::uint32_t>(y0), static_cast<std::uint32_t>(rows),
                                             child_ptr, child, member_ptr, top_ptr, top, splat_ptr, splat_list,
                                             field.level_offset[0], field.level_offset[1], field.level_offset[2],
                                             field.level_offset[3], field.level_offset[4], field.tiles_x, field.samples,
                                             field.enabled ? 1u : 0u, static_cast<std::uint32_t>(field.top_ptr.empty() ? 0 : field.top_ptr.size() - 1),
                                             static_cast<std::uint32_t>(field.seed), static_cast<std::uint32_t>(field.seed >> 32), next,
                                             parent, 0};
    std::array<std::uint8_t, sizeof push> push_bytes;
    const std::array<std::uint32_t, 3> groups = {(cam.width + 7) / 8, static_cast<std::uint32_t>((rows + 7) / 8), 1};
    if (nd != nullptr) {
      // List the samples, infer the network at them, then composite with its outputs.
      push[24] = 1;
      std::memcpy(push_bytes.data(), push.data(), sizeof push);
      R1_TRY(ctx_->dispatch(pipeline_, bound, groups, push_bytes));
      infer_push[0] = static_cast<std::uint32_t>(n);
      std::array<std::uint8_t, sizeof infer_push> ib;
      std::memcpy(ib.data(), infer_push.data(), sizeof infer_push);
      R1_TRY(ctx_->dispatch(infer_, infer_slots, detail::groups_for(std::uint64_t{n} * std::max<std::uint32_t>(field.samples, 1)), ib));
      push[24] = 2;
    }
    std::memcpy(push_bytes.data(), push.data(), sizeof push);
    R1_TRY(ctx_->dispatch(pipeline_, bound, groups, push_bytes));
    R1_ASSIGN(const auto out, ctx_->buffer_read(buffers_[5], 0, n * 28));
    for (std::size_t k = 0; k < n; ++k) {
      float v[7];
      std::memcpy(v, out.data() + k * 28, 28);
      if (std::isnan(v[3])) host_pixels.push_back(static_cast<std::uint32_t>(at + k));
      std::copy(v, v + 4, rgba.begin() + static_cast<std::ptrdiff_t>((at + k) * 4));
      std::copy(v + 4, v + 7, flows.begin() + static_cast<std::ptrdiff_t>((at + k) * 3));
    }
  }
  R1_ASSIGN(const auto flags, ctx_->buffer_read(buffers_[7], 0, 16));
  std::uint32_t f[4];
  std::memcpy(f, flags.data(), 16);
  inferred_ = f[2];
  rewalked_ = f[3];
  flow.clear();
  if (f[1] != 0) flow = std::move(flows);
  return Status::ok();
}

}  // namespace r1::vk
