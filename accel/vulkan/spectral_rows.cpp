// The spectral operator's rows on a Vulkan device (R1-SPEC-073, R1-BKD-071): for a compact block
// of columns, x_i 2^32 - sum_k M_ik x_k - g_i coef in 192 bits, rounded once by 2^32, ties to even,
// so the solver's block applications are the host's bits (SpectralOperator<Q32>::apply_block).
#include <algorithm>
#include <array>
#include <cstring>
#include <mutex>
#include <stdexcept>
#include <string>

#include "r1/accel/vulkan_panel.hpp"
#include "shader_common.hpp"

namespace r1::vk {

namespace {

constexpr const char* kVersion = "#version 460\n#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require\n";
// One invocation per (row, column) of the block: its loop runs over the row's stored entries, so
// an operator with a row longer than kLongestRow is declined (the host's rows run it, R1-BKD-073).

constexpr const char* kRows = R"(
layout(std430, binding = 0) readonly buffer R { uint64_t row_ptr[]; };
layout(std430, binding = 1) readonly buffer C { uint col[]; };
layout(std430, binding = 2) readonly buffer M { int64_t m[]; };
layout(std430, binding = 3) readonly buffer G { int64_t g[]; };
layout(std430, binding = 4) readonly buffer X { int64_t x[]; };
layout(std430, binding = 5) readonly buffer K { int64_t coef[]; };
layout(std430, binding = 6) writeonly buffer Y { int64_t y[]; };
layout(std430, binding = 7) buffer F { uint first_overflow; };
layout(push_constant) uniform P { uint rows; uint count; uint has_g; } p;
void main() {
  uint v = invocation();
  if (v >= p.rows * p.count) return;
  uint i = v / p.count, a = v % p.count;
  uint64_t s[3], ph, pl;
  mul128(x[v], 4294967296l, ph, pl);
  s[0] = pl;
  s[1] = ph;
  s[2] = int64_t(ph) < 0l ? ~0ul : 0ul;
  uint b = uint(row_ptr[i]), e = uint(row_ptr[i + 1u]);
  for (uint k = b; k < e; ++k) {
    mul128(-m[k], x[col[k] * p.count + a], ph, pl);
    add128(s, ph, pl);
  }
  if (p.has_g != 0u) {
    mul128(-g[i], coef[a], ph, pl);
    add128(s, ph, pl);
  }
  int64_t r;
  if (!round192(s, 32u, r)) {
    atomicMin(first_overflow, i);
    y[v] = 0l;
    return;
  }
  y[v] = r;
}
)";

struct Shared {
  std::shared_ptr<Context> ctx;
  std::uint32_t pipeline = 0;
  std::mutex lock;
};

void ok(const Status& st) {
  if (!st.is_ok()) throw std::runtime_error(st.message());
}

template <class T>
std::uint32_t uploaded(Context& ctx, std::span<const T> v) {
  auto id = ctx.buffer_create(std::max<std::size_t>(v.size_bytes(), 8));
  ok(id.status());
  if (!v.empty()) ok(ctx.buffer_write(*id, detail::bytes_of(v), 0));
  return *id;
}

class VulkanRows final : public spectral::BlockRows {
 public:
  VulkanRows(std::shared_ptr<Shared> shared, const SpectralOperator<fx::Q32>& op) : s_(std::move(shared)) {
    const Graph& g = *op.graph;
    rows_ = op.n;
    if (g.col.size() >= 0xffffffffu) throw std::runtime_error("vulkan spectral rows: 2^32 - 1 stored entries at most");
    std::lock_guard<std::mutex> guard(s_->lock);
    Context& ctx = *s_->ctx;
    std::vector<std::int64_t> m(op.m.size()), gv(op.g.size());
    for (std::size_t k = 0; k < m.size(); ++k) m[k] = op.m[k].raw;
    for (std::size_t k = 0; k < gv.size(); ++k) gv[k] = op.g[k].raw;
    has_g_ = !gv.empty();
    try {
      buffers_[0] = uploaded(ctx, std::span<const std::uint64_t>(g.row_ptr));
      buffers_[1] = uploaded(ctx, std::span<const std::uint32_t>(g.col));
      buffers_[2] = uploaded(ctx, std::span<const std::int64_t>(m));
      buffers_[3] = uploaded(ctx, std::span<const std::int64_t>(gv));
    } catch (...) {
      release();  // no destructor runs for a constructor that throws
      throw;
    }
  }
  ~VulkanRows() override {
    std::lock_guard<std::mutex> guard(s_->lock);
    release();
  }
  VulkanRows(const VulkanRows&) = delete;
  VulkanRows& operator=(const VulkanRows&) = delete;

  void apply(const fx::Q32* x, std::span<const std::int64_t> coef, fx::Q32* y, std::size_t count) override {
    run(x, count, coef, y, count);
  }
  // The solver's line-wide blocks (R1-SPEC-074): gathered into the device's compact block and
  // scattered back as the copies to and from the device are made anyway.
  bool apply_strided(const fx::Q32* x, std::size_t ld, std::span<const std::int64_t> coef, fx::Q32* y,
                     std::size_t count) override {
    run(x, ld, coef, y, count);
    return true;
  }

 private:
  void run(const fx::Q32* x, std::size_t ld, std::span<const std::int64_t> coef, fx::Q32* y, std::size_t count) {
    if (count == 0) return;
    if (has_g_ && coef.size() != count) throw std::runtime_error("vulkan spectral rows: one coefficient a column");
    std::lock_guard<std::mutex> guard(s_->lock);
    Context& ctx = *s_->ctx;
    const std::size_t entries = std::size_t{rows_} * count;
    std::vector<std::int64_t> xs(entries);
    for (std::size_t i = 0; i < rows_; ++i)
      for (std::size_t c = 0; c < count; ++c) xs[i * count + c] = x[i * ld + c].raw;
    ok(ctx.buffer_ensure(buffers_[4], entries * 8));
    ok(ctx.buffer_write(buffers_[4], detail::bytes_of(std::span<const std::int64_t>(xs)), 0));
    const std::vector<std::int64_t> cs = has_g_ ? std::vector<std::int64_t>(coef.begin(), coef.end()) : std::vector<std::int64_t>(count, 0);
    ok(ctx.buffer_ensure(buffers_[5], count * 8));
    ok(ctx.buffer_write(buffers_[5], detail::bytes_of(std::span<const std::int64_t>(cs)), 0));
    ok(ctx.buffer_ensure(buffers_[6], entries * 8));
    ok(ctx.buffer_ensure(buffers_[7], 4));
    const std::uint32_t none = 0xffffffffu;
    ok(ctx.buffer_write(buffers_[7], std::span(reinterpret_cast<const std::uint8_t*>(&none), 4), 0));
    const Slot slots[] = {{0, buffers_[0]}, {1, buffers_[1]}, {2, buffers_[2]}, {3, buffers_[3]},
                          {4, buffers_[4]}, {5, buffers_[5]}, {6, buffers_[6]}, {7, buffers_[7]}};
    if (entries >= 0xffffffffu) throw std::runtime_error("vulkan spectral rows: 2^32 - 1 block entries at most");
    const std::array<std::uint32_t, 3> push = {rows_, static_cast<std::uint32_t>(count), has_g_ ? 1u : 0u};
    std::array<std::uint8_t, 12> bytes{};
    std::memcpy(bytes.data(), push.data(), bytes.size());
    ok(ctx.dispatch(s_->pipeline, slots, detail::groups_for(entries), bytes));
    auto flag = ctx.buffer_read(buffers_[7], 0, 4);
    ok(flag.status());
    std::uint32_t first = 0;
    std::memcpy(&first, flag->data(), 4);
    if (first != none)
      throw fx::OverflowError("spectral round (device, row " + std::to_string(first) + ")");
    auto out = ctx.buffer_read(buffers_[6], 0, entries * 8);
    ok(out.status());
    for (std::size_t k = 0; k < entries; ++k) {
      std::int64_t v = 0;
      std::memcpy(&v, out->data() + k * 8, 8);
      y[k / count * ld + k % count] = fx::Q32::from_raw(v);
    }
  }

  void release() {
    for (const std::uint32_t id : buffers_) s_->ctx->buffer_release(id);  // 0 (never made): a no-op
  }
  std::shared_ptr<Shared> s_;
  std::uint32_t rows_ = 0;
  bool has_g_ = false;
  // row_ptr, col, m, g, then the block, the coefficients, the result and the overflow flag.
  std::array<std::uint32_t, 8> buffers_{};
};

}  // namespace

Result<Q32RowsFactory> rows_factory(std::shared_ptr<Context> ctx) {
  auto shared = std::make_shared<Shared>();
  shared->ctx = std::move(ctx);
  R1_ASSIGN(shared->pipeline, shared->ctx->compute_compile(std::string(kVersion) + detail::kWideInt + kRows, "spectral_rows"));
  return Q32RowsFactory([shared](const SpectralOperator<fx::Q32>& op) -> std::unique_ptr<spectral::BlockRows> {
    if (!rows_fit_the_loop_limit(op.graph->row_ptr)) return nullptr;  // declined: the host's rows
    return std::make_unique<VulkanRows>(shared, op);
  });
}

}  // namespace r1::vk
