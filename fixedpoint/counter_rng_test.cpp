// Counter-based randomness: Random123 known answers, order independence, unbiased uniform_below (R1-NUM-060..062).
#include "r1/fixedpoint/counter_rng.hpp"

#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <vector>

namespace {

namespace rng = r1::rng;

// tests/kat_vectors of Random123 (github.com/DEShawResearch/random123), the three
// "philox4x32 10" lines: counter (4 words), key (2 words), expected output (4 words).
struct Kat {
  rng::Ctr ctr;
  rng::Key key;
  rng::Ctr out;
};
constexpr std::array<Kat, 3> kKat = {{
    {{0x00000000, 0x00000000, 0x00000000, 0x00000000}, {0x00000000, 0x00000000}, {0x6627e8d5, 0xe169c58d, 0xbc57ac4c, 0x9b00dbd8}},
    {{0xffffffff, 0xffffffff, 0xffffffff, 0xffffffff}, {0xffffffff, 0xffffffff}, {0x408f276d, 0x41c83b0e, 0xa20bc7c6, 0x6d5451fd}},
    {{0x243f6a88, 0x85a308d3, 0x13198a2e, 0x03707344}, {0xa4093822, 0x299f31d0}, {0xd16cfe09, 0x94fdcceb, 0x5001e420, 0x24126ea1}},
}};

// The generator is constexpr: the known answers hold at compile time too.
static_assert(rng::philox4x32_10(kKat[0].ctr, kKat[0].key) == kKat[0].out);
static_assert(rng::philox4x32_10(kKat[2].ctr, kKat[2].key) == kKat[2].out);

TEST(CounterRng, Random123KnownAnswers) {
  for (const Kat& k : kKat) EXPECT_EQ(rng::philox4x32_10(k.ctr, k.key), k.out);
}

// bits(seed, item, dim) is Philox with counter (item, dim) and key seed, little-endian words,
// returning output words 1:0 (R1-NUM-061): pinned through the third known answer.
TEST(CounterRng, BitsLayout) {
  const std::uint64_t item = 0x85a308d3243f6a88ull, dim = 0x0370734413198a2eull, seed = 0x299f31d0a4093822ull;
  EXPECT_EQ(rng::bits(seed, item, dim), 0x94fdccebd16cfe09ull);
  EXPECT_EQ(rng::bits(0, 0, 0), 0xe169c58d6627e8d5ull);
}

// A pure function of (seed, item, dim): forward, backward, shuffled and parallel evaluation of
// the same grid agree value for value.
TEST(CounterRng, EvaluationOrderDoesNotMatter) {
  constexpr std::uint64_t kSeed = 0x5eed;
  constexpr std::size_t kItems = 512, kDims = 8;
  const auto at = [](std::size_t i, std::size_t d) { return rng::bits(kSeed, i, d); };
  std::vector<std::uint64_t> forward(kItems * kDims), backward(kItems * kDims), shuffled(kItems * kDims),
      parallel(kItems * kDims);
  for (std::size_t k = 0; k < forward.size(); ++k) forward[k] = at(k / kDims, k % kDims);
  for (std::size_t k = forward.size(); k-- > 0;) backward[k] = at(k / kDims, k % kDims);
  std::vector<std::size_t> order(forward.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::shuffle(order.begin(), order.end(), std::mt19937_64(7));
  for (const std::size_t k : order) shuffled[k] = at(k / kDims, k % kDims);
  tbb::parallel_for(std::size_t{0}, parallel.size(), [&](std::size_t k) { parallel[k] = at(k / kDims, k % kDims); });
  EXPECT_EQ(forward, backward);
  EXPECT_EQ(forward, shuffled);
  EXPECT_EQ(forward, parallel);
  // And the values differ from cell to cell (a broken counter layout would repeat them).
  std::vector<std::uint64_t> sorted = forward;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_EQ(std::adjacent_find(sorted.begin(), sorted.end()), sorted.end());
}

// Pearson's chi-square statistic of counts against equal expectation.
double chi_square(const std::vector<long>& counts, long total) {
  const double expect = static_cast<double>(total) / static_cast<double>(counts.size());
  double chi = 0.0;
  for (const long c : counts) chi += (static_cast<double>(c) - expect) * (static_cast<double>(c) - expect) / expect;
  return chi;
}

// For n = 3 * 2^62 the two classic biases are large: plain `bits % n` puts half the mass on
// the first third of the range; multiply-shift without rejection puts half the mass on
// outputs divisible by 3. Both statistics below catch them; the rejection rule removes both.
constexpr std::uint64_t kN = 3ull << 62;
constexpr long kDraws = 30000;
constexpr double kChi2Critical = 18.42;  // chi-square, 2 degrees of freedom, p = 1e-4

struct TwoStats {
  double by_third;  // buckets: which third of [0, n)
  double by_mod3;   // buckets: value mod 3
};

template <class Draw>
TwoStats stats_of(Draw draw) {
  std::vector<long> third(3), mod3(3);
  for (long i = 0; i < kDraws; ++i) {
    const std::uint64_t v = draw(static_cast<std::uint64_t>(i));
    EXPECT_LT(v, kN);
    ++third[v / (1ull << 62)];
    ++mod3[v % 3];
  }
  return {chi_square(third, kDraws), chi_square(mod3, kDraws)};
}

TEST(CounterRng, UniformBelowIsUnbiased) {
  const TwoStats good = stats_of([](std::uint64_t i) { return rng::uniform_below(11, i, 3, kN); });
  EXPECT_LT(good.by_third, kChi2Critical);
  EXPECT_LT(good.by_mod3, kChi2Critical);
  // Negative controls: the same statistics reject the two biased methods, so the test can fail.
  const TwoStats modulo = stats_of([](std::uint64_t i) { return rng::bits(11, i, 3) % kN; });
  EXPECT_GT(modulo.by_third, kChi2Critical);
  const TwoStats no_reject = stats_of([](std::uint64_t i) {
    return static_cast<std::uint64_t>((static_cast<r1::u128>(rng::bits(11, i, 3)) * kN) >> 64);
  });
  EXPECT_GT(no_reject.by_mod3, kChi2Critical);
}

TEST(CounterRng, UniformBelowSmallRangeChiSquare) {
  constexpr std::uint64_t n = 6;
  std::vector<long> counts(n);
  for (long i = 0; i < 60000; ++i) ++counts[rng::uniform_below(5, static_cast<std::uint64_t>(i), 0, n)];
  EXPECT_LT(chi_square(counts, 60000), 25.74);  // 5 degrees of freedom, p = 1e-4
  EXPECT_EQ(rng::uniform_below(1, 2, 3, 1), 0u);
}

// The rejection rule of R1-NUM-062: a rejected draw retries at dim + k 2^56.
TEST(CounterRng, RejectedDrawRetriesAtShiftedDimension) {
  int rejected = 0;
  for (std::uint64_t item = 0; item < 200; ++item) {
    const std::uint64_t threshold = (0 - kN) % kN;
    const r1::u128 m0 = static_cast<r1::u128>(rng::bits(1, item, 5)) * kN;
    if (static_cast<std::uint64_t>(m0) >= threshold) {
      EXPECT_EQ(rng::uniform_below(1, item, 5, kN), static_cast<std::uint64_t>(m0 >> 64));
      continue;
    }
    ++rejected;
    const r1::u128 m1 = static_cast<r1::u128>(rng::bits(1, item, 5 + rng::kDimLimit)) * kN;
    if (static_cast<std::uint64_t>(m1) >= threshold) {
      EXPECT_EQ(rng::uniform_below(1, item, 5, kN), static_cast<std::uint64_t>(m1 >> 64));
    }
  }
  EXPECT_GT(rejected, 20);  // about a quarter of the draws are rejected for this n
}

TEST(CounterRng, UniformQ32AndDouble) {
  for (std::uint64_t i = 0; i < 1000; ++i) {
    const std::int64_t q = rng::uniform_q32(9, i, 1);
    EXPECT_GE(q, 0);
    EXPECT_LT(q, std::int64_t{1} << 32);
    EXPECT_EQ(static_cast<std::uint64_t>(q), rng::bits(9, i, 1) >> 32);
    const double d = rng::uniform_double(9, i, 1);
    EXPECT_GE(d, 0.0);
    EXPECT_LT(d, 1.0);
    EXPECT_EQ(std::ldexp(d, 53), std::floor(std::ldexp(d, 53)));  // a multiple of 2^-53
  }
}

}  // namespace
