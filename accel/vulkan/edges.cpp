// The frame's edge tubes on a Vulkan device (R1-BKD-075): one invocation a pixel over the opaque
// layer the impostors left, casting the pixel's ray at the tubes binned into its 16-pixel tile, in
// tube order, with the reference's open-wall intersection (reference/render/shapes.cpp
// intersect_tube) and strip shading (renderer.cpp draw_edge_tubes) in fp64, every expression
// `precise`. GLSL has no fp64 cosine: det_cos reduces by pi/2 in two parts (Cody-Waite) and sums
// Taylor series to degree 19 on |r| <= pi/4.
#include <algorithm>
#include <cstring>
#include <limits>
#include <string>
#include <utility>

#include "r1/accel/vulkan.hpp"
#include "shader_common.hpp"

namespace r1::vk {

using render::Vec3;

namespace {

constexpr std::uint32_t kTile = 16;
constexpr std::uint32_t kNone = 0xffffffffu;

// Bindings: 0 tubes (16 doubles each), 1 rows (4 words each), 2 spans (2 ints a row), 3 tiles
// (tiles + 1 offsets, then the tube indices), 4 t, 5 colour (3 doubles a pixel), 6 owner (the
// band's pixels, read and written), 7 camera (position, right, up, forward, focal_px, time).
constexpr const char* kHeader = R"(#version 460
layout(local_size_x = 8, local_size_y = 8) in;
layout(std430, binding = 0) readonly buffer G { double tube[]; };
layout(std430, binding = 1) readonly buffer R { uint row_meta[]; };
layout(std430, binding = 2) readonly buffer S { int span[]; };
layout(std430, binding = 3) readonly buffer T { uint tiles[]; };
layout(std430, binding = 4) buffer LT { double lay_t[]; };
layout(std430, binding = 5) buffer LC { double lay_c[]; };
layout(std430, binding = 6) buffer LO { int lay_o[]; };
layout(std430, binding = 7) readonly buffer CAM { double cam[]; };
layout(push_constant) uniform P { uint width; uint height; uint tiles_x; uint y0; uint rows; } p;
#define CAMERA cam
)";

constexpr const char* kMain = R"(
// cos x for 0 <= x <= 2 pi: x = k pi/2 + r with |r| <= pi/4 (pi/2 in a 33-bit head, exact times
// k <= 4, and a tail), then cos r or sin r by Horner on the Taylor coefficients.
double det_cos(double x) {
  const double kTwoOverPi = 6.36619772367581382433e-01LF;
  const double kPio2Hi = 1.57079632673412561417e+00LF;
  const double kPio2Lo = 6.07710050650619224932e-11LF;
  precise double k = floor(x * kTwoOverPi + 0.5LF);
  precise double r = (x - k * kPio2Hi) - k * kPio2Lo;
  precise double r2 = r * r;
  precise double c = 1.0LF + r2 * (-1.0LF / 2.0LF + r2 * (1.0LF / 24.0LF + r2 * (-1.0LF / 720.0LF + r2 * (1.0LF / 40320.0LF
      + r2 * (-1.0LF / 3628800.0LF + r2 * (1.0LF / 479001600.0LF + r2 * (-1.0LF / 87178291200.0LF
      + r2 * (1.0LF / 20922789888000.0LF + r2 * (-1.0LF / 6402373705728000.0LF)))))))));
  precise double s = r * (1.0LF + r2 * (-1.0LF / 6.0LF + r2 * (1.0LF / 120.0LF + r2 * (-1.0LF / 5040.0LF
      + r2 * (1.0LF / 362880.0LF + r2 * (-1.0LF / 39916800.0LF + r2 * (1.0LF / 6227020800.0LF
      + r2 * (-1.0LF / 1307674368000.0LF + r2 * (1.0LF / 355687428096000.0LF
      + r2 * (-1.0LF / 121645100408832000.0LF))))))))));
  uint q = uint(int(k)) & 3u;
  if (q == 0u) return c;
  if (q == 1u) return -s;
  if (q == 2u) return -c;
  return s;
}

// intersect_tube: the open wall |o_perp + t d_perp| = radius between the ends, the first root in
// (tmin, tmax) whose axial parameter u lies in [0, 1].
bool tube_hit(dvec3 a, dvec3 b, double radius, dvec3 ro, dvec3 d, double tmin, double tmax, out double t, out dvec3 n,
              out double u) {
  t = 0.0LF; n = dvec3(0.0LF); u = 0.0LF;
  precise dvec3 w = b - a;
  double ww = dotp(w, w);
  if (ww == 0.0LF) return false;
  precise dvec3 o = ro - a;
  precise double so = dotp(o, w) / ww;
  precise dvec3 op = o - w * so;
  precise double sd = dotp(d, w) / ww;
  precise dvec3 dp = d - w * sd;
  double qa = dotp(dp, dp);
  if (qa == 0.0LF) return false;
  double bh = dotp(op, dp);
  precise double sf = bh / qa;
  precise dvec3 f = op - dp * sf;
  precise double rr = radius * radius;
  precise double c = dotp(op, op) - rr;
  precise double disc = qa * (rr - dotp(f, f));
  double r0, r1;
  if (quadratic_roots(qa, bh, c, disc, r0, r1) == 0) return false;
  for (int i = 0; i < 2; ++i) {
    double ti = i == 0 ? r0 : r1;
    if (!(ti > tmin && ti < tmax)) continue;
    precise dvec3 x = o + d * ti;
    precise double ui = dotp(x, w) / ww;
    if (!(ui >= 0.0LF && ui <= 1.0LF)) continue;
    precise dvec3 radial = x - w * ui;
    t = ti;
    n = nrm(radial);
    u = ui;
    return true;
  }
  return false;
}

void main() {
  uint x = gl_GlobalInvocationID.x, y = p.y0 + gl_GlobalInvocationID.y;
  if (x >= p.width || gl_GlobalInvocationID.y >= p.rows) return;
  uint px = gl_GlobalInvocationID.y * p.width + x;  // within the band
  double best = lay_t[px];
  dvec3 color = dvec3(lay_c[px * 3u], lay_c[px * 3u + 1u], lay_c[px * 3u + 2u]);
  int owner = lay_o[px];
  bool changed = false;
  dvec3 pos = dvec3(cam[0], cam[1], cam[2]);
  dvec3 d = pixel_dir(x, y, p.width, p.height);
  double time = cam[13];
  uint tile = (y / 16u) * p.tiles_x + x / 16u;
  for (uint k = tiles[tile]; k < tiles[tile + 1u]; ++k) {
    uint i = tiles[k];
    int r = int(y) - int(row_meta[i * 4u]);
    if (r < 0 || r >= int(row_meta[i * 4u + 1u])) continue;
    uint sp = (row_meta[i * 4u + 2u] + uint(r)) * 2u;
    if (int(x) < span[sp] || int(x) >= span[sp + 1u]) continue;
    uint g = i * 16u;
    dvec3 a = dvec3(tube[g], tube[g + 1u], tube[g + 2u]), b = dvec3(tube[g + 3u], tube[g + 4u], tube[g + 5u]);
    double t, u; dvec3 n;
    if (!tube_hit(a, b, tube[g + 6u], pos, d, kNear, best, t, n, u)) continue;
    precise double phase = tube[g + 7u] * u - tube[g + 8u] * time;
    precise double frac = phase - floor(phase);
    precise double strip = 0.55LF + 0.45LF * 0.5LF * (1.0LF + det_cos(2.0LF * kPi * frac));
    precise double s6 = 0.6LF * strip;
    precise double v = 1.0LF - u;
    precise dvec3 albedo = dvec3((tube[g + 9u] * v + tube[g + 12u] * u) * s6, (tube[g + 10u] * v + tube[g + 13u] * u) * s6,
                                 (tube[g + 11u] * v + tube[g + 14u] * u) * s6);
    precise double l = -dotp(n, d);
    precise double lit = 0.25LF + 0.75LF * (0.0LF < l ? l : 0.0LF);
    best = t;
    color = dvec3(albedo.x * lit, albedo.y * lit, albedo.z * lit);
    owner = -2;
    changed = true;
  }
  if (!changed) return;
  lay_t[px] = best;
  lay_c[px * 3u] = color.x; lay_c[px * 3u + 1u] = color.y; lay_c[px * 3u + 2u] = color.z;
  lay_o[px] = owner;
}
)";

}  // namespace

EdgePass& EdgePass::operator=(EdgePass&& o) noexcept {
  if (this == &o) return *this;
  this->~EdgePass();
  ctx_ = std::exchange(o.ctx_, nullptr);
  pipeline_ = o.pipeline_;
  buffers_ = std::exchange(o.buffers_, {});
  return *this;
}

EdgePass::~EdgePass() {
  if (ctx_ == nullptr) return;
  for (const std::uint32_t id : buffers_) ctx_->buffer_release(id);
  ctx_ = nullptr;
}

Result<EdgePass> EdgePass::build(Context& ctx) {
  EdgePass pass;
  pass.ctx_ = &ctx;
  R1_ASSIGN(pass.pipeline_,
            ctx.compute_compile(std::string(kHeader) + detail::kPixelRay + detail::kRayRoots + kMain, "edges"));
  return pass;
}

Result<bool> EdgePass::draw(const ImpostorCamera& cam, const EdgeData& edges, std::span<double> t, std::span<Vec3> color,
                            std::span<std::int64_t> owner) {
  const std::size_t pixels = std::size_t{cam.width} * cam.height;
  if (cam.width == 0 || cam.height == 0 || t.size() != pixels || color.size() != pixels || owner.size() != pixels)
    return Status::input("vulkan edges: the layer is not " + std::to_string(cam.width) + " x " + std::to_string(cam.height));
  const std::size_t count = edges.tubes.size() / 16;
  if (edges.tubes.size() != count * 16 || edges.rows.size() != count * 4)
    return Status::input("vulkan edges: " + std::to_string(count) + " tubes with " + std::to_string(edges.rows.size()) + " row words");
  if (count == 0) return true;
  // Bin the tubes into 16-pixel tiles by their row spans, each tile's list in tube order.
  const std::uint32_t tiles_x = (cam.width + kTile - 1) / kTile, tiles_y = (cam.height + kTile - 1) / kTile;
  const std::size_t tiles = std::size_t{tiles_x} * tiles_y;
  std::vector<std::uint32_t> last(tiles, kNone);
  const auto tiles_of = [&](std::uint32_t i, auto&& fn) -> Status {
    const std::uint32_t first = edges.rows[i * 4], rows = edges.rows[i * 4 + 1], at = edges.rows[i * 4 + 2];
    if (std::size_t{at} + rows > edges.spans.size() / 2 || std::size_t{first} + rows > cam.height)
      return Status::input("vulkan edges: tube " + std::to_string(i) + "'s rows leave the image or its spans");
    for (std::uint32_t r = 0; r < rows; ++r) {
      const std::int32_t x0 = std::max(edges.spans[(std::size_t{at} + r) * 2], 0);
      const std::int32_t x1 = std::min<std::int32_t>(edges.spans[(std::size_t{at} + r) * 2 + 1], static_cast<std::int32_t>(cam.width));
      if (x0 >= x1) continue;
      const std::size_t ty = (first + r) / kTile;
      for (auto tx = static_cast<std::size_t>(x0) / kTile; tx <= static_cast<std::size_t>(x1 - 1) / kTile; ++tx) {
        const std::size_t k = ty * tiles_x + tx;
        if (last[k] == i) continue;
        last[k] = i;
        fn(k);
      }
    }
    return Status::ok();
  };
  std::vector<std::uint32_t> list(tiles + 1, 0);
  for (std::uint32_t i = 0; i < count; ++i) R1_TRY(tiles_of(i, [&](std::size_t k) { ++list[k + 1]; }));
  std::size_t entries = 0;
  for (std::size_t k = 1; k <= tiles; ++k) {
    if (list[k] > kMaxTileTubes) return false;  // declined: lavapipe's loop limit
    entries += list[k];
    list[k] += list[k - 1];
  }
  if (entries + tiles + 1 >= 0xffffffffu) return false;
  for (std::size_t k = 0; k <= tiles; ++k) list[k] += static_cast<std::uint32_t>(tiles + 1);
  list.resize(tiles + 1 + entries);
  std::vector<std::uint32_t> fill(list.begin(), list.begin() + static_cast<std::ptrdiff_t>(tiles));
  std::fill(last.begin(), last.end(), kNone);
  for (std::uint32_t i = 0; i < count; ++i) R1_TRY(tiles_of(i, [&](std::size_t k) { list[fill[k]++] = i; }));

  Context& ctx = *ctx_;
  const double camera[16] = {cam.position.x, cam.position.y, cam.position.z, cam.right.x, cam.right.y, cam.right.z,
                             cam.up.x,       cam.up.y,       cam.up.z,       cam.forward.x, cam.forward.y, cam.forward.z,
                             cam.focal_px,   edges.time,     0,              0};
  const auto upload = [&](std::size_t which, std::span<const std::uint8_t> bytes) -> Status {
    R1_TRY(ctx.buffer_ensure(buffers_[which], std::max<std::size_t>(bytes.size(), 16)));
    return ctx.buffer_write(buffers_[which], bytes, 0);
  };
  R1_TRY(upload(0, detail::bytes_of(std::span<const double>(edges.tubes))));
  R1_TRY(upload(1, detail::bytes_of(std::span<const std::uint32_t>(edges.rows))));
  R1_TRY(upload(2, detail::bytes_of(std::span<const std::int32_t>(edges.spans))));
  R1_TRY(upload(3, detail::bytes_of(std::span<const std::uint32_t>(list))));
  R1_TRY(upload(7, detail::bytes_of(std::span<const double>(camera))));
  // The image in bands of rows whose colour fits one storage buffer: the band's layer up, the
  // pass, the band's layer back.
  const std::size_t max_rows = std::max<std::size_t>(1, ctx.info().max_buffer / (std::size_t{cam.width} * 3 * sizeof(double)));
  const std::size_t band_rows = std::min<std::size_t>(cam.height, max_rows);
  const std::size_t band_pixels = band_rows * cam.width;
  R1_TRY(ctx.buffer_ensure(buffers_[4], band_pixels * sizeof(double)));
  R1_TRY(ctx.buffer_ensure(buffers_[5], band_pixels * 3 * sizeof(double)));
  R1_TRY(ctx.buffer_ensure(buffers_[6], band_pixels * sizeof(std::int32_t)));
  Slot slots[8];
  for (std::uint32_t b = 0; b < 8; ++b) slots[b] = {b, buffers_[b]};
  std::vector<double> cbuf(band_pixels * 3);
  std::vector<std::int32_t> obuf(band_pixels);
  for (std::size_t y0 = 0; y0 < cam.height; y0 += band_rows) {
    const std::size_t rows = std::min<std::size_t>(band_rows, cam.height - y0), n = rows * cam.width, at = y0 * cam.width;
    for (std::size_t k = 0; k < n; ++k) {
      cbuf[k * 3] = color[at + k].x, cbuf[k * 3 + 1] = color[at + k].y, cbuf[k * 3 + 2] = color[at + k].z;
      obuf[k] = static_cast<std::int32_t>(owner[at + k]);
    }
    R1_TRY(ctx.buffer_write(buffers_[4], detail::bytes_of(std::span<const double>(t.data() + at, n)), 0));
    R1_TRY(ctx.buffer_write(buffers_[5], detail::bytes_of(std::span<const double>(cbuf.data(), n * 3)), 0));
    R1_TRY(ctx.buffer_write(buffers_[6], detail::bytes_of(std::span<const std::int32_t>(obuf.data(), n)), 0));
    R1_TRY(detail::layer_band(ctx, pipeline_, slots, cam.width, cam.height, tiles_x, y0, rows, {buffers_[4], buffers_[5], buffers_[6]}, t,
                              color, owner));
  }
  return true;
}

}  // namespace r1::vk
