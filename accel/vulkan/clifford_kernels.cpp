// The Clifford primitives of the R-1.0 13.1 trait as Vulkan compute shaders (R1-BKD-062): the
// reference's fp64 evaluation order, every expression `precise` (no contraction into fma), and
// det_exp by the same Cody-Waite reduction and Taylor polynomial with the caller's constants.
#include <algorithm>
#include <cstring>
#include <limits>
#include <string>

#include "r1/accel/vulkan.hpp"
#include "shader_common.hpp"

namespace r1::vk {

namespace {

// Tensor buffers (R1-BKD-013): u32 n, u32 d, then n x d doubles: std430 puts v at byte 8.
// Binding 7 holds det_exp's constants: log2 e, ln 2 (high, low), then the Taylor coefficients.
constexpr const char* kPrelude = R"(#version 460
layout(local_size_x = 64) in;
layout(std430, set = 0, binding = 7) readonly buffer Constants { double k[]; } consts;
const int kDegree = 13;

double pow2(int k) { return packDouble2x32(uvec2(0u, uint(k + 1023) << 20)); }

double det_exp(double x) {
  if (isnan(x)) return x;
  if (x > 710.0LF) return packDouble2x32(uvec2(0u, 0x7ff00000u));
  if (x < -746.0LF) return 0.0LF;
  precise double t = x * consts.k[0];
  int k = int(t >= 0.0LF ? t + 0.5LF : t - 0.5LF);
  double kd = double(k);
  precise double r = (x - kd * consts.k[1]) - kd * consts.k[2];
  precise double p = consts.k[3 + kDegree];
  for (int n = kDegree - 1; n >= 0; --n) p = p * r + consts.k[3 + n];
  if (k >= -1022 && k <= 1023) return p * pow2(k);
  int k1 = k >= 0 ? k / 2 : -((-k) / 2);
  precise double a = p * pow2(k1);
  precise double b = a * pow2(k - k1);
  return b;
}
double silu(double x) { precise double y = x / (1.0LF + det_exp(-x)); return y; }
double sigmoid(double x) { precise double y = 1.0LF / (1.0LF + det_exp(-x)); return y; }
uint element() { return gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 64u; }
)";

constexpr const char* kRoll = R"(
layout(std430, binding = 0) readonly buffer X { uint n; uint d; double v[]; } x;
layout(std430, binding = 1) buffer Y { uint n; uint d; double v[]; } y;
layout(push_constant) uniform P { uint s; uint axis; } p;
void main() {
  uint e = element();
  if (e >= x.n * x.d) return;
  uint i = e / x.d, c = e % x.d;
  if (p.axis == 1u) {
    uint to = c + p.s;
    if (to >= x.d) to -= x.d;
    y.v[i * x.d + to] = x.v[e];
  } else {
    uint to = i + p.s;
    if (to >= x.n) to -= x.n;
    y.v[to * x.d + c] = x.v[e];
  }
}
)";

// Inner (mode 0) or Wedge (mode 1) of every shift, the block of shift k at columns
// [offset + k stride, offset + k stride + d) of the output.
constexpr const char* kShifted = R"(
layout(std430, binding = 0) readonly buffer H { uint n; uint d; double v[]; } h;
layout(std430, binding = 1) readonly buffer C { uint n; uint d; double v[]; } c;
layout(std430, binding = 2) readonly buffer S { uint s[]; } sh;
layout(std430, binding = 3) buffer Y { uint n; uint d; double v[]; } y;
layout(push_constant) uniform P { uint mode; uint shifts; uint offset; uint stride; } p;
void main() {
  uint d = h.d, e = element();
  if (e >= h.n * p.shifts * d) return;
  uint i = e / (p.shifts * d), rest = e % (p.shifts * d);
  uint k = rest / d, ch = rest % d;
  uint j = ch + sh.s[k];
  if (j >= d) j -= d;
  precise double a = h.v[i * d + ch] * c.v[i * d + j];
  double out_value;
  if (p.mode == 0u) {
    out_value = silu(a);
  } else {
    precise double b = h.v[i * d + j] * c.v[i * d + ch];
    precise double w = a - b;
    out_value = w;
  }
  y.v[i * y.d + p.offset + k * p.stride + ch] = out_value;
}
)";

// y(i, o) = sum over ascending f of x(i, f) w(f, o), from +0, then + bias(o) (the reference's
// linear). w and bias are doubles of the parameter buffer at the given offsets (in doubles).
constexpr const char* kLinear = R"(
layout(std430, binding = 0) readonly buffer X { uint n; uint d; double v[]; } x;
layout(std430, binding = 1) readonly buffer W { double v[]; } w;
layout(std430, binding = 2) buffer Y { uint n; uint d; double v[]; } y;
layout(push_constant) uniform P { uint w_at; uint bias_at; } p;
void main() {
  uint e = element();
  uint outs = y.d;
  if (e >= x.n * outs) return;
  uint i = e / outs, o = e % outs;
  precise double acc = 0.0LF;
  for (uint f = 0u; f < x.d; ++f) acc = acc + x.v[i * x.d + f] * w.v[p.w_at + f * outs + o];
  acc = acc + w.v[p.bias_at + o];
  y.v[e] = acc;
}
)";

// The block's residual: gate = [H | G] wg + bg, out = x + gamma (silu(x) + sigmoid(gate) g).
constexpr const char* kResidual = R"(
layout(std430, binding = 0) readonly buffer H { uint n; uint d; double v[]; } h;
layout(std430, binding = 1) readonly buffer G { uint n; uint d; double v[]; } g;
layout(std430, binding = 2) readonly buffer W { double v[]; } w;
layout(std430, binding = 3) buffer Y { uint n; uint d; double v[]; } y;
layout(push_constant) uniform P { uint wg_at; uint bg_at; uint gamma_at; } p;
void main() {
  uint d = h.d, e = element();
  if (e >= h.n * d) return;
  uint i = e / d, ch = e % d;
  precise double gate = 0.0LF;
  for (uint f = 0u; f < d; ++f) gate = gate + h.v[i * d + f] * w.v[p.wg_at + f * d + ch];
  for (uint f = 0u; f < d; ++f) gate = gate + g.v[i * d + f] * w.v[p.wg_at + (d + f) * d + ch];
  gate = gate + w.v[p.bg_at + ch];
  double xv = h.v[e];
  precise double out_value = xv + w.v[p.gamma_at + ch] * (silu(xv) + sigmoid(gate) * g.v[e]);
  y.v[e] = out_value;
}
)";

std::string shape(std::uint32_t n, std::uint32_t d) { return std::to_string(n) + " x " + std::to_string(d); }

std::uint32_t mod(std::int64_t s, std::uint32_t m) {
  const std::int64_t r = s % static_cast<std::int64_t>(m);
  return static_cast<std::uint32_t>(r < 0 ? r + m : r);
}

template <class... T>
std::vector<std::uint8_t> words(T... w) {
  const std::uint32_t a[] = {static_cast<std::uint32_t>(w)...};
  std::vector<std::uint8_t> b(sizeof a);
  std::memcpy(b.data(), a, sizeof a);
  return b;
}


}  // namespace

struct CliffordKernels::Shape {
  std::uint32_t n = 0, d = 0;
};

Result<CliffordKernels> CliffordKernels::build(Context& ctx, const ExpConstants& c) {
  CliffordKernels k;
  k.ctx_ = &ctx;
  std::vector<double> values = {c.log2e, c.ln2_hi, c.ln2_lo};
  values.insert(values.end(), c.taylor.begin(), c.taylor.end());
  if (c.taylor.size() != 14) return Status::input("vulkan: det_exp takes 14 Taylor coefficients, not " + std::to_string(c.taylor.size()));
  R1_ASSIGN(k.constants_, ctx.buffer_create(values.size() * 8));
  std::vector<std::uint8_t> bytes(values.size() * 8);
  std::memcpy(bytes.data(), values.data(), bytes.size());
  R1_TRY(ctx.buffer_write(k.constants_, bytes, 0));
  const std::string prelude = kPrelude;
  R1_ASSIGN(k.roll_, ctx.compute_compile(prelude + kRoll, "clifford_roll"));
  R1_ASSIGN(k.shifted_, ctx.compute_compile(prelude + kShifted, "clifford_shifted"));
  R1_ASSIGN(k.linear_, ctx.compute_compile(prelude + kLinear, "clifford_linear"));
  R1_ASSIGN(k.residual_, ctx.compute_compile(prelude + kResidual, "clifford_residual"));
  return k;
}

Result<CliffordKernels::Shape> CliffordKernels::shape_of(std::uint32_t t, const char* what) {
  const std::size_t size = ctx_->buffer_size(t);
  if (size < 8) return Status::input("vulkan: buffer " + std::to_string(t) + " is no tensor (" + std::to_string(size) + " bytes)");
  R1_ASSIGN(const auto head, ctx_->buffer_read(t, 0, 8));
  Shape s;
  std::memcpy(&s.n, head.data(), 4);
  std::memcpy(&s.d, head.data() + 4, 4);
  if (s.d == 0) return Status::input(std::string("clifford: ") + what + " has no channels (d = 0)");
  if (std::uint64_t{s.n} * s.d * 8 + 8 != size)
    return Status::input(std::string("clifford: ") + what + " buffer holds " + std::to_string(size) + " bytes, not the " +
                         std::to_string(std::uint64_t{s.n} * s.d * 8 + 8) + " of " + shape(s.n, s.d));
  return s;
}

Result<std::uint32_t> CliffordKernels::tensor(std::uint32_t n, std::uint32_t d) {
  R1_ASSIGN(const std::uint32_t id, ctx_->buffer_create(std::uint64_t{n} * d * 8 + 8));
  R1_TRY(ctx_->buffer_write(id, words(n, d), 0));
  return id;
}

Result<std::uint32_t> CliffordKernels::roll(std::uint32_t t, std::int32_t shift, std::uint32_t axis) {
  R1_ASSIGN(const Shape x, shape_of(t, "the tensor"));
  if (axis > 1) return Status::input("clifford: roll axis must be 0 (rows) or 1 (channels), got " + std::to_string(axis));
  R1_ASSIGN(const std::uint32_t out, tensor(x.n, x.d));
  if (x.n == 0) return out;
  const std::uint32_t s = mod(shift, axis == 1 ? x.d : x.n);
  const Slot slots[] = {{0, t}, {1, out}, {7, constants_}};
  R1_TRY(ctx_->dispatch(roll_, slots, detail::groups_for(std::uint64_t{x.n} * x.d), words(s, axis)));
  return out;
}

Result<std::uint32_t> CliffordKernels::shifted(std::uint32_t h, std::uint32_t c, std::span<const std::int32_t> shifts, bool inner,
                                               std::uint32_t width_factor) {
  R1_ASSIGN(const Shape a, shape_of(h, "H"));
  R1_ASSIGN(const Shape b, shape_of(c, "C"));
  if (a.n != b.n || a.d != b.d)
    return Status::input("clifford: H is " + shape(a.n, a.d) + " but C is " + shape(b.n, b.d) + "; they must match");
  if (shifts.empty()) return Status::input("clifford: the shift set is empty");
  const std::uint64_t cols = std::uint64_t{a.d} * shifts.size() * width_factor;
  if (cols > std::numeric_limits<std::uint32_t>::max())
    return Status::input("clifford: " + std::to_string(shifts.size()) + " shifts of " + std::to_string(a.d) + " channels are too many columns");
  std::vector<std::uint8_t> s(shifts.size() * 4);
  for (std::size_t k = 0; k < shifts.size(); ++k) {
    const std::uint32_t m = mod(shifts[k], a.d);
    std::memcpy(s.data() + 4 * k, &m, 4);
  }
  R1_ASSIGN(const std::uint32_t sbuf, ctx_->buffer_create(s.size()));
  R1_TRY(ctx_->buffer_write(sbuf, s, 0));
  R1_ASSIGN(const std::uint32_t out, tensor(a.n, static_cast<std::uint32_t>(cols)));
  if (a.n == 0) return out;
  const Slot slots[] = {{0, h}, {1, c}, {2, sbuf}, {3, out}, {7, constants_}};
  const auto k = static_cast<std::uint32_t>(shifts.size());
  const auto groups = detail::groups_for(std::uint64_t{a.n} * k * a.d);
  if (width_factor == 1) {
    R1_TRY(ctx_->dispatch(shifted_, slots, groups, words(inner ? 0 : 1, k, 0, a.d)));
  } else {  // the Clifford features: Inner and Wedge interleaved per shift, 2 d columns each
    R1_TRY(ctx_->dispatch(shifted_, slots, groups, words(0, k, 0, 2 * a.d)));
    R1_TRY(ctx_->dispatch(shifted_, slots, groups, words(1, k, a.d, 2 * a.d)));
  }
  return out;
}

Result<std::uint32_t> CliffordKernels::shifted_inner(std::uint32_t h, std::uint32_t c, std::span<const std::int32_t> shifts) {
  return shifted(h, c, shifts, true, 1);
}

Result<std::uint32_t> CliffordKernels::shifted_wedge(std::uint32_t h, std::uint32_t c, std::span<const std::int32_t> shifts) {
  return shifted(h, c, shifts, false, 1);
}

Result<std::uint32_t> CliffordKernels::block(std::uint32_t h, std::uint32_t c, std::span<const std::int32_t> shifts, std::uint32_t gate) {
  R1_ASSIGN(const Shape a, shape_of(h, "H"));
  R1_ASSIGN(const std::uint32_t features, shifted(h, c, shifts, true, 2));
  const std::uint64_t d = a.d, s = shifts.size();
  const std::uint64_t sizes[5] = {2 * s * d * d, d, 2 * d * d, d, d};  // w, bias, wg, bg, gamma
  std::uint64_t total = 0, at[5];
  for (std::size_t k = 0; k < 5; ++k) {
    at[k] = total;
    total += sizes[k];
  }
  if (ctx_->buffer_size(gate) != total * 8)
    return Status::input("vulkan: gate buffer " + std::to_string(gate) + " holds " + std::to_string(ctx_->buffer_size(gate)) +
                         " bytes, expected " + std::to_string(total * 8) + " for d = " + std::to_string(d) + " and " +
                         std::to_string(s) + " shifts");
  if (total > std::numeric_limits<std::uint32_t>::max()) return Status::input("vulkan: the gate buffer is too large");
  R1_ASSIGN(const std::uint32_t g, tensor(a.n, a.d));
  R1_ASSIGN(const std::uint32_t out, tensor(a.n, a.d));
  if (a.n == 0) return out;
  const auto groups = detail::groups_for(std::uint64_t{a.n} * a.d);
  const Slot linear_slots[] = {{0, features}, {1, gate}, {2, g}, {7, constants_}};
  R1_TRY(ctx_->dispatch(linear_, linear_slots, groups, words(at[0], at[1])));
  const Slot residual_slots[] = {{0, h}, {1, g}, {2, gate}, {3, out}, {7, constants_}};
  R1_TRY(ctx_->dispatch(residual_, residual_slots, groups, words(at[2], at[3], at[4])));
  return out;
}

}  // namespace r1::vk
