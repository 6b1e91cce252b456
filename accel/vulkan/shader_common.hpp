// What accel/vulkan's kernels share (internal): the host side of a dispatch, and GLSL snippets
// that several shaders need, written once.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <span>

#include "r1/accel/vulkan.hpp"

namespace r1::vk::detail {

template <class T>
std::span<const std::uint8_t> bytes_of(std::span<const T> v) {
  return {reinterpret_cast<const std::uint8_t*>(v.data()), v.size_bytes()};
}

// One band of rows of a per-pixel layer pass (the impostor and edge passes): 8 x 8 workgroups
// over `rows` rows from y0 (push constants width, height, tiles_x, y0, rows), then the band's
// t, colour (3 doubles) and owner (int32) read from buffers t_buf, c_buf, o_buf into the layer.
inline Status layer_band(Context& ctx, std::uint32_t pipeline, std::span<const Slot> slots, std::uint32_t width, std::uint32_t height,
                         std::uint32_t tiles_x, std::size_t y0, std::size_t rows, std::array<std::uint32_t, 3> bufs,
                         std::span<double> t, std::span<render::Vec3> color, std::span<std::int64_t> owner) {
  const std::size_t n = rows * width, at = y0 * width;
  const std::uint32_t push[5] = {width, height, tiles_x, static_cast<std::uint32_t>(y0), static_cast<std::uint32_t>(rows)};
  std::uint8_t push_bytes[sizeof push];
  std::memcpy(push_bytes, push, sizeof push);
  R1_TRY(ctx.dispatch(pipeline, slots, {(width + 7) / 8, static_cast<std::uint32_t>((rows + 7) / 8), 1}, push_bytes));
  R1_ASSIGN(const auto tb, ctx.buffer_read(bufs[0], 0, n * sizeof(double)));
  R1_ASSIGN(const auto cb, ctx.buffer_read(bufs[1], 0, n * 3 * sizeof(double)));
  R1_ASSIGN(const auto ob, ctx.buffer_read(bufs[2], 0, n * sizeof(std::int32_t)));
  std::memcpy(t.data() + at, tb.data(), tb.size());
  for (std::size_t k = 0; k < n; ++k) {
    double c[3];
    std::memcpy(c, cb.data() + k * 24, 24);
    color[at + k] = {c[0], c[1], c[2]};
    std::int32_t o = 0;
    std::memcpy(&o, ob.data() + k * 4, 4);
    owner[at + k] = o;
  }
  return Status::ok();
}

// Workgroups of 64 invocations for `count` elements, spread over y past the 65535 of x; the
// shader's element is invocation() of kWideInt (or the same expression).
inline std::array<std::uint32_t, 3> groups_for(std::uint64_t count) {
  const std::uint64_t g = std::max<std::uint64_t>(1, (count + 63) / 64);
  const std::uint64_t x = std::min<std::uint64_t>(g, 65535);
  return {static_cast<std::uint32_t>(x), static_cast<std::uint32_t>((g + x - 1) / x), 1};
}

// Exact integer arithmetic for 64-invocation compute shaders (after #version and the int64
// extension): magnitude, the signed 64 x 64 -> 128-bit product in (hi, lo), a signed 128-bit
// term added to a 192-bit two's complement sum, its rounding by a power of two, and the
// invocation's element index.
inline constexpr const char* kWideInt = R"(
layout(local_size_x = 64) in;

uint64_t magnitude(int64_t v) { return v < 0l ? uint64_t(-(v + 1l)) + 1ul : uint64_t(v); }

// a * b as a signed 128-bit (hi, lo): four 32-bit partial products of the magnitudes.
void mul128(int64_t a, int64_t b, out uint64_t hi, out uint64_t lo) {
  uint64_t x = magnitude(a), y = magnitude(b);
  uint64_t x0 = x & 0xfffffffful, x1 = x >> 32, y0 = y & 0xfffffffful, y1 = y >> 32;
  uint64_t p00 = x0 * y0, p01 = x0 * y1, p10 = x1 * y0, p11 = x1 * y1;
  uint64_t mid = (p00 >> 32) + (p01 & 0xfffffffful) + (p10 & 0xfffffffful);
  lo = (mid << 32) | (p00 & 0xfffffffful);
  hi = p11 + (p01 >> 32) + (p10 >> 32) + (mid >> 32);
  if ((a < 0l) != (b < 0l)) {
    lo = ~lo + 1ul;
    hi = ~hi + (lo == 0ul ? 1ul : 0ul);
  }
}

// s += the signed 128-bit (hi, lo), sign-extended to 192 bits.
void add128(inout uint64_t s[3], uint64_t hi, uint64_t lo) {
  uint64_t a = s[0] + lo;
  uint64_t c0 = a < lo ? 1ul : 0ul;
  uint64_t b = s[1] + hi;
  uint64_t c1 = b < hi ? 1ul : 0ul;
  uint64_t b2 = b + c0;
  c1 += b2 < b ? 1ul : 0ul;
  s[0] = a;
  s[1] = b2;
  s[2] += c1 + (int64_t(hi) < 0l ? ~0ul : 0ul);
}

// r = the 192-bit s / 2^shift (0 < shift < 64) rounded half to even, as fx::detail::rne_shift
// rounds; false when that leaves int64.
bool round192(uint64_t s[3], uint shift, out int64_t r) {
  uint64_t q0 = (s[0] >> shift) | (s[1] << (64u - shift)), q1 = (s[1] >> shift) | (s[2] << (64u - shift));
  uint64_t q2 = uint64_t(int64_t(s[2]) >> shift);
  uint64_t rem = s[0] & ((1ul << shift) - 1ul), tie = 1ul << (shift - 1u);
  if (rem > tie || (rem == tie && (q0 & 1ul) != 0ul)) {
    q0 += 1ul;
    if (q0 == 0ul) {
      q1 += 1ul;
      if (q1 == 0ul) q2 += 1ul;
    }
  }
  uint64_t ext = uint64_t(int64_t(q0) >> 63);
  r = int64_t(q0);
  return q1 == ext && q2 == ext;
}

uint invocation() { return gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 64u; }
)";

// The reference's vector helpers and primary ray (render::pixel_ray) in fp64, every value
// `precise`. The shader defines CAMERA as a double array holding the camera position, right,
// up, forward and focal_px at 0..12.
inline constexpr const char* kPixelRay = R"(
double dotp(dvec3 a, dvec3 b) { precise double r = a.x * b.x + a.y * b.y + a.z * b.z; return r; }
double len(dvec3 a) { precise double r = sqrt(dotp(a, a)); return r; }
dvec3 nrm(dvec3 a) { double l = len(a); precise dvec3 r = dvec3(a.x / l, a.y / l, a.z / l); return r; }

// The unit direction through pixel centre (x + 0.5, y + 0.5) of a width x height image.
dvec3 pixel_dir(uint x, uint y, uint width, uint height) {
  dvec3 right = dvec3(CAMERA[3], CAMERA[4], CAMERA[5]);
  dvec3 up = dvec3(CAMERA[6], CAMERA[7], CAMERA[8]);
  dvec3 fwd = dvec3(CAMERA[9], CAMERA[10], CAMERA[11]);
  double focal = CAMERA[12];
  precise double sx = ((double(x) + 0.5LF) - double(width) * 0.5LF) / focal;
  precise double sy = (double(height) * 0.5LF - (double(y) + 0.5LF)) / focal;
  precise dvec3 dir = dvec3(fwd.x + right.x * sx + up.x * sy, fwd.y + right.y * sx + up.y * sy,
                            fwd.z + right.z * sx + up.z * sy);
  return nrm(dir);
}
)";

// The ray casts' shared pieces (after kPixelRay): the near plane and pi of the reference
// (reference/render/shapes.cpp), +infinity, copysign, and the reference's stable quadratic roots
// of a t^2 + 2 bh t + c with the discriminant given, ascending (0 or 2 roots; q = 0 gives two
// zeros, as the reference does).
inline constexpr const char* kRayRoots = R"(
const double kNear = 1e-3LF;
const double kPi = 3.14159265358979323846LF;

double inf() { return packDouble2x32(uvec2(0u, 0x7ff00000u)); }
double copysign_of(double m, double s) { return (unpackDouble2x32(s).y >> 31) != 0u ? -abs(m) : abs(m); }

int quadratic_roots(double a, double bh, double c, double disc, out double r0, out double r1) {
  r0 = 0.0LF; r1 = 0.0LF;
  if (!(disc >= 0.0LF)) return 0;
  precise double s = sqrt(disc);
  precise double q = -(bh + copysign_of(s, bh));
  if (q == 0.0LF) return 2;
  precise double x0 = q / a;
  precise double x1 = c / q;
  if (x0 > x1) { r0 = x1; r1 = x0; } else { r0 = x0; r1 = x1; }
  return 2;
}
)";

}  // namespace r1::vk::detail
