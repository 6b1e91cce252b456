// The splats' depth sort on a Vulkan device (R1-BKD-072): a stable least-significant-digit radix
// sort of the depths' bit patterns (positive doubles order as their bits do), eight bits a pass.
// Each pass: per 256-key block a digit histogram; an exclusive scan of the histograms, digit
// major, so every (digit, block) learns where its keys go; a scatter that walks each block in
// order, which keeps equal digits in input order. So equal depths stay in index order.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <numeric>
#include <string>
#include <utility>

#include "r1/accel/vulkan.hpp"
#include "shader_common.hpp"

namespace r1::vk {

namespace {

constexpr const char* kVersion = "#version 460\n#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require\n";
constexpr std::uint32_t kBlock = 256;  // keys per histogram and scatter invocation

// One workgroup a block of 256 keys; its 64 invocations own four digits each, so each digit's
// keys are counted and placed by one invocation walking the block in order (stable).
constexpr const char* kPush = R"(
layout(local_size_x = 64) in;
layout(push_constant) uniform P { uint n; uint blocks; uint shift; } p;
const uint kBlock = 256u;
uint block_id() { return gl_WorkGroupID.x + gl_WorkGroupID.y * gl_NumWorkGroups.x; }
)";

constexpr const char* kHistogram = R"(
layout(std430, binding = 0) readonly buffer K { uint64_t key[]; };
layout(std430, binding = 2) writeonly buffer H { uint counts[]; };
void main() {
  uint b = block_id();
  if (b >= p.blocks) return;
  uint d0 = gl_LocalInvocationID.x * 4u;
  uint c[4] = uint[4](0u, 0u, 0u, 0u);
  uint lo = b * kBlock, hi = min(p.n, lo + kBlock);
  for (uint e = lo; e < hi; ++e) {
    uint d = (uint(key[e] >> p.shift) & 255u) - d0;
    if (d < 4u) c[d] += 1u;
  }
  for (uint j = 0u; j < 4u; ++j) counts[(d0 + j) * p.blocks + b] = c[j];
}
)";

// The exclusive scan of the histograms, digit major, in two dispatches of 256 invocations, one a
// digit: first each digit's counts over the blocks, scanned within the digit, and the digit's
// total; then each digit adds the totals of the digits below it. No invocation loops more than
// `blocks` times in one loop nest: llvmpipe (lavapipe) stops a loop nest after 65535 iterations,
// so the keys are capped at kMaxKeys (32768 blocks).
constexpr const char* kScanDigits = R"(
layout(std430, binding = 2) buffer H { uint counts[]; };
layout(std430, binding = 5) buffer T { uint totals[]; };
void main() {
  uint d = block_id() * 64u + gl_LocalInvocationID.x;
  if (d >= 256u) return;
  uint sum = 0u, base = d * p.blocks;
  for (uint b = 0u; b < p.blocks; ++b) {
    uint c = counts[base + b];
    counts[base + b] = sum;
    sum += c;
  }
  totals[d] = sum;
}
)";

constexpr const char* kScanBases = R"(
layout(std430, binding = 2) buffer H { uint counts[]; };
layout(std430, binding = 5) readonly buffer T { uint totals[]; };
void main() {
  uint d = block_id() * 64u + gl_LocalInvocationID.x;
  if (d >= 256u) return;
  uint below = 0u;
  for (uint e = 0u; e < d; ++e) below += totals[e];
  uint base = d * p.blocks;
  for (uint b = 0u; b < p.blocks; ++b) counts[base + b] += below;
}
)";

constexpr const char* kScatter = R"(
layout(std430, binding = 0) readonly buffer K { uint64_t key[]; };
layout(std430, binding = 1) readonly buffer I { uint idx[]; };
layout(std430, binding = 2) readonly buffer H { uint counts[]; };
layout(std430, binding = 3) writeonly buffer KO { uint64_t key_out[]; };
layout(std430, binding = 4) writeonly buffer IO { uint idx_out[]; };
void main() {
  uint b = block_id();
  if (b >= p.blocks) return;
  uint d0 = gl_LocalInvocationID.x * 4u;
  uint next[4];
  for (uint j = 0u; j < 4u; ++j) next[j] = counts[(d0 + j) * p.blocks + b];
  uint lo = b * kBlock, hi = min(p.n, lo + kBlock);
  for (uint e = lo; e < hi; ++e) {
    uint64_t k = key[e];
    uint d = (uint(k >> p.shift) & 255u) - d0;
    if (d >= 4u) continue;
    uint dst = next[d];
    next[d] = dst + 1u;
    key_out[dst] = k;
    idx_out[dst] = idx[e];
  }
}
)";

std::string source(const char* body) { return std::string(kVersion) + kPush + body; }

}  // namespace

DepthSort& DepthSort::operator=(DepthSort&& o) noexcept {
  if (this == &o) return *this;
  this->~DepthSort();
  ctx_ = std::exchange(o.ctx_, nullptr);
  histogram_ = o.histogram_;
  scan_digits_ = o.scan_digits_;
  scan_bases_ = o.scan_bases_;
  scatter_ = o.scatter_;
  buffers_ = o.buffers_;
  return *this;
}

DepthSort::~DepthSort() {
  if (ctx_ == nullptr) return;
  for (const std::uint32_t id : buffers_) ctx_->buffer_release(id);  // 0 (never made): a no-op
  ctx_ = nullptr;
}

Result<DepthSort> DepthSort::build(Context& ctx) {
  DepthSort s;
  s.ctx_ = &ctx;
  R1_ASSIGN(s.histogram_, ctx.compute_compile(source(kHistogram), "depth_sort_histogram"));
  R1_ASSIGN(s.scan_digits_, ctx.compute_compile(source(kScanDigits), "depth_sort_scan_digits"));
  R1_ASSIGN(s.scan_bases_, ctx.compute_compile(source(kScanBases), "depth_sort_scan_bases"));
  R1_ASSIGN(s.scatter_, ctx.compute_compile(source(kScatter), "depth_sort_scatter"));
  return s;
}

Result<std::vector<std::uint32_t>> DepthSort::order(std::span<const double> depth) {
  const std::size_t n = depth.size();
  if (n > kMaxKeys) return Status::input("depth sort: " + std::to_string(n) + " keys, " + std::to_string(kMaxKeys) + " at most");
  std::vector<std::uint64_t> keys(n);
  std::uint64_t all = ~std::uint64_t{0}, any = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!(depth[i] > 0) || !std::isfinite(depth[i]))
      return Status::input("depth sort: depth " + std::to_string(i) + " is not a positive finite number");
    keys[i] = std::bit_cast<std::uint64_t>(depth[i]);
    all &= keys[i];
    any |= keys[i];
  }
  std::vector<std::uint32_t> idx(n);
  std::iota(idx.begin(), idx.end(), 0u);
  if (n < 2) return idx;
  Context& ctx = *ctx_;
  const auto blocks = static_cast<std::uint32_t>((n + kBlock - 1) / kBlock);
  // keys in, indices in, counts, keys out, indices out, digit totals.
  auto& [key_in, idx_in, counts, key_out, idx_out, totals] = buffers_;
  R1_TRY(ctx.buffer_ensure(key_in, n * 8));
  R1_TRY(ctx.buffer_ensure(key_out, n * 8));
  R1_TRY(ctx.buffer_ensure(idx_in, n * 4));
  R1_TRY(ctx.buffer_ensure(idx_out, n * 4));
  R1_TRY(ctx.buffer_ensure(counts, std::size_t{blocks} * 256 * 4));
  R1_TRY(ctx.buffer_ensure(totals, 256 * 4));
  R1_TRY(ctx.buffer_write(key_in, detail::bytes_of(std::span<const std::uint64_t>(keys)), 0));
  R1_TRY(ctx.buffer_write(idx_in, detail::bytes_of(std::span<const std::uint32_t>(idx)), 0));
  const std::uint64_t varying = all ^ any;  // the bits not every key shares
  const auto groups = detail::groups_for(std::uint64_t{blocks} * 64);  // a workgroup a block
  for (std::uint32_t shift = 0; shift < 64; shift += 8) {
    if (((varying >> shift) & 0xff) == 0) continue;
    const std::array<std::uint32_t, 3> push = {static_cast<std::uint32_t>(n), blocks, shift};
    std::array<std::uint8_t, 12> bytes{};
    std::memcpy(bytes.data(), push.data(), bytes.size());
    const Slot hist[] = {{0, key_in}, {2, counts}};
    R1_TRY(ctx.dispatch(histogram_, hist, groups, bytes));
    const Slot scan[] = {{2, counts}, {5, totals}};
    R1_TRY(ctx.dispatch(scan_digits_, scan, {4, 1, 1}, bytes));  // 256 invocations, a digit each
    R1_TRY(ctx.dispatch(scan_bases_, scan, {4, 1, 1}, bytes));
    const Slot scatter[] = {{0, key_in}, {1, idx_in}, {2, counts}, {3, key_out}, {4, idx_out}};
    R1_TRY(ctx.dispatch(scatter_, scatter, groups, bytes));
    std::swap(key_in, key_out);
    std::swap(idx_in, idx_out);
  }
  R1_ASSIGN(const auto out, ctx.buffer_read(idx_in, 0, n * 4));
  std::memcpy(idx.data(), out.data(), n * 4);
  return idx;
}

}  // namespace r1::vk
