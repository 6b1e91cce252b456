// The Clifford primitives: deterministic exp against std::exp, roll, the published CT-0 checks (Wedge_s(X, X) = 0, zero bivector = scalar-only model, shifted products against a naive reference), antisymmetry, the block and the graph context (R1-RND-100..107).
#include "r1/reference/clifford.hpp"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <algorithm>
#include <bit>
#include <boost/multiprecision/cpp_bin_float.hpp>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "r1/fixedpoint/counter_rng.hpp"

namespace {

namespace cl = r1::clifford;
using cl::Rows;

// A random n x d tensor, entries uniform in [lo, hi) from the counter RNG.
Rows random_rows(std::uint64_t seed, std::uint32_t n, std::uint32_t d, double lo = -2.0, double hi = 2.0) {
  Rows x = cl::zeros(n, d);
  for (std::size_t e = 0; e < x.v.size(); ++e) x.v[e] = lo + (hi - lo) * r1::rng::uniform_double(seed, e, 0);
  return x;
}

// Never zero: magnitude in [0.25, 2.25), random sign (tests that compare bytes of h + 0 * t).
Rows nonzero_rows(std::uint64_t seed, std::uint32_t n, std::uint32_t d) {
  Rows x = cl::zeros(n, d);
  for (std::size_t e = 0; e < x.v.size(); ++e) {
    const double m = 0.25 + 2.0 * r1::rng::uniform_double(seed, e, 0);
    x.v[e] = r1::rng::uniform_double(seed, e, 1) < 0.5 ? -m : m;
  }
  return x;
}

bool same_bytes(const Rows& a, const Rows& b) {
  return a.n == b.n && a.d == b.d && a.v.size() == b.v.size() &&
         (a.v.empty() || std::memcmp(a.v.data(), b.v.data(), a.v.size() * sizeof(double)) == 0);
}

// Random test inputs drawn by RapidCheck: sizes, a seed for the values and a shift set that
// includes negative shifts and shifts >= d.
struct Case {
  std::uint32_t n, d;
  std::uint64_t seed;
  std::vector<std::int32_t> shifts;
};
Case random_case() {
  Case k;
  k.n = *rc::gen::inRange<std::uint32_t>(0, 9);
  k.d = *rc::gen::inRange<std::uint32_t>(1, 20);
  k.seed = *rc::gen::inRange<std::uint64_t>(1, std::uint64_t{1} << 40);
  const auto count = *rc::gen::inRange<std::size_t>(1, 7);
  for (std::size_t i = 0; i < count; ++i) k.shifts.push_back(*rc::gen::inRange<std::int32_t>(-40, 41));
  return k;
}

// Random block parameters with gamma of order 1 (so the whole residual path is exercised).
cl::BlockParams random_params(std::uint64_t seed, std::uint32_t d, std::size_t shifts) {
  cl::BlockParams p;
  p.w = random_rows(seed ^ 0x11, static_cast<std::uint32_t>(2 * shifts * d), d, -0.5, 0.5);
  p.wg = random_rows(seed ^ 0x22, 2 * d, d, -0.5, 0.5);
  const Rows vecs = random_rows(seed ^ 0x33, 3, d, -1.0, 1.0);
  p.bias.assign(vecs.v.begin(), vecs.v.begin() + d);
  p.bg.assign(vecs.v.begin() + d, vecs.v.begin() + 2 * d);
  p.gamma.assign(vecs.v.begin() + 2 * d, vecs.v.end());
  return p;
}

// ---- the naive reference: plain loops in another order, std::exp, channel index by a % ----------

long long wrap(long long c, long long d) { return ((c % d) + d) % d; }
double naive_silu(double x) { return x / (1.0 + std::exp(-x)); }

// Inner and Wedge of shift s at (i, c), indexing C(i, c + s) directly.
double naive_inner(const Rows& h, const Rows& c, std::uint32_t i, std::uint32_t ch, std::int32_t s) {
  const auto j = static_cast<std::uint32_t>(wrap(static_cast<long long>(ch) + s, h.d));
  return naive_silu(h.v[i * h.d + ch] * c.v[i * h.d + j]);
}
double naive_wedge(const Rows& h, const Rows& c, std::uint32_t i, std::uint32_t ch, std::int32_t s) {
  const auto j = static_cast<std::uint32_t>(wrap(static_cast<long long>(ch) + s, h.d));
  return h.v[i * h.d + ch] * c.v[i * h.d + j] - h.v[i * h.d + j] * c.v[i * h.d + ch];
}

// ---- deterministic exp (R1-RND-101) -------------------------------------------------------------

TEST(Clifford, LnTwoSplitIsExact) {
  using F = boost::multiprecision::cpp_bin_float_50;
  const F ln2 = boost::multiprecision::log(F(2));
  const F err = abs(F(cl::detail::kLn2Hi) + F(cl::detail::kLn2Lo) - ln2);
  EXPECT_LT(err, F(std::ldexp(1.0, -85)));
  // The low 20 fraction bits of kLn2Hi are zero, so k * kLn2Hi is exact for |k| < 2^20.
  const auto bits = std::bit_cast<std::uint64_t>(cl::detail::kLn2Hi);
  EXPECT_EQ(bits & ((std::uint64_t{1} << 20) - 1), 0u);
}

TEST(Clifford, DetExpMatchesStdExpOnAGrid) {
  // Relative 1e-14 over the normal range (results below 2^-1022 are subnormal and lose relative
  // precision by design) on a grid that crosses every reduction interval many times.
  double worst = 0;
  for (int i = 0; i <= 400000; ++i) {
    const double x = -708.0 + i * (1417.7 / 400000.0);
    const double want = std::exp(x);
    worst = std::max(worst, std::fabs(cl::det_exp(x) - want) / want);
  }
  // A fine grid around 0 and the reduction boundaries +-ln2/2.
  for (int i = -20000; i <= 20000; ++i) {
    const double x = i * 1e-4;
    worst = std::max(worst, std::fabs(cl::det_exp(x) - std::exp(x)) / std::exp(x));
  }
  EXPECT_LT(worst, 1e-14);
  char text[32];
  std::snprintf(text, sizeof text, "%.3e", worst);
  RecordProperty("worst_relative_error", text);
}

TEST(Clifford, DetExpSpecialValues) {
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(cl::det_exp(0.0), 1.0);
  EXPECT_EQ(cl::det_exp(-0.0), 1.0);
  EXPECT_EQ(cl::det_exp(inf), inf);
  EXPECT_EQ(cl::det_exp(-inf), 0.0);
  EXPECT_TRUE(std::isnan(cl::det_exp(std::numeric_limits<double>::quiet_NaN())));
  EXPECT_EQ(cl::det_exp(709.79), inf);   // past ln(DBL_MAX) = 709.7827...
  EXPECT_EQ(cl::det_exp(800.0), inf);
  EXPECT_EQ(cl::det_exp(-800.0), 0.0);
  EXPECT_GT(cl::det_exp(709.78), 1e308);  // still finite
  // Subnormal results: within one subnormal step of std::exp.
  for (const double x : {-710.0, -720.5, -740.0, -744.4}) {
    EXPECT_LE(std::fabs(cl::det_exp(x) - std::exp(x)), std::numeric_limits<double>::denorm_min()) << x;
  }
}

TEST(Clifford, SiluAndSigmoid) {
  EXPECT_EQ(cl::sigmoid(0.0), 0.5);
  EXPECT_EQ(cl::silu(0.0), 0.0);
  EXPECT_EQ(cl::sigmoid(1000.0), 1.0);
  EXPECT_EQ(cl::sigmoid(-1000.0), 0.0);
  EXPECT_EQ(cl::silu(-1000.0), 0.0);  // -1000 / inf
  EXPECT_EQ(cl::silu(1000.0), 1000.0);
  for (int i = -3000; i <= 3000; ++i) {
    const double x = i * 0.01;
    EXPECT_NEAR(cl::sigmoid(x), 1.0 / (1.0 + std::exp(-x)), 1e-15);
    EXPECT_NEAR(cl::silu(x), naive_silu(x), 1e-14 * std::max(1.0, std::fabs(x)));
  }
}

// ---- roll (R1-RND-102) --------------------------------------------------------------------------

TEST(Clifford, RollHandExample) {
  // numpy: x = [[0,1,2,3],[4,5,6,7]]; np.roll(x, 1, axis=1) = [[3,0,1,2],[7,4,5,6]],
  // np.roll(x, -1, axis=1) = [[1,2,3,0],[5,6,7,4]], np.roll(x, 1, axis=0) swaps the rows.
  const Rows x{2, 4, {0, 1, 2, 3, 4, 5, 6, 7}};
  EXPECT_EQ(cl::roll(x, 1, 1)->v, (std::vector<double>{3, 0, 1, 2, 7, 4, 5, 6}));
  EXPECT_EQ(cl::roll(x, -1, 1)->v, (std::vector<double>{1, 2, 3, 0, 5, 6, 7, 4}));
  EXPECT_EQ(cl::roll(x, 5, 1)->v, (std::vector<double>{3, 0, 1, 2, 7, 4, 5, 6}));  // 5 = 1 mod 4
  EXPECT_EQ(cl::roll(x, 1, 0)->v, (std::vector<double>{4, 5, 6, 7, 0, 1, 2, 3}));
  EXPECT_EQ(cl::roll(x, std::numeric_limits<std::int32_t>::min(), 1)->v, x.v);  // -2^31 = 0 mod 4
  const Rows three{3, 1, {10, 20, 30}};
  EXPECT_EQ(cl::roll(three, -4, 0)->v, (std::vector<double>{20, 30, 10}));  // -4 = 2 mod 3
}

RC_GTEST_PROP(Clifford, RollInverseAndFullTurn, ()) {
  const Case k = random_case();
  const Rows x = random_rows(k.seed, k.n, k.d);
  const auto s = *rc::gen::inRange<std::int32_t>(-1000, 1001);
  const auto axis = *rc::gen::inRange<std::uint32_t>(0, 2);
  const auto there = cl::roll(x, s, axis);
  RC_ASSERT(there.is_ok());
  const auto back = cl::roll(*there, -s, axis);
  RC_ASSERT(back.is_ok());
  RC_ASSERT(same_bytes(*back, x));
  RC_ASSERT(same_bytes(*cl::roll(x, static_cast<std::int32_t>(k.d), 1), x));
  RC_ASSERT(same_bytes(*cl::roll(x, static_cast<std::int32_t>(k.n), 0), x));
  // Channel roll is the shift the products use: roll(C, -s)(i, c) = C(i, c + s).
  const auto r = cl::roll(x, -s, 1);
  for (std::uint32_t i = 0; i < x.n; ++i)
    for (std::uint32_t c = 0; c < x.d; ++c)
      RC_ASSERT(r->at(i, c) == x.at(i, static_cast<std::uint32_t>(wrap(static_cast<long long>(c) + s, x.d))));
}

// ---- the shifted products (R1-RND-103, R1-RND-107) ----------------------------------------------

TEST(Clifford, ShiftedProductsHandExample) {
  const Rows h{1, 3, {1, 2, 3}}, c{1, 3, {4, 5, 6}};
  const std::vector<std::int32_t> s{1};
  // Wedge_1: 1*5 - 2*4, 2*6 - 3*5, 3*4 - 1*6.
  EXPECT_EQ(cl::shifted_wedge(h, c, s)->v, (std::vector<double>{-3, -3, 6}));
  const auto inner = cl::shifted_inner(h, c, s);
  ASSERT_TRUE(inner.is_ok());
  EXPECT_EQ(inner->v, (std::vector<double>{cl::silu(5), cl::silu(12), cl::silu(12)}));
  // Two shifts: blocks side by side in shift order; shift 0 (and 3 = 0 mod 3) has zero wedge.
  const std::vector<std::int32_t> s2{1, 3};
  const auto w2 = cl::shifted_wedge(h, c, s2);
  EXPECT_EQ(w2->n, 1u);
  EXPECT_EQ(w2->d, 6u);
  EXPECT_EQ(w2->v, (std::vector<double>{-3, -3, 6, 0, 0, 0}));
}

// Published check: Wedge_s(X, X) = 0. With X = H = C each entry is a*b - b*a: IEEE
// multiplication is commutative and correctly rounded, so both products are the same double and
// their difference is exactly +0. (With FMA contraction the compiler could compute
// fma(a, b, -(b*a)), the rounding error of a*b, which is not 0: hence -ffp-contract=off.)
RC_GTEST_PROP(Clifford, WedgeOfSelfIsExactlyZero, ()) {
  const Case k = random_case();
  const Rows x = random_rows(k.seed, k.n, k.d, -1e3, 1e3);
  const auto w = cl::shifted_wedge(x, x, k.shifts);
  RC_ASSERT(w.is_ok());
  RC_ASSERT(w->v.size() == std::size_t{k.n} * k.d * k.shifts.size());
  for (const double v : w->v) RC_ASSERT(v == 0.0 && !std::signbit(v));
}

// fl(a - b) = -fl(b - a) under round-to-nearest-even, and Wedge_s(C, H) has the same two
// products as Wedge_s(H, C) with the operands of the subtraction swapped: exact antisymmetry.
RC_GTEST_PROP(Clifford, WedgeAntisymmetric, ()) {
  const Case k = random_case();
  const Rows h = random_rows(k.seed, k.n, k.d), c = random_rows(k.seed + 1, k.n, k.d);
  const auto hc = cl::shifted_wedge(h, c, k.shifts), ch = cl::shifted_wedge(c, h, k.shifts);
  RC_ASSERT(hc.is_ok() && ch.is_ok());
  for (std::size_t e = 0; e < hc->v.size(); ++e) RC_ASSERT(hc->v[e] == -ch->v[e]);
}

// Published check: the shifted products match a reference within 1e-9. The reference walks
// shift, channel, row (the implementation row, shift, channel), wraps indices with %, and uses
// std::exp; the Clifford linear map is summed in reverse order in long double.
RC_GTEST_PROP(Clifford, ShiftedProductsMatchNaiveReference, ()) {
  const Case k = random_case();
  const Rows h = random_rows(k.seed, k.n, k.d), c = random_rows(k.seed + 1, k.n, k.d);
  const auto inner = cl::shifted_inner(h, c, k.shifts);
  const auto wedge = cl::shifted_wedge(h, c, k.shifts);
  RC_ASSERT(inner.is_ok() && wedge.is_ok());
  const std::size_t cols = k.shifts.size() * k.d;
  RC_ASSERT(inner->d == cols && wedge->d == cols && inner->n == k.n);
  for (std::size_t b = 0; b < k.shifts.size(); ++b)
    for (std::uint32_t ch = 0; ch < k.d; ++ch)
      for (std::uint32_t i = 0; i < k.n; ++i) {
        RC_ASSERT(std::fabs(inner->v[i * cols + b * k.d + ch] - naive_inner(h, c, i, ch, k.shifts[b])) <= 1e-9);
        RC_ASSERT(std::fabs(wedge->v[i * cols + b * k.d + ch] - naive_wedge(h, c, i, ch, k.shifts[b])) <= 1e-9);
      }
  // The full Clifford map: y(i, o) = bias(o) + sum over shifts b, halves, channels of F * W.
  const cl::BlockParams p = random_params(k.seed + 2, k.d, k.shifts.size());
  const auto y = cl::clifford(h, c, k.shifts, p.w, p.bias);
  RC_ASSERT(y.is_ok());
  for (std::uint32_t i = 0; i < k.n; ++i)
    for (std::uint32_t o = 0; o < k.d; ++o) {
      long double acc = static_cast<long double>(p.bias[o]);
      for (std::size_t b = k.shifts.size(); b-- > 0;)
        for (std::uint32_t ch = k.d; ch-- > 0;) {
          const std::size_t row_inner = 2 * b * k.d + ch, row_wedge = row_inner + k.d;
          acc += static_cast<long double>(naive_inner(h, c, i, ch, k.shifts[b])) * static_cast<long double>(p.w.v[row_inner * k.d + o]);
          acc += static_cast<long double>(naive_wedge(h, c, i, ch, k.shifts[b])) * static_cast<long double>(p.w.v[row_wedge * k.d + o]);
        }
      RC_ASSERT(std::fabs(static_cast<long double>(y->at(i, o)) - acc) <= 1e-9L);
    }
}

// Published check: a zero bivector input gives the output of a scalar-only model. The bivector
// half of the Clifford features is Wedge_s(H, C); it vanishes exactly when C = H (above), while
// the scalar half Inner_s(H, H) = SiLU(H(c) H(c + s)) does not. The scalar-only model is the same
// block whose linear map has the wedge rows removed: W_s = the Inner rows of W, G_s =
// linear(Inner(H, H), W_s, bias). Bit-for-bit: the full map adds the same products in the same
// order plus terms (+0) * w = +-0, and adding a signed zero to the running sum never changes
// it (the sum starts at +0 and an exact cancellation gives +0, so it is never -0).
RC_GTEST_PROP(Clifford, ZeroBivectorEqualsScalarOnlyModel, ()) {
  const Case k = random_case();
  const Rows h = random_rows(k.seed, k.n, k.d);
  const cl::BlockParams p = random_params(k.seed + 7, k.d, k.shifts.size());
  // W_s: for shift block b, the d Inner rows 2 b d .. 2 b d + d - 1.
  Rows ws = cl::zeros(static_cast<std::uint32_t>(k.shifts.size() * k.d), k.d);
  for (std::size_t b = 0; b < k.shifts.size(); ++b)
    for (std::uint32_t r = 0; r < k.d; ++r)
      for (std::uint32_t o = 0; o < k.d; ++o)
        ws.at(static_cast<std::uint32_t>(b * k.d + r), o) = p.w.at(static_cast<std::uint32_t>(2 * b * k.d + r), o);
  const auto inner = cl::shifted_inner(h, h, k.shifts);
  RC_ASSERT(inner.is_ok());
  const auto g_scalar = cl::linear(*inner, ws, p.bias);
  const auto g_full = cl::clifford(h, h, k.shifts, p.w, p.bias);
  RC_ASSERT(g_scalar.is_ok() && g_full.is_ok());
  RC_ASSERT(same_bytes(*g_full, *g_scalar));
  const auto out_scalar = cl::block_residual(h, *g_scalar, p);
  const auto out_full = cl::clifford_block(h, h, k.shifts, p);
  RC_ASSERT(out_scalar.is_ok() && out_full.is_ok());
  RC_ASSERT(same_bytes(*out_full, *out_scalar));
}

// C = 0 is the degenerate case: both halves vanish (SiLU(+-0) = +-0, Wedge = +-0), so the
// Clifford output is the bias alone.
TEST(Clifford, ZeroContextLeavesOnlyTheBias) {
  const Rows h = random_rows(3, 5, 6);
  const std::vector<std::int32_t> s{1, 2, 4, 8, 16};
  const cl::BlockParams p = random_params(4, 6, s.size());
  const auto g = cl::clifford(h, cl::zeros(5, 6), s, p.w, p.bias);
  ASSERT_TRUE(g.is_ok());
  for (std::uint32_t i = 0; i < 5; ++i)
    for (std::uint32_t o = 0; o < 6; ++o) EXPECT_EQ(g->at(i, o), p.bias[o]);
}

// ---- the block (R1-RND-104, R1-RND-105) ---------------------------------------------------------

RC_GTEST_PROP(Clifford, BlockWithGammaZeroReturnsH, ()) {
  const Case k = random_case();
  const Rows h = nonzero_rows(k.seed, k.n, k.d), c = random_rows(k.seed + 1, k.n, k.d);
  cl::BlockParams p = random_params(k.seed + 2, k.d, k.shifts.size());
  p.gamma.assign(k.d, 0.0);
  const auto out = cl::clifford_block(h, c, k.shifts, p);
  RC_ASSERT(out.is_ok());
  RC_ASSERT(same_bytes(*out, h));  // h + 0 * t = h for finite t and h != 0
}

TEST(Clifford, BlockMatchesItsFormula) {
  const std::vector<std::int32_t> s{1, 2, 4, 8, 16};
  const Rows h = random_rows(11, 4, 7), c = random_rows(12, 4, 7);
  const cl::BlockParams p = random_params(13, 7, s.size());
  const auto g = cl::clifford(h, c, s, p.w, p.bias);
  const auto out = cl::clifford_block(h, c, s, p);
  ASSERT_TRUE(g.is_ok() && out.is_ok());
  for (std::uint32_t i = 0; i < 4; ++i)
    for (std::uint32_t o = 0; o < 7; ++o) {
      double z = p.bg[o];
      for (std::uint32_t f = 0; f < 7; ++f) z += h.at(i, f) * p.wg.at(f, o) + g->at(i, f) * p.wg.at(7 + f, o);
      const double gate = 1.0 / (1.0 + std::exp(-z));
      const double x = h.at(i, o);
      EXPECT_NEAR(out->at(i, o), x + p.gamma[o] * (naive_silu(x) + gate * g->at(i, o)), 1e-12);
    }
}

TEST(Clifford, BlockIsDeterministic) {
  const std::vector<std::int32_t> s{1, 2, 4, 8, 16};
  const Rows h = random_rows(21, 16, 32), c = random_rows(22, 16, 32);
  const auto p1 = cl::init_block_params(32, s.size(), 99);
  const auto p2 = cl::init_block_params(32, s.size(), 99);
  ASSERT_TRUE(p1.is_ok() && p2.is_ok());
  EXPECT_TRUE(same_bytes(p1->w, p2->w));
  EXPECT_TRUE(same_bytes(p1->wg, p2->wg));
  const auto a = cl::clifford_block(h, c, s, *p1);
  const auto b = cl::clifford_block(h, c, s, *p2);
  ASSERT_TRUE(a.is_ok() && b.is_ok());
  EXPECT_TRUE(same_bytes(*a, *b));
  EXPECT_FALSE(same_bytes(*a, h));  // gamma = 1e-5 moves it, a little
}

TEST(Clifford, InitialParameters) {
  const auto p = cl::init_block_params(8, 5, 7);
  ASSERT_TRUE(p.is_ok());
  EXPECT_EQ(p->w.n, 80u);
  EXPECT_EQ(p->w.d, 8u);
  EXPECT_EQ(p->wg.n, 16u);
  EXPECT_EQ(p->wg.d, 8u);
  EXPECT_EQ(p->gamma, std::vector<double>(8, 1e-5));
  EXPECT_EQ(p->bias, std::vector<double>(8, 0.0));
  EXPECT_EQ(p->bg, std::vector<double>(8, 0.0));
  const double bw = 1.0 / std::sqrt(80.0), bg = 1.0 / std::sqrt(16.0);
  for (const double v : p->w.v) EXPECT_TRUE(v >= -bw && v < bw);
  for (const double v : p->wg.v) EXPECT_TRUE(v >= -bg && v < bg);
  EXPECT_EQ(p->w.v[3], (2.0 * r1::rng::uniform_double(7, 3, 0) - 1.0) * bw);
  EXPECT_EQ(p->wg.v[5], (2.0 * r1::rng::uniform_double(7, 5, 1) - 1.0) * bg);
  const auto other = cl::init_block_params(8, 5, 8);
  EXPECT_FALSE(same_bytes(p->w, other->w));
}

// ---- errors (R1-RND-100) ------------------------------------------------------------------------

TEST(Clifford, InputErrors) {
  const auto is_input = [](const auto& r) { return !r.is_ok() && r.status().kind() == r1::ErrorKind::kInput; };
  const Rows h = random_rows(1, 3, 4), c = random_rows(2, 3, 4), other = random_rows(3, 3, 5);
  const std::vector<std::int32_t> s{1, 2};
  const std::vector<std::int32_t> none;
  const Rows empty_d{3, 0, {}};
  const Rows bad_size{3, 4, {1.0, 2.0}};
  EXPECT_TRUE(is_input(cl::roll(empty_d, 1, 1)));
  EXPECT_TRUE(is_input(cl::roll(bad_size, 1, 1)));
  EXPECT_TRUE(is_input(cl::roll(h, 1, 2)));
  EXPECT_TRUE(is_input(cl::shifted_inner(h, other, s)));
  EXPECT_TRUE(is_input(cl::shifted_wedge(h, c, none)));
  EXPECT_TRUE(is_input(cl::shifted_inner(empty_d, empty_d, s)));
  const cl::BlockParams p = random_params(5, 4, s.size());
  EXPECT_TRUE(is_input(cl::clifford(h, c, none, p.w, p.bias)));
  EXPECT_TRUE(is_input(cl::clifford(h, c, std::vector<std::int32_t>{1}, p.w, p.bias)));  // W for 2 shifts
  EXPECT_TRUE(is_input(cl::clifford(h, c, s, p.w, std::vector<double>(3, 0.0))));
  cl::BlockParams bad = p;
  bad.gamma.pop_back();
  EXPECT_TRUE(is_input(cl::clifford_block(h, c, s, bad)));
  bad = p;
  bad.wg = random_rows(6, 4, 4);
  EXPECT_TRUE(is_input(cl::clifford_block(h, c, s, bad)));
  EXPECT_TRUE(is_input(cl::init_block_params(0, 5, 1)));
  EXPECT_TRUE(is_input(cl::init_block_params(4, 0, 1)));
  EXPECT_TRUE(is_input(cl::linear(h, random_rows(7, 5, 2), std::vector<double>(2, 0.0))));
  // No rows is fine: an empty batch.
  const Rows none_rows{0, 4, {}};
  const auto e = cl::shifted_wedge(none_rows, none_rows, s);
  ASSERT_TRUE(e.is_ok());
  EXPECT_EQ(e->n, 0u);
  EXPECT_EQ(e->d, 8u);
}

// ---- graph context (R1-RND-106) -----------------------------------------------------------------

// A path 0 - 1 - 2 with Q32 weights 1 and 0.5, plus an isolated particle 3.
r1::Graph small_graph() {
  constexpr std::int64_t one = std::int64_t{1} << 32, half = one / 2;
  r1::Graph g;
  g.n = 4;
  g.row_ptr = {0, 1, 3, 4, 4};
  g.col = {1, 0, 2, 1};
  g.w = {one, one, half, half};
  g.degree = {static_cast<std::uint64_t>(one), static_cast<std::uint64_t>(one + half), static_cast<std::uint64_t>(half), 0};
  return g;
}

TEST(Clifford, GraphContextOnAPath) {
  const r1::Graph g = small_graph();
  const Rows h = random_rows(31, 4, 3);
  // Dense normalized Laplacian with degrees 1, 1.5, 0.5, 0.
  const double a[4][4] = {{0, 1, 0, 0}, {1, 0, 0.5, 0}, {0, 0.5, 0, 0}, {0, 0, 0, 0}};
  const double deg[4] = {1, 1.5, 0.5, 0};
  const auto c = cl::graph_context(g, h);
  ASSERT_TRUE(c.is_ok());
  for (std::uint32_t i = 0; i < 4; ++i)
    for (std::uint32_t ch = 0; ch < 3; ++ch) {
      double lh = h.at(i, ch);
      for (std::uint32_t j = 0; j < 4; ++j)
        if (a[i][j] != 0) lh -= a[i][j] / std::sqrt(deg[i] * deg[j]) * h.at(j, ch);
      EXPECT_NEAR(c->at(i, ch), lh - h.at(i, ch), 1e-12);
    }
  // The isolated particle: L H = H there, so C = H - H = 0 exactly.
  for (std::uint32_t ch = 0; ch < 3; ++ch) EXPECT_EQ(c->at(3, ch), 0.0);
}

TEST(Clifford, GraphContextFromACallback) {
  const Rows h = random_rows(41, 5, 4);
  const cl::LaplacianAction twice = [](const Rows& x) -> r1::Result<Rows> {
    Rows y = x;
    for (double& v : y.v) v *= 2;
    return y;
  };
  const auto c = cl::graph_context(h, twice);  // 2H - H = H exactly
  ASSERT_TRUE(c.is_ok());
  EXPECT_TRUE(same_bytes(*c, h));
  const cl::LaplacianAction wrong = [](const Rows& x) -> r1::Result<Rows> { return cl::zeros(x.n, x.d + 1); };
  EXPECT_EQ(cl::graph_context(h, wrong).status().kind(), r1::ErrorKind::kInput);
  const cl::LaplacianAction failing = [](const Rows&) -> r1::Result<Rows> { return r1::Status::internal("boom"); };
  EXPECT_EQ(cl::graph_context(h, failing).status().kind(), r1::ErrorKind::kInternal);
  EXPECT_EQ(cl::graph_context(small_graph(), h).status().kind(), r1::ErrorKind::kInput);  // 5 rows, 4 particles
  r1::Graph broken = small_graph();
  broken.col[0] = 9;
  EXPECT_EQ(cl::graph_context(broken, random_rows(1, 4, 2)).status().kind(), r1::ErrorKind::kInput);
}

}  // namespace
