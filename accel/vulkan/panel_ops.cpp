// The spectral solver's exact Q32 inner products and combinations as Vulkan compute shaders
// (R1-BKD-069). Integer sums are exact, so the device's grouping of them never shows: the
// results are the portable kernels' bits (spectral::PanelOps<Q32>).
#include <algorithm>
#include <cstring>
#include <mutex>
#include <stdexcept>
#include <string>

#include "r1/accel/vulkan_panel.hpp"
#include "r1/solvers/exact_round.hpp"
#include "shader_common.hpp"

namespace r1::vk {

namespace {

using spectral::Cols;
using spectral::Panel;

constexpr const char* kVersion = "#version 460\n#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require\n";

// Inner products: invocation (pair, chunk) sums the products of rows [chunk c, chunk (c + 1)) of
// the data's columns q and nq + w, pair = q nw + w, into 192 bits.
constexpr const char* kDots = R"(
layout(std430, binding = 0) readonly buffer D { int64_t data[]; };
layout(std430, binding = 3) writeonly buffer O { uint64_t partial[]; };
layout(push_constant) uniform P { uint rows; uint k; uint nq; uint nw; uint chunk; uint chunks; } p;
void main() {
  uint g = invocation();
  if (g >= p.nq * p.nw * p.chunks) return;
  uint pair = g / p.chunks, c = g % p.chunks;
  uint q = pair / p.nw, w = p.nq + pair % p.nw;
  uint lo = c * p.chunk, hi = min(p.rows, lo + p.chunk);
  uint64_t s[3] = uint64_t[3](0ul, 0ul, 0ul);
  for (uint i = lo; i < hi; ++i) {
    uint64_t ph, pl;
    mul128(data[i * p.k + q], data[i * p.k + w], ph, pl);
    add128(s, ph, pl);
  }
  partial[g * 3u] = s[0];
  partial[g * 3u + 1u] = s[1];
  partial[g * 3u + 2u] = s[2];
}
)";

// Combinations: invocation (row, o) forms base_o 2^60 + sum_t coef[t no + o] x_t in 192 bits and
// rounds it once by 2^60, ties to even; a result outside int64 marks the first such row.
constexpr const char* kCombine = R"(
layout(std430, binding = 0) readonly buffer D { int64_t data[]; };
layout(std430, binding = 1) readonly buffer C { int64_t coef[]; };
layout(std430, binding = 4) writeonly buffer O { int64_t result[]; };
layout(std430, binding = 5) buffer F { uint first_overflow; };
layout(push_constant) uniform P { uint rows; uint k; uint nt; uint no; uint bases; uint row0; } p;
void main() {
  uint g = invocation();
  if (g >= p.rows * p.no) return;
  uint i = g / p.no, o = g % p.no;
  uint64_t s[3] = uint64_t[3](0ul, 0ul, 0ul);
  if (p.bases != 0u) {
    int64_t b = data[i * p.k + p.nt + o];
    s[0] = uint64_t(b) << 60;
    s[1] = uint64_t(b >> 4);
    s[2] = b < 0l ? ~0ul : 0ul;
  }
  for (uint t = 0u; t < p.nt; ++t) {
    uint64_t ph, pl;
    mul128(coef[t * p.no + o], data[i * p.k + t], ph, pl);
    add128(s, ph, pl);
  }
  int64_t r;
  if (!round192(s, 60u, r)) {
    atomicMin(first_overflow, p.row0 + i);
    result[g] = 0l;
    return;
  }
  result[g] = r;
}
)";

constexpr std::uint32_t kChunk = 256;  // rows an inner-product invocation sums

// The pipelines and buffers one context's kernels share; calls are serialised.
struct Shared {
  std::shared_ptr<Context> ctx;
  std::uint32_t dots = 0, combine = 0;
  std::uint32_t data = 0, coef = 0, partial = 0, result = 0, flag = 0;
  std::mutex lock;
};


template <std::size_t N>
std::array<std::uint8_t, N * 4> push_of(const std::array<std::uint32_t, N>& words) {
  std::array<std::uint8_t, N * 4> b{};
  std::memcpy(b.data(), words.data(), N * 4);
  return b;
}

// Rows [r0, r0 + rows) of the listed columns, side by side: the data a shader reads.
std::vector<std::int64_t> gather(const Panel<fx::Q32>& p, std::size_t r0, std::size_t rows, Cols a, Cols b) {
  const std::size_t k = a.size() + b.size();
  std::vector<std::int64_t> out(rows * k);
  for (std::size_t i = 0; i < rows; ++i) {
    const fx::Q32* row = p.row(r0 + i);
    std::int64_t* o = out.data() + i * k;
    for (const std::uint32_t c : a) *o++ = row[c].raw;
    for (const std::uint32_t c : b) *o++ = row[c].raw;
  }
  return out;
}

class VulkanPanelOps final : public spectral::PanelOps<fx::Q32> {
 public:
  VulkanPanelOps(std::shared_ptr<Shared> shared, std::size_t n, int e, bool parallel, int frac)
      : PanelOps<fx::Q32>(n, e, parallel, frac), s_(std::move(shared)) {}

  void dots(const Panel<fx::Q32>& p, Cols qs, Cols ws, std::span<double> out) const override {
    spectral::check_dots(p.rows(), size(), p.cols(), qs, ws, out.size());
    const std::size_t nq = qs.size(), nw = ws.size(), pairs = nq * nw, k = nq + nw;
    if (pairs == 0) return;
    std::lock_guard<std::mutex> guard(s_->lock);
    Context& ctx = *s_->ctx;
    std::vector<fx::ExactSum> total(pairs);
    // Bands of rows whose data fits one storage buffer and whose partial sums stay few.
    const std::size_t band = std::max<std::size_t>(
        kChunk, std::min(ctx.info().max_buffer / (k * 8) / kChunk * kChunk, std::size_t{kChunk} * (std::size_t{1} << 16)));
    for (std::size_t r0 = 0; r0 < size(); r0 += band) {
      const std::size_t rows = std::min(band, size() - r0), chunks = (rows + kChunk - 1) / kChunk;
      const std::vector<std::int64_t> data = gather(p, r0, rows, qs, ws);
      ok(ctx.buffer_ensure(s_->data, data.size() * 8));
      ok(ctx.buffer_write(s_->data, detail::bytes_of(std::span<const std::int64_t>(data)), 0));
      ok(ctx.buffer_ensure(s_->partial, pairs * chunks * 24));
      const std::array<std::uint32_t, 6> push{static_cast<std::uint32_t>(rows), static_cast<std::uint32_t>(k),
                                              static_cast<std::uint32_t>(nq), static_cast<std::uint32_t>(nw), kChunk,
                                              static_cast<std::uint32_t>(chunks)};
      const Slot slots[] = {{0, s_->data}, {3, s_->partial}};
      ok(ctx.dispatch(s_->dots, slots, detail::groups_for(pairs * chunks), push_of(push)));
      auto bytes = ctx.buffer_read(s_->partial, 0, pairs * chunks * 24);
      ok(bytes.status());
      for (std::size_t pr = 0; pr < pairs; ++pr)
        for (std::size_t c = 0; c < chunks; ++c) {
          std::array<std::uint64_t, 3> limbs;
          std::memcpy(limbs.data(), bytes->data() + (pr * chunks + c) * 24, 24);
          total[pr].merge(fx::ExactSum::from_limbs(limbs));
        }
    }
    // Products count units of 2^-(2 frac); the scaled inner product divides by 2^e.
    for (std::size_t pr = 0; pr < pairs; ++pr) out[pr] = spectral::to_double_scaled(total[pr], 2 * frac_bits() + scale_exponent());
  }

  void combine(Panel<fx::Q32>& p, Cols outs, Cols bases, Cols terms, std::span<const double> c) const override {
    spectral::check_combine(p.rows(), size(), p.cols(), outs, bases, terms, c.size());
    const std::size_t no = outs.size(), nt = terms.size(), k = nt + bases.size();
    if (no == 0) return;
    std::vector<std::int64_t> coef(nt * no);
    for (std::size_t t = 0; t < nt; ++t)
      for (std::size_t o = 0; o < no; ++o) coef[t * no + o] = spectral::coef60(c[t * no + o]);
    std::lock_guard<std::mutex> guard(s_->lock);
    Context& ctx = *s_->ctx;
    ok(ctx.buffer_ensure(s_->coef, std::max<std::size_t>(coef.size() * 8, 8)));
    ok(ctx.buffer_write(s_->coef, detail::bytes_of(std::span<const std::int64_t>(coef)), 0));
    ok(ctx.buffer_ensure(s_->flag, 4));
    const std::size_t per_row = std::max(k, no) * 8;
    const std::size_t band = std::max<std::size_t>(1, ctx.info().max_buffer / per_row);
    // Every band is read before any result is written back, band by band: a row's results
    // depend on that row only.
    for (std::size_t r0 = 0; r0 < size(); r0 += band) {
      const std::size_t rows = std::min(band, size() - r0);
      const std::vector<std::int64_t> data = gather(p, r0, rows, terms, bases);
      ok(ctx.buffer_ensure(s_->data, std::max<std::size_t>(data.size() * 8, 8)));
      ok(ctx.buffer_write(s_->data, detail::bytes_of(std::span<const std::int64_t>(data)), 0));
      ok(ctx.buffer_ensure(s_->result, rows * no * 8));
      const std::uint32_t none = 0xffffffffu;
      ok(ctx.buffer_write(s_->flag, std::span(reinterpret_cast<const std::uint8_t*>(&none), 4), 0));
      const std::array<std::uint32_t, 6> push{static_cast<std::uint32_t>(rows), static_cast<std::uint32_t>(k),
                                              static_cast<std::uint32_t>(nt), static_cast<std::uint32_t>(no),
                                              bases.empty() ? 0u : 1u, static_cast<std::uint32_t>(r0)};
      const Slot slots[] = {{0, s_->data}, {1, s_->coef}, {4, s_->result}, {5, s_->flag}};
      ok(ctx.dispatch(s_->combine, slots, detail::groups_for(rows * no), push_of(push)));
      auto flag = ctx.buffer_read(s_->flag, 0, 4);
      ok(flag.status());
      std::uint32_t first = 0;
      std::memcpy(&first, flag->data(), 4);
      if (first != none) fx::detail::throw_overflow("spectral round");
      auto result = ctx.buffer_read(s_->result, 0, rows * no * 8);
      ok(result.status());
      for (std::size_t i = 0; i < rows; ++i) {
        fx::Q32* row = p.row(r0 + i);
        for (std::size_t o = 0; o < no; ++o) {
          std::int64_t v;
          std::memcpy(&v, result->data() + (i * no + o) * 8, 8);
          row[outs[o]] = fx::Q32::from_raw(v);
        }
      }
    }
  }

 private:
  // A device failure inside a kernel: the solver's interface has no error values, so it throws
  // (the stage turns it into an internal error naming itself).
  static void ok(const Status& st) {
    if (!st.is_ok()) throw std::runtime_error(st.message());
  }
  std::shared_ptr<Shared> s_;
};

}  // namespace

Result<Q32KernelFactory> panel_kernel_factory(std::shared_ptr<Context> ctx) {
  auto shared = std::make_shared<Shared>();
  shared->ctx = std::move(ctx);
  R1_ASSIGN(shared->dots, shared->ctx->compute_compile(std::string(kVersion) + detail::kWideInt + kDots, "spectral_dots"));
  R1_ASSIGN(shared->combine, shared->ctx->compute_compile(std::string(kVersion) + detail::kWideInt + kCombine, "spectral_combine"));
  return Q32KernelFactory([shared](std::size_t n, int e, bool parallel, int frac) -> std::unique_ptr<spectral::PanelOps<fx::Q32>> {
    return std::make_unique<VulkanPanelOps>(shared, n, e, parallel, frac);
  });
}

}  // namespace r1::vk
