// The exact Q32 sparse product on a Vulkan device (R1-BKD-064): 128-bit row sums in two 64-bit
// limbs, rounded once, ties to even, the bits of the host's i128 arithmetic.
#include <cstring>
#include <string>
#include <utility>

#include "r1/accel/vulkan.hpp"
#include "shader_common.hpp"

namespace r1::vk {

namespace {

constexpr const char* kVersion = "#version 460\n#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require\n";

// One invocation a row (kWideInt's mul128 for each product). The signed 128-bit sum in (hi, lo),
// two's complement; the result floor(sum / 2^32) plus the round-half-even of the remainder, as
// fx::detail::rne_shift does.
constexpr const char* kSpmv = R"(
layout(std430, binding = 0) readonly buffer R { uint64_t row_ptr[]; };
layout(std430, binding = 1) readonly buffer C { uint col[]; };
layout(std430, binding = 2) readonly buffer V { int64_t val[]; };
layout(std430, binding = 3) readonly buffer X { int64_t x[]; };
layout(std430, binding = 4) writeonly buffer Y { int64_t y[]; };
layout(std430, binding = 5) buffer F { uint first_overflow; };
layout(push_constant) uniform P { uint rows; uint identity; } p;

void main() {
  uint i = invocation();
  if (i >= p.rows) return;
  uint b = uint(row_ptr[i]), e = uint(row_ptr[i + 1u]);
  if (b == e && p.identity != 0u) {
    y[i] = x[i];
    return;
  }
  uint64_t hi = 0ul, lo = 0ul;
  for (uint k = b; k < e; ++k) {
    uint64_t ph, pl;
    mul128(val[k], x[col[k]], ph, pl);
    uint64_t sum = lo + pl;
    hi += ph + (sum < lo ? 1ul : 0ul);
    lo = sum;
  }
  uint64_t qlo = (lo >> 32) | (hi << 32);
  int64_t qhi = int64_t(hi) >> 32;
  uint64_t rem = lo & 0xfffffffful;
  if (rem > 0x80000000ul || (rem == 0x80000000ul && (qlo & 1ul) != 0ul)) {
    qlo += 1ul;
    if (qlo == 0ul) qhi += 1l;
  }
  if (qhi != (int64_t(qlo) >> 63)) {
    atomicMin(first_overflow, i);
    y[i] = 0l;
    return;
  }
  y[i] = int64_t(qlo);
}
)";

}  // namespace

ExactSpmv& ExactSpmv::operator=(ExactSpmv&& o) noexcept {
  if (this == &o) return *this;
  this->~ExactSpmv();
  ctx_ = std::exchange(o.ctx_, nullptr);
  rows_ = o.rows_;
  columns_ = o.columns_;
  identity_ = o.identity_;
  pipeline_ = o.pipeline_;
  row_ptr_ = o.row_ptr_;
  col_ = o.col_;
  val_ = o.val_;
  x_ = o.x_;
  y_ = o.y_;
  flag_ = o.flag_;
  return *this;
}

ExactSpmv::~ExactSpmv() {
  if (ctx_ == nullptr) return;
  for (const std::uint32_t id : {row_ptr_, col_, val_, x_, y_, flag_}) ctx_->buffer_release(id);  // 0 (never made): a no-op
  ctx_ = nullptr;
}

Result<ExactSpmv> ExactSpmv::build(Context& ctx, std::span<const std::uint64_t> row_ptr, std::span<const std::uint32_t> col,
                                   std::span<const std::int64_t> val, bool empty_rows_identity) {
  if (row_ptr.empty() || row_ptr.front() != 0 || row_ptr.back() != col.size() || col.size() != val.size())
    return Status::input("vulkan spmv: row pointers, columns and values do not describe one CSR matrix");
  const std::size_t rows = row_ptr.size() - 1;
  if (rows >= 0xffffffffu || col.size() >= 0xffffffffu)
    return Status::input("vulkan spmv: " + std::to_string(rows) + " rows and " + std::to_string(col.size()) + " entries: 2^32 - 1 of each at most");
  for (std::size_t i = 0; i < rows; ++i)
    if (row_ptr[i] > row_ptr[i + 1]) return Status::input("vulkan spmv: row pointer " + std::to_string(i) + " decreases");
  std::uint32_t columns = 0;
  for (const std::uint32_t c : col) columns = std::max(columns, c + 1);
  ExactSpmv m;
  m.ctx_ = &ctx;
  m.rows_ = static_cast<std::uint32_t>(rows);
  m.columns_ = std::max<std::uint32_t>(columns, empty_rows_identity ? m.rows_ : 0);
  m.identity_ = empty_rows_identity;
  R1_ASSIGN(m.pipeline_, ctx.compute_compile(std::string(kVersion) + detail::kWideInt + kSpmv, "exact_spmv"));
  R1_ASSIGN(m.row_ptr_, ctx.buffer_create(row_ptr.size_bytes()));
  R1_ASSIGN(m.col_, ctx.buffer_create(col.size_bytes()));
  R1_ASSIGN(m.val_, ctx.buffer_create(val.size_bytes()));
  R1_ASSIGN(m.x_, ctx.buffer_create(std::size_t{m.columns_} * 8));
  R1_ASSIGN(m.y_, ctx.buffer_create(std::size_t{m.rows_} * 8));
  R1_ASSIGN(m.flag_, ctx.buffer_create(4));
  R1_TRY(ctx.buffer_write(m.row_ptr_, detail::bytes_of(row_ptr), 0));
  R1_TRY(ctx.buffer_write(m.col_, detail::bytes_of(col), 0));
  R1_TRY(ctx.buffer_write(m.val_, detail::bytes_of(val), 0));
  return m;
}

Result<std::vector<std::int64_t>> ExactSpmv::apply(std::span<const std::int64_t> x) {
  if (x.size() != columns_)
    return Status::input("vulkan spmv: x has " + std::to_string(x.size()) + " entries for " + std::to_string(columns_) + " columns");
  R1_TRY(ctx_->buffer_write(x_, detail::bytes_of(x), 0));
  const std::uint32_t none = 0xffffffffu;
  R1_TRY(ctx_->buffer_write(flag_, std::span(reinterpret_cast<const std::uint8_t*>(&none), 4), 0));
  const Slot slots[] = {{0, row_ptr_}, {1, col_}, {2, val_}, {3, x_}, {4, y_}, {5, flag_}};
  std::uint32_t push[2] = {rows_, identity_ ? 1u : 0u};
  std::uint8_t push_bytes[8];
  std::memcpy(push_bytes, push, 8);
  R1_TRY(ctx_->dispatch(pipeline_, slots, detail::groups_for(rows_), push_bytes));
  R1_ASSIGN(const auto flag, ctx_->buffer_read(flag_, 0, 4));
  std::uint32_t first = 0;
  std::memcpy(&first, flag.data(), 4);
  if (first != none) return Status::internal("vulkan spmv: row " + std::to_string(first) + " rounds outside the Q32 range");
  R1_ASSIGN(const auto y, ctx_->buffer_read(y_, 0, std::size_t{rows_} * 8));
  std::vector<std::int64_t> out(rows_);
  std::memcpy(out.data(), y.data(), y.size());
  return out;
}

}  // namespace r1::vk
