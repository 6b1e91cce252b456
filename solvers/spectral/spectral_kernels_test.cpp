// The spectral solver's exact kernels against independent references: RNE square roots of
// ratios and RNE shifts against Boost cpp_int, correctly rounded doubles against cpp_bin_float,
// Jacobi against Eigen, panel kernels serial vs TBB and against exact references (R1-SPEC-010..015, R1-SPEC-040..042).
#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <Eigen/Dense>
#include <boost/multiprecision/cpp_bin_float.hpp>
#include <boost/multiprecision/cpp_int.hpp>

#include <cmath>
#include <limits>
#include <numeric>

#include "r1/solvers/exact_round.hpp"
#include "r1/fixedpoint/counter_rng.hpp"
#include "jacobi.hpp"
#include "r1/solvers/panel.hpp"
#include "r1/fixedpoint/pairwise.hpp"

namespace {

using boost::multiprecision::cpp_int;
using r1::i128;
using r1::u128;
using r1::spectral::U256;

cpp_int big(u128 x) { return (cpp_int(static_cast<std::uint64_t>(x >> 64)) << 64) | cpp_int(static_cast<std::uint64_t>(x)); }
cpp_int big(const U256& x) { return (big(x.hi) << 128) | big(x.lo); }

// The reference: q = RNE(sqrt(num / den)) by the definition, with cpp_int.
std::uint64_t ref_sqrt_ratio(const cpp_int& num, const cpp_int& den) {
  // floor(sqrt(4 num / den)) = floor(2 sqrt(x)); the nearest integer to sqrt(x) is then decided
  // exactly by comparing (2q +- 1)^2 den with 4 num.
  cpp_int q = boost::multiprecision::sqrt(cpp_int(num / den));
  while ((2 * q + 1) * (2 * q + 1) * den <= 4 * num) ++q;
  while (q > 0 && (2 * q - 1) * (2 * q - 1) * den > 4 * num) --q;
  if (q > 0 && (2 * q - 1) * (2 * q - 1) * den == 4 * num && (q & 1) != 0) --q;
  return static_cast<std::uint64_t>(q);
}

// RNE(v / 2^s) by the definition: floor, then up when the remainder exceeds half or ties odd.
cpp_int rne_pow2(const cpp_int& v, int s) {
  const cpp_int den = cpp_int(1) << s;
  cpp_int q = v / den;  // truncates toward zero
  if (q * den > v) --q;  // floor for negative v
  const cpp_int rem = v - q * den;
  if (2 * rem > den || (2 * rem == den && (q & 1) != 0)) ++q;
  return q;
}

TEST(SpectralExact, MulWideMatchesCppInt) {
  rc::check([](std::uint64_t a0, std::uint64_t a1, std::uint64_t b0, std::uint64_t b1) {
    const u128 a = (static_cast<u128>(a1) << 64) | a0, b = (static_cast<u128>(b1) << 64) | b0;
    RC_ASSERT(big(r1::spectral::mul_wide(a, b)) == big(a) * big(b));
  });
}

TEST(SpectralExact, SqrtRatioMatchesDefinition) {
  rc::check([](std::uint32_t w, std::uint64_t di, std::uint64_t dj) {
    // The operator's entries: num = 2^64 w^2, den = D_i D_j with D >= w (a degree includes w).
    const u128 wv = static_cast<u128>(w) + 1;
    const u128 d1 = wv + (di >> 8), d2 = wv + (dj >> 8);
    const u128 w2 = wv * wv;
    const U256 num{w2 << 64, w2 >> 64};
    RC_ASSERT(r1::spectral::rne_sqrt_ratio(num, d1 * d2) == ref_sqrt_ratio(big(num), big(d1 * d2)));
  });
}

TEST(SpectralExact, SqrtRatioTiesGoToEven) {
  // sqrt(num / den) = 2.5 exactly (num/den = 6.25 = 25/4), 3.5 (49/4): ties to 2 and 4.
  EXPECT_EQ(r1::spectral::rne_sqrt_ratio(U256{25, 0}, 4), 2u);
  EXPECT_EQ(r1::spectral::rne_sqrt_ratio(U256{49, 0}, 4), 4u);
  EXPECT_EQ(r1::spectral::rne_sqrt_ratio(U256{26, 0}, 4), 3u);  // just above 2.5
  EXPECT_EQ(r1::spectral::rne_sqrt_ratio(U256{0, 0}, 7), 0u);
  // The trivial vector's scale: 2^64 2^20 D / sum D with a root near 2^42.
  const U256 num = r1::spectral::shl(U256{u128{12345} << 32, 0}, 84);
  EXPECT_EQ(r1::spectral::rne_sqrt_ratio(num, u128{98765} << 32), ref_sqrt_ratio(big(num), big(u128{98765} << 32)));
}

TEST(SpectralExact, RoundShiftMatchesCppInt) {
  rc::check([](std::int64_t a, std::int64_t b, std::int64_t c, std::uint8_t s8) {
    const int s = 1 + s8 % 100;
    r1::fx::ExactSum sum;
    sum.add_term(static_cast<i128>(a) * b);
    sum.add_term(static_cast<i128>(c) * (i128{1} << 40));
    const cpp_int v = cpp_int(a) * b + cpp_int(c) * (cpp_int(1) << 40);
    const cpp_int q = rne_pow2(v, s);
    const auto got = r1::spectral::round_shift(sum, s);
    if (q > INT64_MAX || q < INT64_MIN) {
      RC_ASSERT(!got.has_value());
    } else {
      RC_ASSERT(got.has_value());
      RC_ASSERT(cpp_int(*got) == q);
    }
  });
}

TEST(SpectralExact, ToDoubleScaledIsCorrectlyRounded) {
  using Big = boost::multiprecision::cpp_bin_float_100;
  rc::check([](std::int64_t a, std::int64_t b, std::int64_t c, std::uint8_t k8) {
    const int k = k8 % 120;
    r1::fx::ExactSum sum;
    sum.add_term(static_cast<i128>(a) * b);
    sum.add_term(static_cast<i128>(c) * (i128{1} << 62));
    const cpp_int v = cpp_int(a) * b + cpp_int(c) * (cpp_int(1) << 62);
    // cpp_bin_float_100 holds v exactly (< 2^190 needs 190 bits; 100 decimal digits are 332 bits).
    const Big exact = Big(v) / Big(cpp_int(1) << k);
    const double want = exact.convert_to<double>();  // round to nearest, ties to even
    RC_ASSERT(r1::spectral::to_double_scaled(sum, k) == want);
  });
}

TEST(SpectralExact, MulExactMatchesCppInt) {
  rc::check([](std::int32_t hi, std::uint32_t lo, std::uint64_t fbits) {
    const r1::fx::Q32 x = r1::fx::Q32::from_raw((static_cast<std::int64_t>(hi % 4096) << 32) | lo);
    // A finite double with a moderate exponent.
    const double f = std::ldexp(static_cast<double>(fbits >> 11) * 0x1p-53 + 0.5, static_cast<int>(fbits % 40) - 20);
    int ex = 0;
    const double mant = std::frexp(f, &ex);
    const cpp_int m(static_cast<std::int64_t>(std::ldexp(mant, 53)));
    const int shift = ex - 53;  // f = m 2^shift
    const cpp_int p = cpp_int(x.raw) * m;
    const cpp_int q = shift >= 0 ? cpp_int(p << shift) : rne_pow2(p, -shift);
    RC_PRE(q <= INT64_MAX && q >= INT64_MIN);
    RC_ASSERT(cpp_int(r1::spectral::mul_exact(x, f).raw) == q);
  });
}

TEST(SpectralExact, Coef60RoundsOnce) {
  EXPECT_EQ(r1::spectral::coef60(1.0), std::int64_t{1} << 60);
  EXPECT_EQ(r1::spectral::coef60(-0.5), -(std::int64_t{1} << 59));
  EXPECT_EQ(r1::spectral::coef60(0x1p-61), 0);          // a tie: to the even 0
  EXPECT_EQ(r1::spectral::coef60(0x1.8p-60), 2);        // 1.5 units: a tie, to the even 2
  EXPECT_EQ(r1::spectral::coef60(0x1.4p-60), 1);        // 1.25 units
  EXPECT_THROW(r1::spectral::coef60(8.0), r1::fx::OverflowError);
  EXPECT_THROW(r1::spectral::coef60(std::nan("")), r1::fx::OverflowError);
}

TEST(SpectralExact, FastExactSpillsWithoutLoss) {
  // Terms near 2^126 overflow the i128 fast path at once; the total must stay exact.
  r1::spectral::FastExact acc;
  cpp_int ref = 0;
  const i128 big_term = (i128{1} << 126) - 12345;
  for (int i = 0; i < 10; ++i) {
    acc.add(big_term);
    ref += big(static_cast<u128>(big_term));
  }
  acc.add(-big_term);
  ref -= big(static_cast<u128>(big_term));
  const auto l = acc.total().limbs();
  const cpp_int got = (cpp_int(l[2]) << 128) | (cpp_int(l[1]) << 64) | cpp_int(l[0]);
  EXPECT_EQ(got, ref);
}

// ---- Jacobi ----

TEST(SpectralJacobi, MatchesEigenOnRandomSymmetric) {
  rc::check([](std::uint64_t seed) {
    const std::size_t m = 2 + seed % 40;
    std::vector<double> a(m * m);
    Eigen::MatrixXd e(m, m);
    for (std::size_t i = 0; i < m; ++i)
      for (std::size_t j = i; j < m; ++j) {
        const double v = static_cast<double>(static_cast<std::int64_t>(r1::rng::bits(seed, i, j) >> 11)) * 0x1p-53 - 0.5;
        a[i * m + j] = a[j * m + i] = v;
        e(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = e(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(i)) = v;
      }
    const auto r = r1::spectral::jacobi_eigen(m, a);
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(e);
    for (std::size_t c = 0; c < m; ++c) RC_ASSERT(std::fabs(r.values[c] - es.eigenvalues()(static_cast<Eigen::Index>(c))) < 1e-13);
    // A Z = Z diag(values) and Z^T Z = I.
    for (std::size_t c = 0; c < m; ++c)
      for (std::size_t i = 0; i < m; ++i) {
        double az = 0;
        for (std::size_t k = 0; k < m; ++k) az += a[i * m + k] * r.vectors[k * m + c];
        RC_ASSERT(std::fabs(az - r.values[c] * r.vectors[i * m + c]) < 1e-13);
      }
    for (std::size_t c = 0; c < m; ++c)
      for (std::size_t d = 0; d < m; ++d) {
        double dot = 0;
        for (std::size_t k = 0; k < m; ++k) dot += r.vectors[k * m + c] * r.vectors[k * m + d];
        RC_ASSERT(std::fabs(dot - (c == d ? 1.0 : 0.0)) < 1e-13);
      }
    RC_ASSERT(r.sweeps < r1::spectral::kJacobiMaxSweeps);
  });
}

TEST(SpectralJacobi, RepeatedAndDiagonalInputs) {
  // Already diagonal: no sweep; values sorted with ties in diagonal order.
  const auto d = r1::spectral::jacobi_eigen(3, {2, 0, 0, 0, 1, 0, 0, 0, 1});
  EXPECT_EQ(d.sweeps, 0);
  EXPECT_EQ(d.values, (std::vector<double>{1, 1, 2}));
  EXPECT_EQ(d.vectors[1 * 3 + 0], 1.0);  // first 1 came from diagonal entry 1
  // A multiple of the all-ones matrix: eigenvalues 0, 0, 3.
  const auto o = r1::spectral::jacobi_eigen(3, {1, 1, 1, 1, 1, 1, 1, 1, 1});
  EXPECT_NEAR(o.values[0], 0, 1e-15);
  EXPECT_NEAR(o.values[1], 0, 1e-15);
  EXPECT_NEAR(o.values[2], 3, 1e-15);
}

// ---- panel kernels: serial == TBB, Q32 == exact reference, fp64 == the pairwise tree ----

using QPanel = r1::spectral::Panel<r1::fx::Q32>;
using QOps = r1::spectral::PanelOps<r1::fx::Q32>;
using Cols = std::vector<std::uint32_t>;

TEST(SpectralKernels, ParallelMatchesSerialBitForBit) {
  const std::size_t n = (std::size_t{1} << 16) + 777;  // above kParallelMin, ragged last block
  const QOps serial(n, 17, false), parallel(n, 17, true);
  QPanel a(n, 5), b(n, 5);
  for (std::uint32_t c = 0; c < 3; ++c) {
    serial.random(a, c, 7, c);
    parallel.random(b, c, 7, c);
  }
  for (std::size_t i = 0; i < n; ++i)
    for (std::uint32_t c = 0; c < 3; ++c) ASSERT_EQ(a.at(i, c), b.at(i, c));
  const Cols qs{0, 1, 2}, ws{1, 2};
  std::vector<double> d1(6), d2(6);
  serial.dots(a, qs, ws, d1);
  parallel.dots(a, qs, ws, d2);
  EXPECT_EQ(d1, d2);
  const std::vector<double> coef{0.375, -1.25, 0.5, 2.0, -0.125, 1.0};  // 3 terms x 2 outputs
  serial.combine(a, Cols{3, 4}, Cols{0, 1}, qs, coef);
  parallel.combine(b, Cols{3, 4}, Cols{0, 1}, qs, coef);
  serial.scale(a, 3, 0.7071);
  parallel.scale(b, 3, 0.7071);
  for (std::size_t i = 0; i < n; ++i)
    for (std::uint32_t c = 3; c < 5; ++c) ASSERT_EQ(a.at(i, c), b.at(i, c));
  const r1::spectral::PanelOps<double> fs(n, 17, false), fp(n, 17, true);
  r1::spectral::Panel<double> x(n, 3);
  for (std::uint32_t c = 0; c < 3; ++c) fs.random(x, c, 7, c);
  fs.dots(x, qs, ws, d1);
  fp.dots(x, qs, ws, d2);
  EXPECT_EQ(d1, d2);
}

TEST(SpectralKernels, Fp64DotsAreThePairwiseTreeOfEachPair) {
  // One sweep over the rows for many pairs gives, pair by pair, pairwise_dot's bits (R1-NUM-051)
  // times 2^-e, at lengths around the 64-leaf blocks.
  for (const std::size_t n : {1u, 63u, 64u, 65u, 200u, 4159u}) {
    SCOPED_TRACE(n);
    const r1::spectral::PanelOps<double> ops(n, 3, false);
    r1::spectral::Panel<double> p(n, 3);
    for (std::uint32_t c = 0; c < 3; ++c) ops.random(p, c, 11, c);
    for (std::size_t i = 0; i < n; i += 3) p.at(i, 1) = p.at(i, 1) * 1e9;  // make the order matter
    std::vector<double> d(9);
    const Cols all{0, 1, 2};
    ops.dots(p, all, all, d);
    for (std::uint32_t q = 0; q < 3; ++q)
      for (std::uint32_t w = 0; w < 3; ++w)
        EXPECT_EQ(d[q * 3 + w], std::ldexp(r1::fx::pairwise_dot(p.copy_column(q), p.copy_column(w)), -3));
  }
}

TEST(SpectralKernels, Q32CombineRoundsOnceExactly) {
  rc::check([](std::vector<std::int32_t> raw_a, double c0, double c1) {
    RC_PRE(!raw_a.empty());
    RC_PRE(std::fabs(c0) < 7.9 && std::fabs(c1) < 7.9);
    const std::size_t n = raw_a.size();
    const QOps ops(n, 3, false);
    QPanel p(n, 2);
    for (std::size_t i = 0; i < n; ++i) {
      p.at(i, 0) = r1::fx::Q32::from_raw(static_cast<std::int64_t>(raw_a[i]) * 977);
      p.at(i, 1) = r1::fx::Q32::from_raw(-static_cast<std::int64_t>(raw_a[n - 1 - i]) * 313);
    }
    const QPanel before = p;
    // Column 1 <- column 1 + c0 a + c1 b, in place: the row's old values feed every term.
    ops.combine(p, Cols{1}, Cols{1}, Cols{0, 1}, std::vector<double>{c0, c1});
    const cpp_int k0 = r1::spectral::coef60(c0), k1 = r1::spectral::coef60(c1);
    for (std::size_t i = 0; i < n; ++i) {
      const std::int64_t a = before.at(i, 0).raw, b = before.at(i, 1).raw;
      const cpp_int v = (cpp_int(b) << 60) + k0 * a + k1 * b;
      RC_ASSERT(cpp_int(p.at(i, 1).raw) == rne_pow2(v, 60));
      RC_ASSERT(p.at(i, 0) == before.at(i, 0));
    }
  });
}

// The unchecked i128 fast paths and the checked path (a factor too large for the fast path's
// bound in the block or row) give the exact sums a cpp_int computes: mixes of small and
// near-2^62 raws.
TEST(SpectralKernels, FastAndCheckedPathsAreBothExact) {
  for (const int big_bits : {40, 56, 57, 62}) {
    SCOPED_TRACE(big_bits);
    const std::size_t n = 5000;  // two blocks, the second ragged
    const QOps ops(n, 0, false);
    QPanel p(n, 3);
    for (std::size_t i = 0; i < n; ++i) {
      const auto r = r1::rng::bits(99, i, 0);
      const std::int64_t mag = static_cast<std::int64_t>(r >> (64 - big_bits));
      // A few entries at full size, the rest small, signs mixed.
      p.at(i, 0) = r1::fx::Q32::from_raw((i % 97 == 0 ? mag : mag >> 20) * ((r & 1) ? -1 : 1));
      p.at(i, 1) = r1::fx::Q32::from_raw((i % 89 == 0 ? mag : mag >> 18) * ((r & 2) ? -1 : 1));
    }
    std::vector<double> d(2);
    ops.dots(p, Cols{0, 1}, Cols{1}, d);
    cpp_int sa = 0, sb = 0;
    for (std::size_t i = 0; i < n; ++i) {
      cpp_int t = p.at(i, 0).raw;
      t *= p.at(i, 1).raw;
      sa += t;
      t = p.at(i, 1).raw;
      t *= p.at(i, 1).raw;
      sb += t;
    }
    // dots returns the exact sum / 2^64, correctly rounded to double (ldexp of the correctly
    // rounded sum: the scaling by a power of two is exact).
    EXPECT_EQ(d[0], std::ldexp(sa.convert_to<double>(), -64));
    EXPECT_EQ(d[1], std::ldexp(sb.convert_to<double>(), -64));
    if (big_bits <= 57) {
      // Coefficients near 8 push the fast path's bound for the large rows.
      const double c0 = 7.75, c1 = -1.25;
      ops.combine(p, Cols{2}, {}, Cols{0, 1}, std::vector<double>{c0, c1});
      const cpp_int k0 = r1::spectral::coef60(c0), k1 = r1::spectral::coef60(c1);
      for (std::size_t i = 0; i < n; i += 7)
        ASSERT_EQ(cpp_int(p.at(i, 2).raw), rne_pow2(k0 * p.at(i, 0).raw + k1 * p.at(i, 1).raw, 60)) << i;
    }
  }
}

// The filter's recurrence (R1-SPEC-081): three_term is PanelOps::combine with the terms (s, y, p)
// and a diagonal of coefficients, bit for bit, and the exact sum of cpp_int rounded once; with
// gamma = 0 p is not read; in parallel the same bits.
TEST(SpectralKernels, ThreeTermIsTheDiagonalCombination) {
  rc::check([](std::vector<std::int32_t> raw, double a, double b, double g, bool wide) {
    RC_PRE(raw.size() >= 3);
    RC_PRE(std::fabs(a) < 7.9 && std::fabs(b) < 7.9 && std::fabs(g) < 7.9);
    const std::size_t len = raw.size() - 2;
    // Wide raws (near 2^62) take the checked path, narrow ones the plain i128 sum.
    const std::int64_t scale = wide ? (std::int64_t{1} << 31) : 977;
    std::vector<r1::fx::Q32> sv(len), yv(len), pv(len);
    for (std::size_t k = 0; k < len; ++k) {
      sv[k] = r1::fx::Q32::from_raw(static_cast<std::int64_t>(raw[k]) * scale);
      yv[k] = r1::fx::Q32::from_raw(-static_cast<std::int64_t>(raw[k + 1]) * scale);
      pv[k] = r1::fx::Q32::from_raw(static_cast<std::int64_t>(raw[k + 2]) * scale);
    }
    // The combination on a panel whose rows are (s, y, p).
    QPanel panel(len, 3);
    for (std::size_t k = 0; k < len; ++k) {
      panel.at(k, 0) = sv[k];
      panel.at(k, 1) = yv[k];
      panel.at(k, 2) = pv[k];
    }
    const QOps ops(len, 0, false);
    ops.combine(panel, Cols{2}, {}, Cols{0, 1, 2}, std::vector<double>{a, b, g});
    std::vector<r1::fx::Q32> out = pv;
    r1::spectral::three_term(len, sv.data(), yv.data(), out.data(), a, b, g, false);
    const cpp_int ka = r1::spectral::coef60(a), kb = r1::spectral::coef60(b), kg = r1::spectral::coef60(g);
    for (std::size_t k = 0; k < len; ++k) {
      RC_ASSERT(out[k] == panel.at(k, 2));
      RC_ASSERT(cpp_int(out[k].raw) == rne_pow2(ka * sv[k].raw + kb * yv[k].raw + kg * pv[k].raw, 60));
    }
    // gamma = 0: p's old values do not matter.
    std::vector<r1::fx::Q32> junk(len, r1::fx::Q32::from_raw(std::numeric_limits<std::int64_t>::min()));
    r1::spectral::three_term(len, sv.data(), yv.data(), junk.data(), a, b, 0.0, false);
    for (std::size_t k = 0; k < len; ++k)
      RC_ASSERT(cpp_int(junk[k].raw) == rne_pow2(ka * sv[k].raw + kb * yv[k].raw, 60));
  });
  // Long enough for the TBB path: the same bits as serially, fp64 too.
  const std::size_t len = std::size_t{1} << 17;
  std::vector<r1::fx::Q32> s(len), y(len), p(len);
  std::vector<double> sd(len), yd(len), pd(len);
  for (std::size_t k = 0; k < len; ++k) {
    s[k] = r1::fx::Q32::from_raw(static_cast<std::int64_t>(r1::rng::bits(7, k, 0) >> 12) - (std::int64_t{1} << 51));
    y[k] = r1::fx::Q32::from_raw(static_cast<std::int64_t>(r1::rng::bits(7, k, 1) >> 12) - (std::int64_t{1} << 51));
    p[k] = r1::fx::Q32::from_raw(static_cast<std::int64_t>(r1::rng::bits(7, k, 2) >> 12) - (std::int64_t{1} << 51));
    sd[k] = std::ldexp(static_cast<double>(s[k].raw), -48);
    yd[k] = std::ldexp(static_cast<double>(y[k].raw), -48);
    pd[k] = std::ldexp(static_cast<double>(p[k].raw), -48);
  }
  std::vector<r1::fx::Q32> serial = p, parallel = p;
  r1::spectral::three_term(len, s.data(), y.data(), serial.data(), 2.7, -3.4, -0.9, false);
  r1::spectral::three_term(len, s.data(), y.data(), parallel.data(), 2.7, -3.4, -0.9, true);
  EXPECT_TRUE(serial == parallel);
  std::vector<double> dserial = pd, dparallel = pd;
  r1::spectral::three_term(len, sd.data(), yd.data(), dserial.data(), 2.7, -3.4, -0.9, false);
  r1::spectral::three_term(len, sd.data(), yd.data(), dparallel.data(), 2.7, -3.4, -0.9, true);
  EXPECT_TRUE(dserial == dparallel);
  EXPECT_EQ(dserial[5], (2.7 * sd[5] + -3.4 * yd[5]) + -0.9 * pd[5]);
}

}  // namespace
