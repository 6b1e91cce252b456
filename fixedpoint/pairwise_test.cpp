// The fp64 pairwise tree: fast path vs the literal definition, parallel vs serial, error bound (R1-NUM-050..054).
#include "r1/fixedpoint/pairwise.hpp"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>
#include <tbb/info.h>
#include <tbb/task_arena.h>

#include <bit>
#include <boost/multiprecision/cpp_bin_float.hpp>
#include <cmath>
#include <random>
#include <vector>

namespace {

namespace fx = r1::fx;
using Exact = boost::multiprecision::cpp_bin_float_100;

// 1, 2 and 4 threads, capped at what the machine offers (TBB warns about arenas beyond it).
std::vector<int> thread_counts() {
  std::vector<int> t = {1};
  for (const int n : {2, 4}) {
    if (n <= std::max(2, tbb::info::default_concurrency())) t.push_back(n);
  }
  return t;
}

std::uint64_t bits_of(double d) { return std::bit_cast<std::uint64_t>(d); }

// Values whose sum depends on the order of additions: mixed signs, magnitudes 2^-40..2^40.
std::vector<double> mixed(std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<double> v(n);
  for (double& x : v) {
    const double m = static_cast<double>(rng() >> 11) * 0x1p-53;  // [0, 1), 53 random bits
    x = std::ldexp(m, static_cast<int>(rng() % 81) - 40) * ((rng() & 1) ? 1.0 : -1.0);
  }
  return v;
}

double sequential(const std::vector<double>& v) {
  double s = 0.0;
  for (const double x : v) s += x;
  return s;
}

TEST(Pairwise, PinnedSmallTreesDifferFromSequential) {
  // n = 4: (2^53 + 1) + (1 - 2^53) = 2^53 + (1 - 2^53) = 1, where left to right gives 0.
  const std::vector<double> v = {0x1p53, 1.0, 1.0, -0x1p53};
  EXPECT_EQ(fx::pairwise_sum(v), 1.0);
  EXPECT_EQ(sequential(v), 0.0);
  // n = 3 splits at 2: (a + b) + c.
  const std::vector<double> w = {1.0, 0x1p53, -0x1p53};
  EXPECT_EQ(fx::pairwise_sum(w), 0.0);  // 1 + 2^53 rounds to 2^53 (tie to even)
  EXPECT_EQ(fx::pairwise_sum(std::vector<double>{}), 0.0);
  EXPECT_FALSE(std::signbit(fx::pairwise_sum(std::vector<double>{})));
  EXPECT_TRUE(std::signbit(fx::pairwise_sum(std::vector<double>{-0.0})));
  EXPECT_EQ(fx::pairwise_sum(std::vector<double>{2.5}), 2.5);
}

// The blocked fast path is the tree of the definition, bit for bit, for every length up to
// 600 (all block/tail combinations of the first ten blocks) and some long ones.
TEST(Pairwise, FastPathEqualsLiteralRecursion) {
  std::vector<std::size_t> lengths;
  for (std::size_t n = 0; n <= 600; ++n) lengths.push_back(n);
  for (const std::size_t n : {1023, 1024, 1025, 4096 + 63, 65536, 100003}) lengths.push_back(n);
  for (const std::size_t n : lengths) {
    const auto v = mixed(n, n);
    const auto b = mixed(n, n + 7777);
    ASSERT_EQ(bits_of(fx::pairwise_sum(v)), bits_of(fx::pairwise_sum_recursive(v))) << n;
    std::vector<double> prod(n);
    for (std::size_t i = 0; i < n; ++i) prod[i] = v[i] * b[i];
    ASSERT_EQ(bits_of(fx::pairwise_dot(v, b)), bits_of(fx::pairwise_sum_recursive(prod))) << n;
  }
}

// The test has power: on such data a different tree (left to right) gives other bits.
TEST(Pairwise, OrderMattersForTheTestData) {
  int differ = 0;
  for (std::size_t n = 100; n < 110; ++n) {
    const auto v = mixed(n, n);
    differ += bits_of(fx::pairwise_sum(v)) != bits_of(sequential(v));
  }
  EXPECT_GE(differ, 5);
}

// Parallel evaluation is bit-identical for every grain and thread count.
TEST(Pairwise, ParallelMatchesSerialForAllGrainsAndThreads) {
  for (const std::size_t n : {0, 1, 2, 3, 63, 64, 65, 1000, 100000, 300001}) {
    const auto v = mixed(n, 3 * n + 1);
    const auto b = mixed(n, 5 * n + 2);
    const double sum = fx::pairwise_sum(v), dot = fx::pairwise_dot(v, b), norm = fx::pairwise_norm2(v);
    for (const int threads : thread_counts()) {
      tbb::task_arena arena(threads);
      for (const std::size_t grain : {std::size_t{0}, std::size_t{1}, std::size_t{3}, std::size_t{64},
                                      std::size_t{1000}, fx::kPairwiseDefaultGrain}) {
        if (n > 1000 && grain < 64) continue;  // millions of one-leaf tasks: slow and adds nothing
        arena.execute([&] {
          ASSERT_EQ(bits_of(fx::parallel_pairwise_sum(v, grain)), bits_of(sum)) << n << " " << threads << " " << grain;
          ASSERT_EQ(bits_of(fx::parallel_pairwise_dot(v, b, grain)), bits_of(dot)) << n << " " << grain;
          ASSERT_EQ(bits_of(fx::parallel_pairwise_norm2(v, grain)), bits_of(norm)) << n << " " << grain;
        });
      }
    }
  }
}

RC_GTEST_PROP(Pairwise, FastEqualsRecursionAndParallel, ()) {
  const auto v = *rc::gen::container<std::vector<double>>(
      rc::gen::map(rc::gen::pair(rc::gen::arbitrary<std::int32_t>(), rc::gen::inRange(-60, 60)),
                   [](std::pair<std::int32_t, int> p) { return std::ldexp(static_cast<double>(p.first), p.second); }));
  const std::size_t grain = *rc::gen::inRange<std::size_t>(1, 200);
  const double s = fx::pairwise_sum(v);
  RC_ASSERT(bits_of(s) == bits_of(fx::pairwise_sum_recursive(v)));
  RC_ASSERT(bits_of(s) == bits_of(fx::parallel_pairwise_sum(v, grain)));
}

// |S - exact| <= ceil(log2 n) u sum|x| (1 + small): the bound of a depth-ceil(log2 n) tree.
TEST(Pairwise, ErrorWithinTreeBound) {
  for (const std::size_t n : {2, 10, 1000, 65536, 100000}) {
    const auto v = mixed(n, 11 * n);
    Exact exact = 0, abs_sum = 0;  // exact: magnitudes span < 2^134, well within 332 bits
    for (const double x : v) {
      exact += x;
      abs_sum += std::fabs(x);
    }
    const double depth = std::ceil(std::log2(static_cast<double>(n)));
    const Exact bound = Exact(depth) * Exact(0x1p-53) * abs_sum * Exact(1.0 + 1e-10);
    EXPECT_LE(abs(Exact(fx::pairwise_sum(v)) - exact), bound) << n;
  }
}

TEST(Pairwise, DotAndNorm) {
  const std::vector<double> a = {3.0, 4.0};
  EXPECT_EQ(fx::pairwise_norm2(a), 5.0);
  EXPECT_EQ(fx::pairwise_dot(a, std::vector<double>{2.0, 0.5}), 8.0);
  EXPECT_THROW(fx::pairwise_dot(a, std::vector<double>{1.0}), std::invalid_argument);
  EXPECT_THROW(fx::parallel_pairwise_dot(a, std::vector<double>{1.0}), std::invalid_argument);
  EXPECT_TRUE(std::isinf(fx::pairwise_norm2(std::vector<double>{1e200, 1e200})));  // no rescaling
}

}  // namespace
