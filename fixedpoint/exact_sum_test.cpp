// ExactSum against a cpp_int sum rounded once; order independence; the width bound (R1-NUM-030..034).
#include "r1/fixedpoint/exact_sum.hpp"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>
#include <tbb/info.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <boost/multiprecision/cpp_int.hpp>
#include <numeric>
#include <random>
#include <vector>

namespace {

using boost::multiprecision::cpp_int;
using r1::fx::ExactSum;
using r1::fx::Q32;

// 1, 2 and 4 threads, capped at what the machine offers (TBB warns about arenas beyond it).
std::vector<int> thread_counts() {
  std::vector<int> t = {1};
  for (const int n : {2, 4}) {
    if (n <= std::max(2, tbb::info::default_concurrency())) t.push_back(n);
  }
  return t;
}

// The signed value of the 192-bit two's complement limbs.
cpp_int value_of(const ExactSum& s) {
  const auto l = s.limbs();
  cpp_int v = (cpp_int(l[2]) << 128) | (cpp_int(l[1]) << 64) | cpp_int(l[0]);
  if ((l[2] >> 63) != 0) v -= cpp_int(1) << 192;
  return v;
}

// Nearest integer to v / 2^32, ties to even (floor division plus remainder, as in q32_test).
cpp_int ref_round(const cpp_int& v) {
  const cpp_int d = cpp_int(1) << 32;
  cpp_int q = v / d;
  cpp_int r = v - q * d;
  if (r < 0) {
    q -= 1;
    r += d;
  }
  if (2 * r > d || (2 * r == d && (q & 1) != 0)) q += 1;
  return q;
}

bool in_range(const cpp_int& r) { return r >= cpp_int(INT64_MIN) && r <= cpp_int(INT64_MAX); }

rc::Gen<std::int64_t> any_raw() {
  return rc::gen::oneOf(rc::gen::resize(100, rc::gen::arbitrary<std::int64_t>()),
                        rc::gen::elementOf(std::vector<std::int64_t>{INT64_MIN, INT64_MAX, INT64_MIN + 1, 0, 1, -1,
                                                                     std::int64_t{1} << 32, std::int64_t{1} << 31}),
                        rc::gen::map(rc::gen::arbitrary<std::int32_t>(), [](std::int32_t x) { return std::int64_t{x}; }));
}

struct Term {
  int kind;  // 0 add_product, 1 sub_product, 2 add, 3 sub
  std::int64_t a, b;
};

rc::Gen<std::vector<Term>> any_terms() {
  return rc::gen::container<std::vector<Term>>(
      rc::gen::map(rc::gen::tuple(rc::gen::inRange(0, 4), any_raw(), any_raw()),
                   [](const std::tuple<int, std::int64_t, std::int64_t>& t) {
                     return Term{std::get<0>(t), std::get<1>(t), std::get<2>(t)};
                   }));
}

void apply(ExactSum& s, const Term& t) {
  switch (t.kind) {
    case 0: s.add_product(Q32{t.a}, Q32{t.b}); break;
    case 1: s.sub_product(Q32{t.a}, Q32{t.b}); break;
    case 2: s.add(Q32{t.a}); break;
    default: s.sub(Q32{t.a}); break;
  }
}

cpp_int exact_term(const Term& t) {
  switch (t.kind) {
    case 0: return cpp_int(t.a) * t.b;
    case 1: return -cpp_int(t.a) * t.b;
    case 2: return cpp_int(t.a) << 32;
    default: return -(cpp_int(t.a) << 32);
  }
}

RC_GTEST_PROP(ExactSum, EqualsCppIntSumRoundedOnce, ()) {
  const auto terms = *any_terms();
  ExactSum s;
  cpp_int ref = 0;
  for (const Term& t : terms) {
    apply(s, t);
    ref += exact_term(t);
  }
  RC_ASSERT(value_of(s) == ref);
  RC_ASSERT(s.signum() == (ref > 0) - (ref < 0));
  const cpp_int rounded = ref_round(ref);
  const auto r = s.checked_round();
  if (in_range(rounded)) {
    RC_ASSERT(r.has_value());
    RC_ASSERT(cpp_int(r->raw) == rounded);
  } else {
    RC_ASSERT(!r.has_value());
    RC_ASSERT_THROWS_AS(s.round(), r1::fx::OverflowError);
  }
}

// Shuffled, cut into random chunks, each chunk summed separately, the partial sums merged in a
// random order: the limbs are identical (R1-NUM-032).
RC_GTEST_PROP(ExactSum, ShuffledAndMergedPartialSumsAreIdentical, ()) {
  const auto terms = *any_terms();
  ExactSum whole;
  for (const Term& t : terms) apply(whole, t);
  auto shuffled = terms;
  std::mt19937_64 rng(*rc::gen::arbitrary<std::uint64_t>());
  std::shuffle(shuffled.begin(), shuffled.end(), rng);
  std::vector<ExactSum> parts(1 + rng() % 8);
  for (const Term& t : shuffled) apply(parts[rng() % parts.size()], t);
  std::shuffle(parts.begin(), parts.end(), rng);
  while (parts.size() > 1) {  // merge random pairs: an arbitrary tree
    const std::size_t i = rng() % (parts.size() - 1);
    parts[i].merge(parts[i + 1]);
    parts.erase(parts.begin() + static_cast<std::ptrdiff_t>(i) + 1);
  }
  RC_ASSERT(parts.front() == whole);
  RC_ASSERT(parts.front().checked_round() == whole.checked_round());
}

// Every permutation of seven extreme terms leaves the same limbs (5040 orders, exhaustively).
TEST(ExactSum, AllPermutationsOfSevenTermsAgree) {
  std::vector<Term> terms = {{0, INT64_MIN, INT64_MIN}, {0, INT64_MAX, INT64_MIN}, {1, INT64_MIN, INT64_MIN},
                             {2, INT64_MAX, 0},        {3, INT64_MIN, 0},        {0, 12345, -678910},
                             {1, INT64_MAX, INT64_MAX}};
  std::vector<int> order(terms.size());
  std::iota(order.begin(), order.end(), 0);
  ExactSum first;
  for (const Term& t : terms) apply(first, t);
  int perms = 0;
  do {
    ExactSum s;
    for (const int i : order) apply(s, terms[static_cast<std::size_t>(i)]);
    ASSERT_EQ(s, first);
    ++perms;
  } while (std::next_permutation(order.begin(), order.end()));
  EXPECT_EQ(perms, 5040);
}

// A TBB parallel_reduce over partial sums matches the serial sum bit for bit, whatever the
// grain and the number of threads.
TEST(ExactSum, ParallelReduceMatchesSerial) {
  std::mt19937_64 rng(42);
  std::vector<Q32> a(100000), b(100000);
  for (std::size_t i = 0; i < a.size(); ++i) {
    a[i] = Q32{static_cast<std::int64_t>(rng())};
    b[i] = Q32{static_cast<std::int64_t>(rng()) >> (rng() % 40)};
  }
  ExactSum serial;
  for (std::size_t i = 0; i < a.size(); ++i) serial.add_product(a[i], b[i]);
  for (const int threads : thread_counts()) {
    for (const std::size_t grain : {std::size_t{1}, std::size_t{7}, std::size_t{1000}, std::size_t{100000}}) {
      tbb::task_arena arena(threads);
      const ExactSum par = arena.execute([&] {
        return tbb::parallel_reduce(
            tbb::blocked_range<std::size_t>(0, a.size(), grain), ExactSum{},
            [&](const tbb::blocked_range<std::size_t>& r, ExactSum acc) {
              for (std::size_t i = r.begin(); i != r.end(); ++i) acc.add_product(a[i], b[i]);
              return acc;
            },
            [](ExactSum x, const ExactSum& y) {
              x.merge(y);
              return x;
            });
      });
      ASSERT_EQ(par, serial) << threads << " threads, grain " << grain;
    }
  }
}

// ---- the width argument of proofs/accumulator_width.md, machine-checked -----------------------

// 2^64 copies of the largest product, (-2^63)^2 = 2^126, built by 64 doublings with merge:
// the sum 2^190 is held exactly (it is below 2^191). Likewise the most negative product
// -2^63 (2^63 - 1) = -2^126 + 2^63.
TEST(ExactSumProof, TwoTo64ExtremeProductsFit) {
  ExactSum pos;
  pos.add_product(Q32::min(), Q32::min());
  ExactSum neg;
  neg.add_product(Q32::min(), Q32::max());
  for (int i = 0; i < 64; ++i) {
    const ExactSum p = pos, n = neg;
    pos.merge(p);
    neg.merge(n);
  }
  const cpp_int two64 = cpp_int(1) << 64;
  EXPECT_EQ(value_of(pos), two64 * (cpp_int(1) << 126));
  EXPECT_EQ(value_of(pos), cpp_int(1) << 190);
  EXPECT_EQ(value_of(neg), two64 * cpp_int(INT64_MIN) * cpp_int(INT64_MAX));
  EXPECT_EQ(pos.signum(), 1);
  EXPECT_EQ(neg.signum(), -1);
  EXPECT_FALSE(pos.checked_round().has_value());
  EXPECT_FALSE(neg.checked_round().has_value());
  // One more doubling (2^65 terms) reaches 2^191, which no longer fits: the bound is tight.
  ExactSum over = pos;
  over.merge(pos);
  EXPECT_NE(value_of(over), cpp_int(1) << 191);
  EXPECT_EQ(value_of(over), -(cpp_int(1) << 191));
  // And the arithmetic is modular: adding the negation of what was added returns to zero even
  // through that wrap, which is why intermediate overflow never matters (proofs/order_independence.md).
  ExactSum back = over;
  ExactSum minus_pos;
  minus_pos.sub_product(Q32::min(), Q32::min());
  for (int i = 0; i < 65; ++i) {
    const ExactSum m = minus_pos;
    minus_pos.merge(m);
  }
  back.merge(minus_pos);
  EXPECT_EQ(back, ExactSum{});
}

// The worst case of the bound, |sum| <= N * 2^126 < 2^191, holds for every N < 2^65.
TEST(ExactSumProof, BoundArithmetic) {
  const cpp_int max_term = cpp_int(1) << 126;  // |a * b| <= (2^63)^2
  EXPECT_EQ(cpp_int(INT64_MIN) * cpp_int(INT64_MIN), max_term);
  EXPECT_LT(abs(cpp_int(INT64_MIN) * cpp_int(INT64_MAX)), max_term);
  EXPECT_LT(abs(cpp_int(INT64_MIN) << 32), max_term);  // a plain value's term is tiny
  const cpp_int n = (cpp_int(1) << 65) - 1;
  EXPECT_LE(n * max_term, (cpp_int(1) << 191) - 1);
  EXPECT_GE(-n * max_term, -(cpp_int(1) << 191));
  EXPECT_GT((n + 1) * max_term, (cpp_int(1) << 191) - 1);
}

// Rounding at the exact range ends: states around (2^63 - 1/2) 2^32 and (-2^63 - 1/2) 2^32.
TEST(ExactSumProof, RoundingAtRangeEnds) {
  const cpp_int centers[] = {(cpp_int(INT64_MAX) << 32) + (cpp_int(1) << 31), (cpp_int(INT64_MIN) << 32) - (cpp_int(1) << 31),
                             cpp_int(1) << 31, -(cpp_int(1) << 31), cpp_int(3) << 31, 0};
  for (const cpp_int& c : centers) {
    for (int d = -3; d <= 3; ++d) {
      const cpp_int v = c + d;
      const cpp_int u = v < 0 ? cpp_int((cpp_int(1) << 192) + v) : v;
      const auto limb = [&](int i) { return static_cast<std::uint64_t>((u >> (64 * i)) & cpp_int(UINT64_MAX)); };
      const ExactSum s = ExactSum::from_limbs({limb(0), limb(1), limb(2)});
      ASSERT_EQ(value_of(s), v);
      const cpp_int expect = ref_round(v);
      const auto r = s.checked_round();
      ASSERT_EQ(r.has_value(), in_range(expect)) << v;
      if (r) {
        ASSERT_EQ(cpp_int(r->raw), expect) << v;
      }
    }
  }
}

TEST(ExactSum, DotAndSumHelpers) {
  const std::vector<Q32> a = {Q32::from_int(3), Q32::from_decimal("0.5"), Q32::from_int(-2)};
  const std::vector<Q32> b = {Q32::from_int(2), Q32::from_decimal("0.5"), Q32::from_int(4)};
  EXPECT_EQ(r1::fx::exact_dot(a, b), Q32::from_decimal("-1.75"));
  EXPECT_EQ(r1::fx::exact_sum(a), Q32::from_decimal("1.5"));
  EXPECT_THROW(r1::fx::exact_dot(a, std::vector<Q32>{Q32::one()}), std::invalid_argument);
  // The terms overflow Q32 on the way, the sum does not: only the final rounding counts.
  const std::vector<Q32> big = {Q32::max(), Q32::max(), Q32::min(), Q32::min()};
  EXPECT_EQ(r1::fx::exact_sum(big), Q32{-2});
  EXPECT_THROW(r1::fx::exact_sum(std::vector<Q32>{Q32::max(), Q32::epsilon()}), r1::fx::OverflowError);
  // Products below half an ulp each would vanish if rounded one by one; summed exactly they do not.
  const std::vector<Q32> tiny(1000, Q32::epsilon());
  EXPECT_EQ(r1::fx::exact_dot(tiny, tiny), Q32{0});  // 1000 * 2^-64 < 2^-33
  const std::vector<Q32> small(1 << 20, Q32{1 << 16});
  EXPECT_EQ(r1::fx::exact_dot(small, small).raw, 1 << 20);  // 2^20 * 2^32 * 2^-64 exactly
}

static_assert([] {
  ExactSum s;
  s.add_product(Q32::from_int(2), Q32::from_int(3));
  s.sub(Q32::one());
  return s.round() == Q32::from_int(5);
}());

}  // namespace
