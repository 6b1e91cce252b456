// The exact Q32 sparse product on the Vulkan device (R1-BKD-064) against the host's i128 sums and
// fx::detail::rne_shift, bit for bit: random rows of every length up to 40 with entries across
// the int64 range, rows built to land on exact ties of both signs, empty rows, and the overflow
// report. Skips without a device unless R1_REQUIRE_VULKAN is set (make test sets it).
#include <gtest/gtest.h>

#include <cstdlib>
#include <optional>
#include <vector>

#include "device_test_support.hpp"
#include "r1/accel/vulkan.hpp"
#include "r1/fixedpoint/counter_rng.hpp"
#include "r1/fixedpoint/q32.hpp"

namespace {

using r1::i128;

struct Csr {
  std::vector<std::uint64_t> row_ptr{0};
  std::vector<std::uint32_t> col;
  std::vector<std::int64_t> val;
  void row(const std::vector<std::pair<std::uint32_t, std::int64_t>>& entries) {
    for (const auto& [c, v] : entries) {
      col.push_back(c);
      val.push_back(v);
    }
    row_ptr.push_back(col.size());
  }
};

// The host's answer: the exact sum, rounded once, or nothing when it leaves int64.
std::vector<std::optional<std::int64_t>> host(const Csr& a, const std::vector<std::int64_t>& x, bool identity) {
  std::vector<std::optional<std::int64_t>> y;
  for (std::size_t i = 0; i + 1 < a.row_ptr.size(); ++i) {
    if (identity && a.row_ptr[i] == a.row_ptr[i + 1]) {
      y.push_back(x[i]);
      continue;
    }
    i128 acc = 0;
    for (std::uint64_t k = a.row_ptr[i]; k < a.row_ptr[i + 1]; ++k) acc += static_cast<i128>(a.val[k]) * x[a.col[k]];
    const i128 r = r1::fx::detail::rne_shift(acc, 32);
    y.push_back(r1::fx::detail::fits_i64(r) ? std::optional<std::int64_t>(static_cast<std::int64_t>(r)) : std::nullopt);
  }
  return y;
}

// A draw in [-2^bits, 2^bits) from the counter RNG.
std::int64_t draw(std::uint64_t counter, std::uint64_t dim, int bits) {
  const std::uint64_t u = r1::rng::bits(99, counter, dim);
  return static_cast<std::int64_t>(u >> (63 - bits)) - (std::int64_t{1} << bits);
}

TEST(VulkanExactSpmv, RowSumsRoundLikeTheHostsI128BitForBit) {
  R1_NEED_DEVICE(ctx);
  RecordProperty("device", ctx->info().name);
  const std::uint32_t n = 2000;
  Csr a;
  std::uint64_t counter = 0;
  for (std::uint32_t i = 0; i < n; ++i) {
    std::vector<std::pair<std::uint32_t, std::int64_t>> entries;
    const auto len = static_cast<std::uint32_t>(r1::rng::bits(99, i, 7) % 41);
    // Magnitudes from a few bits to 2^45 for the matrix and 2^40 for x: products up to 2^85 (both
    // limbs of the 128-bit sum in use), results within int64.
    const int bits = 2 + static_cast<int>(r1::rng::bits(99, i, 8) % 44);
    for (std::uint32_t k = 0; k < len; ++k, ++counter)
      entries.push_back({static_cast<std::uint32_t>(r1::rng::bits(99, counter, 1) % n), draw(counter, 2, bits)});
    a.row(entries);
  }
  std::vector<std::int64_t> x(n);
  for (std::uint32_t j = 0; j < n; ++j) x[j] = draw(j, 3, 40);
  // Exact ties: 2^31 x_j with x_j = 1, 3, -1, -3 and a sum of 5 * 2^31.
  x[0] = 1;
  x[1] = 3;
  x[2] = -1;
  x[3] = -3;
  const std::int64_t half = std::int64_t{1} << 31;
  a.row({{0, half}});
  a.row({{1, half}});
  a.row({{2, half}});
  a.row({{3, half}});
  a.row({{0, half}, {1, half}, {0, half}});
  a.row({{3, -half}, {3, -half}});
  const std::uint32_t rows = static_cast<std::uint32_t>(a.row_ptr.size() - 1);
  x.resize(std::max<std::size_t>(x.size(), rows), 5);
  for (const bool identity : {false, true}) {
    auto m = r1::vk::ExactSpmv::build(*ctx, a.row_ptr, a.col, a.val, identity);
    ASSERT_TRUE(m.is_ok()) << m.status().message();
    std::vector<std::int64_t> xs(x.begin(), x.begin() + m->columns());
    auto y = m->apply(xs);
    ASSERT_TRUE(y.is_ok()) << y.status().message();
    const auto want = host(a, xs, identity);
    ASSERT_EQ(y->size(), want.size());
    std::size_t empty = 0;
    for (std::size_t i = 0; i < want.size(); ++i) {
      ASSERT_TRUE(want[i].has_value()) << "row " << i;
      ASSERT_EQ((*y)[i], *want[i]) << "row " << i << (identity ? " (identity)" : "");
      empty += a.row_ptr[i] == a.row_ptr[i + 1];
    }
    EXPECT_GT(empty, 10u);  // both conventions for empty rows were exercised
    // The ties: 0.5 -> 0, 1.5 -> 2, -0.5 -> 0, -1.5 -> -2, 2.5 -> 2, 3 -> 3.
    const std::vector<std::int64_t> ties(y->end() - 6, y->end());
    EXPECT_EQ(ties, (std::vector<std::int64_t>{0, 2, 0, -2, 2, 3}));
  }
}

TEST(VulkanExactSpmv, OverflowAndBadInputAreErrors) {
  R1_NEED_DEVICE(ctx);
  Csr a;
  a.row({{0, 1}});
  a.row({{0, std::int64_t{1} << 62}, {1, std::int64_t{1} << 62}});  // 2^125 / 2^32 leaves int64
  auto m = r1::vk::ExactSpmv::build(*ctx, a.row_ptr, a.col, a.val, false);
  ASSERT_TRUE(m.is_ok());
  auto y = m->apply(std::vector<std::int64_t>{std::int64_t{1} << 62, std::int64_t{1} << 62});
  ASSERT_FALSE(y.is_ok());
  EXPECT_NE(y.status().message().find("row 1 rounds outside the Q32 range"), std::string::npos) << y.status().message();
  EXPECT_FALSE(m->apply(std::vector<std::int64_t>{1}).is_ok());  // x of the wrong length
  const std::vector<std::uint64_t> bad_ptr{0, 2, 1, 3};
  const auto bad = r1::vk::ExactSpmv::build(*ctx, bad_ptr, a.col, a.val, false);
  ASSERT_FALSE(bad.is_ok());
  EXPECT_NE(bad.status().message().find("row pointer 1 decreases"), std::string::npos) << bad.status().message();
}

}  // namespace
