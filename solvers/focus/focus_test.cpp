// Focus phi*: exact conservation and positivity, PageRank and heat kernel against independent dense
// references (Eigen), Bessel coefficients against Boost.Math, T(eps), determinism, symmetry
// (R1-FOC-001..091).
#include "r1/solvers/focus.hpp"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <Eigen/Dense>
#include <boost/math/special_functions/bessel.hpp>
#include <boost/multiprecision/cpp_bin_float.hpp>
#include <boost/multiprecision/cpp_int.hpp>
#include <unsupported/Eigen/MatrixFunctions>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <string>
#include <vector>

#include "apportion.hpp"
#include "focus_operators.hpp"
#include "heat_kernel.hpp"
#include "r1/reference/generate.hpp"
#include "r1/reference/graph_build.hpp"
#include "r1/reference/snapshot_builder.hpp"

namespace {

using r1::Graph;
using r1::Q32;
using r1::TriKernelParams;

constexpr std::int64_t ONE = std::int64_t{1} << 32;
constexpr double ULP = 0x1p-32;

// ---- graphs -------------------------------------------------------------------------------------

struct L {
  int from, to;
  std::uint64_t weight;
};

// Particles "v<i>" numbered by first appearance; a particle seen only in a self-loop is isolated.
Graph graph_of(const std::vector<L>& links) {
  r1::SnapshotBuilder b("test");
  b.snapshot().config = r1::text_input_config();
  for (const auto& l : links) {
    r1::Link k;
    k.height = 1;
    k.amount = static_cast<r1::u128>(l.weight) << 32;
    k.from = b.particle_by_name("v" + std::to_string(l.from));
    k.to = b.particle_by_name("v" + std::to_string(l.to));
    b.add_link(k);
  }
  auto s = b.finish();
  EXPECT_TRUE(s.is_ok());
  auto g = r1::build_graph(*s);
  EXPECT_TRUE(g.is_ok()) << g.status().message();
  return std::move(g).value();
}

Graph generated(r1::GenKind kind, std::int64_t n, std::optional<std::int64_t> m = {}) {
  r1::GenParams p;
  p.kind = kind;
  if (kind != r1::GenKind::kCrystal) p.n = n;
  p.m = m;
  auto s = r1::generate(p);
  EXPECT_TRUE(s.is_ok()) << s.status().message();
  auto g = r1::build_graph(*s);
  EXPECT_TRUE(g.is_ok()) << g.status().message();
  return std::move(g).value();
}

// A random snapshot: up to 30 particles, self-loops (isolated particles), several components,
// dangling sources, parallel links with weights 1..8. RapidCheck scales inRange by the test size
// (at size 0 every draw is the minimum, so all links would be self-loops): when no link joins two
// particles, one link v0 -> v1 is appended, because focus needs a positive total degree.
Graph random_graph() {
  const int n = *rc::gen::inRange(2, 30);
  const int m = *rc::gen::inRange(1, 60);
  std::vector<L> links;
  for (int i = 0; i < m; ++i)
    links.push_back({*rc::gen::inRange(0, n), *rc::gen::inRange(0, n), *rc::gen::inRange<std::uint64_t>(1, 9)});
  bool any = false;
  for (const auto& l : links) any = any || l.from != l.to;
  if (!any) links.push_back({0, 1, 1});
  return graph_of(links);
}

TriKernelParams random_params() {
  TriKernelParams p;
  const std::int64_t a = *rc::gen::inRange<std::int64_t>(0, ONE + 1);
  const std::int64_t b = *rc::gen::inRange<std::int64_t>(0, ONE - a + 1);
  p.lambda_d = Q32::from_raw(a);
  p.lambda_s = Q32::from_raw(b);
  p.lambda_h = Q32::from_raw(ONE - a - b);
  p.teleport = Q32::from_raw(*rc::gen::inRange<std::int64_t>(0, ONE + 1));
  p.mu = Q32::from_raw(*rc::gen::inRange<std::int64_t>(1, 8 * ONE));
  p.tau = Q32::from_raw(*rc::gen::inRange<std::int64_t>(1, 6 * ONE));
  p.chebyshev_degree = *rc::gen::inRange<std::uint32_t>(1, 12);
  p.max_steps = *rc::gen::inRange<std::uint32_t>(1, 25);  // keeps the property fast
  return p;
}

// A measured value for RecordProperty, in scientific notation (std::to_string prints 0.000000).
std::string sci(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3e", x);
  return buf;
}

void expect_on_simplex(const std::vector<Q32>& phi) {
  std::int64_t sum = 0;
  for (const Q32 q : phi) {
    ASSERT_GE(q.raw, 1);
    sum += q.raw;
  }
  ASSERT_EQ(sum, ONE);
}

// ---- dense references (independent of the code under test: plain Eigen on exact rationals) -------

using MatL = Eigen::Matrix<long double, Eigen::Dynamic, Eigen::Dynamic>;
using VecL = Eigen::Matrix<long double, Eigen::Dynamic, 1>;

struct Dense {
  MatL a0, w;   // directed A0 and symmetric A_sym, value scale
  VecL degree;  // row sums of w
};

Dense dense_of(const Graph& g) {
  Dense d{MatL::Zero(g.n, g.n), MatL::Zero(g.n, g.n), VecL::Zero(g.n)};
  for (std::uint32_t i = 0; i < g.n; ++i) {
    for (auto k = g.row_ptr[i]; k < g.row_ptr[i + 1]; ++k) d.w(i, g.col[k]) = static_cast<long double>(g.w[k]) / ONE;
    for (auto k = g.out_ptr[i]; k < g.out_ptr[i + 1]; ++k) d.a0(i, g.out_col[k]) = static_cast<long double>(g.out_w[k]) / ONE;
  }
  d.degree = d.w.rowwise().sum();
  return d;
}

// Personalised PageRank with the stake-weighted prior, solved directly:
// x = (1 - t)(P^T x + (dangling . x) u) + t u  <=>  (I - (1 - t) M) x = t u.
VecL pagerank(const Graph& g, long double t) {
  const Dense d = dense_of(g);
  const VecL u = d.degree / d.degree.sum();
  MatL m = MatL::Zero(g.n, g.n);
  for (std::uint32_t p = 0; p < g.n; ++p) {
    const long double out = d.a0.row(p).sum();
    if (out > 0) {
      for (std::uint32_t q = 0; q < g.n; ++q) m(q, p) = d.a0(p, q) / out;
    } else {
      m.col(p) = u;  // dangling: mass to the prior
    }
  }
  const MatL a = MatL::Identity(g.n, g.n) - (1 - t) * m;
  return a.fullPivLu().solve(t * u);
}

// exp(-tau L_rw) x with L_rw = I - A D^-1, by Eigen's Pade matrix exponential. An isolated
// particle j is a fixed point of the walk (N(j, j) = 1, R1-FOC-041), so its column of L_rw is 0
// and the heat leaves its mass alone.
Eigen::VectorXd heat_dense(const Graph& g, double tau, const Eigen::VectorXd& x) {
  const Dense d = dense_of(g);
  Eigen::MatrixXd lrw = Eigen::MatrixXd::Identity(g.n, g.n);
  for (std::uint32_t j = 0; j < g.n; ++j) {
    if (d.degree(j) == 0) {
      lrw(j, j) = 0.0;
      continue;
    }
    for (std::uint32_t i = 0; i < g.n; ++i) lrw(i, j) -= static_cast<double>(d.w(i, j) / d.degree(j));
  }
  const Eigen::MatrixXd h = (-tau * lrw).exp();
  return h * x;
}

// ---- apportionment and projection ------------------------------------------------------------------

TEST(FocusApportion, HandExamples) {
  // 10 over 1:1:1 -> 3.33 each; the remainder unit goes to the lowest index.
  EXPECT_EQ(r1::apportion(10, std::vector<std::uint64_t>{1, 1, 1}), (std::vector<std::int64_t>{4, 3, 3}));
  // 7 over 0:1:2 -> 0, 2.33, 4.67: the largest remainder (0.67) wins; zero weight gets nothing.
  EXPECT_EQ(r1::apportion(7, std::vector<std::uint64_t>{0, 1, 2}), (std::vector<std::int64_t>{0, 2, 5}));
  // All zero: equal weights.
  EXPECT_EQ(r1::apportion(5, std::vector<std::uint64_t>{0, 0}), (std::vector<std::int64_t>{3, 2}));
  EXPECT_THROW(r1::apportion(5, std::vector<std::uint64_t>{}), std::invalid_argument);
}

// Against exact rationals: shares sum to the total, each is floor or ceiling of its exact share,
// and every rounded-up share has a remainder at least that of every rounded-down one.
RC_GTEST_PROP(FocusApportion, LargestRemainderAgainstRationals, ()) {
  using boost::multiprecision::cpp_int;
  const auto n = *rc::gen::inRange<std::size_t>(1, 40);
  // Totals up to 2^63 and weights from tiny to 2^64 (sums below and above 2^64).
  const auto total = *rc::gen::arbitrary<bool>() ? *rc::gen::inRange<std::uint64_t>(0, std::uint64_t{1} << 40)
                                                 : *rc::gen::arbitrary<std::uint64_t>() >> 1;
  const auto big = *rc::gen::inRange(0, 3);
  std::vector<std::uint64_t> w(n);
  for (auto& x : w)
    x = big == 0 ? *rc::gen::inRange<std::uint64_t>(0, 4)
                 : big == 1 ? *rc::gen::arbitrary<std::uint64_t>() >> 8 : *rc::gen::arbitrary<std::uint64_t>();
  const auto out = r1::apportion(total, w);
  cpp_int sum_w = 0;
  for (const auto x : w) sum_w += x;
  const bool equal = sum_w == 0;
  if (equal) sum_w = n;
  std::int64_t sum = 0;
  cpp_int min_up = -1, max_down = -1;
  for (std::size_t i = 0; i < n; ++i) {
    const cpp_int exact = cpp_int(total) * (equal ? 1 : w[i]);
    const cpp_int q = exact / sum_w, r = exact % sum_w;
    RC_ASSERT(cpp_int(out[i]) == q || cpp_int(out[i]) == q + 1);
    if (cpp_int(out[i]) == q + 1) {
      RC_ASSERT(r != 0);
      if (min_up < 0 || r < min_up) min_up = r;
    } else if (r > max_down) {
      max_down = r;
    }
    sum += out[i];
  }
  RC_ASSERT(sum == static_cast<std::int64_t>(total));
  if (min_up >= 0) RC_ASSERT(min_up >= max_down);
}

// From 4096 weights apportion_into takes its fast path (double estimates made exact, a bucketed
// threshold): the shares are apportion_into_plain's, every one, with heavy ties (few distinct
// weights, as integer degrees give), spread weights, zeros, and totals from tiny to 2^40 and
// beyond (where the plain path runs).
RC_GTEST_PROP(FocusApportion, FastPathIsThePlainOneShareForShare, ()) {
  const auto n = *rc::gen::inRange<std::size_t>(4096, 12000);
  const int mode = *rc::gen::inRange(0, 4);
  const std::uint64_t cap = std::uint64_t{1} << *rc::gen::inRange(1, 51);  // sums below 2^64 mostly
  std::vector<std::uint64_t> w(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint64_t r = *rc::gen::arbitrary<std::uint64_t>();
    if (mode == 0) w[i] = (r % 7) << 32;                 // few distinct values: degrees of unit links
    else if (mode == 1) w[i] = r % cap;                   // spread
    else if (mode == 2) w[i] = r % 3 == 0 ? 0 : r % cap;  // a third zero
    else w[i] = r;                                        // sums beyond 2^64: the plain path
  }
  const int t = *rc::gen::inRange(0, 4);
  const std::uint64_t total = t == 0 ? std::uint64_t{1} << 32
                              : t == 1 ? *rc::gen::inRange<std::uint64_t>(0, 100000)
                              : t == 2 ? *rc::gen::inRange<std::uint64_t>(0, std::uint64_t{1} << 40)
                                       : *rc::gen::arbitrary<std::uint64_t>() >> 1;
  std::vector<std::int64_t> fast(n), plain(n);
  r1::focus::ApportionScratch a, b;
  r1::focus::apportion_into(total, w, fast, a);
  r1::focus::apportion_into_plain(total, w, plain, b);
  RC_ASSERT(fast == plain);
}

// Equal weights take a closed form (T / n each, one more for the first T mod n): the plain
// algorithm's shares at every size, zero weights and totals up to 2^63 included.
RC_GTEST_PROP(FocusApportion, EqualWeightsAreThePlainShares, ()) {
  const auto n = *rc::gen::inRange<std::size_t>(1, 6000);
  const int mode = *rc::gen::inRange(0, 3);
  const std::uint64_t v = mode == 0 ? 0 : mode == 1 ? std::uint64_t{1} << 32 : *rc::gen::arbitrary<std::uint64_t>() >> 33;
  const std::vector<std::uint64_t> w(n, v);
  const std::uint64_t total = *rc::gen::inRange(0, 2) == 0 ? std::uint64_t{1} << 32 : *rc::gen::arbitrary<std::uint64_t>() >> 1;
  std::vector<std::int64_t> fast(n), plain(n);
  r1::focus::ApportionScratch a, b;
  r1::focus::apportion_into(total, w, fast, a);
  r1::focus::apportion_into_plain(total, w, plain, b);
  RC_ASSERT(fast == plain);
}

RC_GTEST_PROP(FocusProjection, ExactSumPositiveIdempotent, ()) {
  const auto n = *rc::gen::inRange<std::size_t>(1, 200);
  std::vector<Q32> v(n);
  const int mode = *rc::gen::inRange(0, 3);
  for (auto& q : v) {
    if (mode == 0) q = Q32::from_raw(*rc::gen::arbitrary<std::int64_t>());  // anything, any sign
    else if (mode == 1) q = Q32::from_raw(*rc::gen::inRange<std::int64_t>(-5, 5));  // all tiny
    else q = Q32::from_raw(*rc::gen::inRange<std::int64_t>(0, 3 * ONE / static_cast<std::int64_t>(n)));
  }
  const auto phi = r1::project_to_simplex_q32(v);
  expect_on_simplex(phi);
  RC_ASSERT(r1::project_to_simplex_q32(phi) == phi);  // the identity on the simplex
}

TEST(FocusProjection, FloorAndUniform) {
  // No raw above 1: uniform, the remainder to the lowest indices.
  const auto phi = r1::project_to_simplex_q32(std::vector<Q32>(3, Q32::zero()));
  EXPECT_EQ(phi[0].raw, 1431655766);
  EXPECT_EQ(phi[1].raw, 1431655765);
  EXPECT_EQ(phi[2].raw, 1431655765);
  // A negative entry keeps its one raw; the rest is shared by excess.
  const auto p2 = r1::project_to_simplex_q32(std::vector<Q32>{Q32::from_int(-3), Q32::from_decimal("0.25"), Q32::from_decimal("0.75")});
  EXPECT_EQ(p2[0].raw, 1);
  EXPECT_EQ(p2[1].raw + p2[2].raw, ONE - 1);
  EXPECT_NEAR(static_cast<double>(p2[2].raw) / static_cast<double>(p2[1].raw), 3.0, 1e-8);
  EXPECT_THROW(r1::project_to_simplex_q32(std::vector<Q32>{}), std::invalid_argument);
}

TEST(FocusProjection, FromF64) {
  const auto q = r1::simplex_from_f64(std::vector<double>{0.5, 0.25, 0.25});
  ASSERT_TRUE(q.is_ok());
  EXPECT_EQ((*q)[0].raw, ONE / 2);
  EXPECT_EQ((*q)[1].raw, ONE / 4);
  EXPECT_FALSE(r1::simplex_from_f64(std::vector<double>{0.5, std::nan("")}).is_ok());
  EXPECT_FALSE(r1::simplex_from_f64(std::vector<double>{}).is_ok());
  const auto f = r1::project_to_simplex_f64(std::vector<double>{-1.0, 1.0, 3.0});
  EXPECT_EQ(f[0], 0x1p-32 / (4.0 + 0x1p-32));
  EXPECT_DOUBLE_EQ(f[2], 3.0 * f[1]);
}

// ---- parameters and T(eps) ---------------------------------------------------------------------------

TEST(FocusParams, Validation) {
  TriKernelParams p;
  EXPECT_TRUE(r1::validate_tri_kernel_params(p).is_ok());
  auto expect_bad = [](TriKernelParams q, const char* what) {
    const auto s = r1::validate_tri_kernel_params(q);
    EXPECT_FALSE(s.is_ok()) << what;
    EXPECT_EQ(s.kind(), r1::ErrorKind::kInput);
    EXPECT_NE(s.message().find(what), std::string::npos) << s.message();
  };
  TriKernelParams q = p;
  q.lambda_h = Q32::from_raw(q.lambda_h.raw + 1);  // sum one ulp above 1
  expect_bad(q, "exactly 1");
  q = p;
  q.lambda_d = Q32::from_decimal("-0.1");
  expect_bad(q, "lambda_d");
  q = p;
  q.teleport = Q32::from_decimal("1.5");
  expect_bad(q, "teleport");
  q = p;
  q.mu = Q32::zero();
  expect_bad(q, "mu");
  q = p;
  q.tau = Q32::from_int(65);
  expect_bad(q, "tau");
  q = p;
  q.eps = Q32::one();
  expect_bad(q, "eps");
  q = p;
  q.max_steps = 0;
  expect_bad(q, "max_steps");
  q = p;
  q.chebyshev_degree = 33;
  expect_bad(q, "chebyshev_degree");
  const Graph g = graph_of({{0, 1, 1}, {1, 2, 1}});
  EXPECT_EQ(r1::compute_focus_q32(g, p, std::nan("")).status().kind(), r1::ErrorKind::kInput);
  EXPECT_EQ(r1::compute_focus_f64(g, p, 2.5).status().kind(), r1::ErrorKind::kInput);
  Graph broken = g;
  broken.degree[0] += 1;
  EXPECT_EQ(r1::compute_focus_q32(broken, p, 0).status().kind(), r1::ErrorKind::kInput);
  broken = g;
  broken.out_ptr.pop_back();
  EXPECT_EQ(r1::compute_focus_f64(broken, p, 0).status().kind(), r1::ErrorKind::kInput);
}

TEST(FocusSteps, HandComputedKappas) {
  const Q32 eps = Q32::from_decimal("0.000001");
  // log2(2^-20) / log2(1/2) = 20 exactly: log2 is exact at powers of two.
  EXPECT_EQ(r1::steps_for_kappa(Q32::from_decimal("0.5"), Q32::from_raw(ONE >> 20), 500), 20u);
  EXPECT_EQ(r1::steps_for_kappa(Q32::from_decimal("0.25"), Q32::from_raw(ONE >> 20), 500), 10u);
  // ln(1e-6) / ln(0.85) = 85.0086 -> 86 (PageRank alone: kappa = 1 - t).
  EXPECT_EQ(r1::steps_for_kappa(Q32::from_decimal("0.85"), eps, 500), 86u);
  // ln(1e-6) / ln(0.9) = 131.13 -> 132, and the cap.
  EXPECT_EQ(r1::steps_for_kappa(Q32::from_decimal("0.9"), eps, 500), 132u);
  EXPECT_EQ(r1::steps_for_kappa(Q32::from_decimal("0.9"), eps, 100), 100u);
  EXPECT_EQ(r1::steps_for_kappa(Q32::one(), eps, 500), 500u);
  EXPECT_EQ(r1::steps_for_kappa(Q32::from_raw(ONE - 1), eps, 500), 500u);
  EXPECT_EQ(r1::steps_for_kappa(Q32::zero(), eps, 500), 1u);
  EXPECT_EQ(r1::steps_for_kappa(Q32::from_raw(1), eps, 500), 1u);  // 2^-32 contracts in one step
}

TEST(FocusSteps, DefaultPlanOnRing) {
  // Ring: every degree 2, ||L|| = 4. kappa = RNE(0.5 * 0.85) + RNE(0.3 * 4 / 5) + RNE(0.2 * e^0)
  // = 1825361101 + 1030792151 + 858993459 raws = 0.865; ln(1e-6) / ln(0.865) = 95.26 -> 96.
  const Graph g = generated(r1::GenKind::kRing, 64);
  const auto plan = r1::plan_focus_steps(g, TriKernelParams{}, 0.0);
  ASSERT_TRUE(plan.is_ok());
  EXPECT_EQ(plan->kappa.raw, std::int64_t{1825361101} + 1030792151 + 858993459);
  EXPECT_EQ(plan->norm_l, 4.0);
  EXPECT_EQ(plan->steps, 96u);
  // lambda2 = 2 (the largest possible): the heat term is 0.2 e^-2 = 0.0270671, kappa = 0.6920671.
  const auto p2 = r1::plan_focus_steps(g, TriKernelParams{}, 2.0);
  ASSERT_TRUE(p2.is_ok());
  EXPECT_NEAR(p2->kappa.to_double(), 0.425 + 0.24 + 0.2 * 0.1353352832366127, 3 * ULP);
  EXPECT_EQ(p2->steps, 38u);  // 13.8155 / 0.368117 = 37.53
}

// ---- heat kernel ---------------------------------------------------------------------------------------

// Against Boost.Math's modified Bessel functions in 50-digit arithmetic (about 166 bits). What the
// heat kernel needs (R1-FOC-044): the Q32 coefficient is the correctly rounded value (it multiplies
// Q32 vectors, so only its 32 fractional bits matter); the double is the nearest double for every
// c_k >= 2^-180, and below that the nearest double of a value within 2^-240 of c_k. That is the
// property that matters: a coefficient error of 2^-240 moves h_i by at most 2^-240 |t_k,i| <=
// 2^-208 (|t_k,i| <= sqrt(d_max / d_min) < 2^32 for Q32 weights), far below the 2^-32 floor that
// the fp64 phi resolves (R1-FOC-053). Correct rounding of doubles below 2^-180 would need more
// than 256 fractional bits for no effect on any result.
TEST(FocusHeat, CoefficientsAgainstBoostBessel) {
  using F = boost::multiprecision::cpp_bin_float_50;
  for (const char* tau_text : {"0.0625", "0.3", "1", "2", "2.0000000003", "3", "4.5", "64"}) {
    const Q32 tau = Q32::from_decimal(tau_text);
    const auto c = r1::heat_coefficients(tau, 32);
    const std::uint32_t m = static_cast<std::uint32_t>((tau.raw + 2 * ONE - 1) / (2 * ONE));
    EXPECT_EQ(c.substeps, m) << tau_text;
    ASSERT_EQ(c.q32.size(), 33u);
    const F sigma = F(tau.raw) / F(ONE) / m;
    for (std::uint32_t k = 0; k <= 32; ++k) {
      const F ref = (k == 0 ? 1 : 2) * exp(-sigma) * boost::math::cyl_bessel_i(k, sigma);
      const F scaled = ref * F(ONE);
      const F fl = floor(scaled);
      const F frac = scaled - fl;
      // Skip the (never met) case of a value within 10^-30 of a rounding midpoint.
      ASSERT_GT(abs(frac - F(0.5)), F(1e-30));
      const std::int64_t want = fl.convert_to<std::int64_t>() + (frac > F(0.5) ? 1 : 0);
      EXPECT_EQ(c.q32[k].raw, want) << "tau " << tau_text << " k " << k;
      if (ref >= F(0x1p-180)) {
        EXPECT_EQ(c.f64[k], ref.convert_to<double>()) << "tau " << tau_text << " k " << k;
      } else {
        // The nearest double of a value within 2^-240 of c_k: half an ulp of the double plus that.
        const double ulp = std::max(std::nextafter(c.f64[k], 1.0) - c.f64[k], c.f64[k] - std::nextafter(c.f64[k], 0.0));
        EXPECT_LE(abs(F(c.f64[k]) - ref), F(ulp) / 2 + F(0x1p-240)) << "tau " << tau_text << " k " << k;
      }
      // And the double-precision Boost.Math value, a second independent implementation.
      const double sd = sigma.convert_to<double>();
      EXPECT_NEAR(c.f64[k], (k == 0 ? 1 : 2) * std::exp(-sd) * boost::math::cyl_bessel_i(k, sd), 1e-15);
    }
  }
  EXPECT_EQ(r1::heat_coefficients(Q32::from_int(2), 8).substeps, 1u);
  EXPECT_EQ(r1::heat_coefficients(Q32::from_raw(2 * ONE + 1), 8).substeps, 2u);
  EXPECT_THROW(r1::heat_coefficients(Q32::zero(), 8), std::invalid_argument);
}

// 2 e^-sigma sum_{k > K} I_k(sigma): the truncation of one sub-step in the D^(-1/2)-weighted norm.
double chebyshev_tail(double sigma, std::uint32_t degree) {
  double s = 0;
  for (std::uint32_t k = degree + 1; k <= degree + 40; ++k) s += boost::math::cyl_bessel_i(k, sigma);
  return 2 * std::exp(-sigma) * s;
}

struct HeatCase {
  std::vector<L> links;
  double tau;
  std::uint32_t degree;
};

// fp64 heat against Eigen's matrix exponential within the Chebyshev truncation bound, and Q32 heat
// against fp64 heat within the rounding bound derived in the comment below.
TEST(FocusHeat, AgainstDenseMatrixExponential) {
  const std::vector<HeatCase> cases = {
      {{{0, 1, 1}, {1, 2, 2}, {2, 3, 1}, {3, 0, 3}, {0, 2, 1}, {4, 4, 1}, {5, 6, 2}}, 1.0, 8},  // isolated v4, two components
      {{{0, 1, 1}, {0, 2, 1}, {0, 3, 1}, {0, 4, 1}, {0, 5, 1}, {1, 2, 5}}, 1.0, 8},            // star-ish: degrees 1..6
      {{{0, 1, 1}, {1, 2, 1}, {2, 3, 1}, {3, 4, 1}, {4, 5, 1}, {5, 0, 1}}, 4.5, 8},            // bipartite ring: lambda_max = 2
      {{{0, 1, 3}, {1, 2, 1}, {2, 0, 2}, {2, 3, 1}, {3, 4, 7}, {4, 5, 1}, {5, 3, 1}}, 2.0, 4},  // sigma = 2, K = 4: visible truncation
  };
  for (const auto& hc : cases) {
    const Graph g = graph_of(hc.links);
    TriKernelParams p;
    p.tau = Q32::from_double(hc.tau);
    p.chebyshev_degree = hc.degree;
    auto q_ops = r1::focus::OperatorsQ32::build(g, p, false);
    auto f_ops = r1::focus::OperatorsF64::build(g, p, false);
    ASSERT_TRUE(q_ops.is_ok() && f_ops.is_ok());
    const auto coeff = r1::heat_coefficients(p.tau, hc.degree);
    // A non-uniform positive vector on the simplex.
    std::vector<Q32> xq(g.n);
    for (std::uint32_t i = 0; i < g.n; ++i) xq[i] = Q32::from_raw(ONE / 64 * (i % 5 + 1));
    xq = r1::project_to_simplex_q32(xq);
    std::vector<double> xf(g.n);
    Eigen::VectorXd xe(g.n);
    for (std::uint32_t i = 0; i < g.n; ++i) xe(i) = xf[i] = xq[i].to_double();
    std::vector<Q32> hq;
    std::vector<double> hf;
    r1::focus::heat_q32(*q_ops, coeff, xq, hq);
    r1::focus::heat_f64(*f_ops, coeff, xf, hf);
    const Eigen::VectorXd ref = heat_dense(g, p.tau.to_double(), xe);

    // Bounds. With N = D^(1/2) S D^(-1/2) (S symmetric, spectrum in [-1, 1]; isolated particles
    // count as d = 1), T_k(N) has norm <= 1 in nu(x) = ||D^(-1/2) x||_2. Truncation per sub-step:
    // eps_K(sigma) nu(x); over m sub-steps m eps (1 + eps)^m nu(x); and |x_i| <= sqrt(d_max) nu(x).
    double dmin = 1e300, dmax = 0, nu = 0, x2 = 0;
    std::uint64_t max_count = 0;
    for (std::uint32_t i = 0; i < g.n; ++i) {
      const double d = g.degree[i] == 0 ? 1.0 : static_cast<double>(g.degree[i]) * ULP;
      dmin = std::min(dmin, d);
      dmax = std::max(dmax, d);
      nu += xf[i] * xf[i] / d;
      x2 += xf[i] * xf[i];
      max_count = std::max<std::uint64_t>(max_count, g.row_ptr[i + 1] - g.row_ptr[i]);
    }
    nu = std::sqrt(nu);
    x2 = std::sqrt(x2);
    const double m = coeff.substeps, sigma = p.tau.to_double() / m;
    const double tail = chebyshev_tail(sigma, hc.degree);
    const double trunc_bound = std::sqrt(dmax) * m * tail * std::pow(1 + tail, m) * nu + 1e-14;
    // Rounding (Q32 vs fp64): recurrence errors e_j = 2 (N^ - N) t_j + r_j with |N^ - N| < 1 ulp per
    // entry (apportioned shares) and |r_j| <= 1/2 ulp; |t_j,i| <= t_max = sqrt(dmax / dmin) ||x||_2.
    // They propagate through U_(k-j-1)(N), of nu-norm <= k - j, so nu(delta_k) <= k(k+1)/2 nu(e);
    // the result adds sum_k c_k nu(delta_k) plus the coefficient and final roundings.
    const double t_max = std::sqrt(dmax / dmin) * x2;
    const double e_entry = (2.0 * static_cast<double>(max_count) * t_max + 0.5) * ULP;
    double weight = 0;
    for (std::uint32_t k = 0; k <= hc.degree; ++k) weight += coeff.f64[k] * k * (k + 1) / 2.0;
    const double round_bound =
        m * (std::sqrt(dmax / dmin) * std::sqrt(static_cast<double>(g.n)) * e_entry * weight + (hc.degree + 2) * 0.5 * ULP * t_max + 0.5 * ULP) * (1 + tail);
    double err_f = 0, err_q = 0;
    for (std::uint32_t i = 0; i < g.n; ++i) {
      err_f = std::max(err_f, std::abs(hf[i] - ref(i)));
      err_q = std::max(err_q, std::abs(hq[i].to_double() - hf[i]));
    }
    EXPECT_LE(err_f, trunc_bound) << "tau " << hc.tau << " K " << hc.degree;
    EXPECT_LE(err_q, round_bound) << "tau " << hc.tau << " K " << hc.degree;
    const std::string id = std::to_string(&hc - cases.data());
    RecordProperty("heat_err_f64_case" + id, sci(err_f) + " <= " + sci(trunc_bound));
    RecordProperty("heat_err_q32_case" + id, sci(err_q) + " <= " + sci(round_bound));
  }
}

// The operators against dense arithmetic on the same (apportioned) Q32 matrices and on exact ones.
TEST(FocusOperators, DiffusionAndSpringsAgainstDense) {
  const Graph g = graph_of({{0, 1, 2}, {1, 2, 1}, {2, 0, 5}, {0, 3, 1}, {3, 3, 1}, {4, 1, 1}, {5, 5, 1}});
  TriKernelParams p;
  auto ops = r1::focus::OperatorsQ32::build(g, p, false);
  ASSERT_TRUE(ops.is_ok());
  const Dense d = dense_of(g);
  std::vector<Q32> phi(g.n);
  for (std::uint32_t i = 0; i < g.n; ++i) phi[i] = Q32::from_raw(ONE / 16 * (i + 1));
  phi = r1::project_to_simplex_q32(phi);
  std::vector<Q32> dq, sq;
  ops->diffusion(phi, dq);
  ops->springs(phi, sq);
  const long double t = static_cast<long double>(p.teleport.to_double()), mu = static_cast<long double>(p.mu.to_double());
  const VecL u = d.degree / d.degree.sum();
  long double dangling = 0;
  for (std::uint32_t q = 0; q < g.n; ++q)
    if (d.a0.row(q).sum() == 0) dangling += static_cast<long double>(phi[q].to_double());
  for (std::uint32_t q = 0; q < g.n; ++q) {
    long double y = 0, r = 0;
    for (std::uint32_t s = 0; s < g.n; ++s) {
      const long double out = d.a0.row(s).sum();
      if (out > 0) y += static_cast<long double>(phi[s].to_double()) * d.a0(s, q) / out;
      r += d.w(q, s) * static_cast<long double>(phi[s].to_double());
    }
    const long double dq_exact = (1 - t) * (y + dangling * u(q)) + t * u(q);
    const long double sq_exact = (mu / g.n + r) / (mu + d.degree(q));
    // Shares of P and u are within 1 ulp of exact; three roundings of 1/2 ulp; out-degree <= 2.
    EXPECT_LE(std::abs(static_cast<long double>(dq[q].to_double()) - dq_exact), 4.5L * static_cast<long double>(ULP)) << q;
    // a = RNE(mu / n) and the final division: 1 ulp.
    EXPECT_LE(std::abs(static_cast<long double>(sq[q].to_double()) - sq_exact), 1.0L * static_cast<long double>(ULP)) << q;
  }
}

// ---- the iteration ---------------------------------------------------------------------------------------

// A5 on random graphs with random parameters: raws sum to exactly 2^32, every raw >= 1, and the
// fp64 phi is positive and sums to 1 within rounding.
RC_GTEST_PROP(FocusIteration, ConservationAndPositivity, ()) {
  const Graph g = random_graph();
  const TriKernelParams p = random_params();
  const double lambda2 = *rc::gen::inRange(0, 2001) / 1000.0;
  const auto q = r1::compute_focus_q32(g, p, lambda2);
  RC_ASSERT(q.is_ok());
  std::int64_t sum = 0;
  for (const Q32 x : q->phi) {
    RC_ASSERT(x.raw >= 1);
    sum += x.raw;
  }
  RC_ASSERT(sum == ONE);
  RC_ASSERT(q->steps >= 1u && q->steps <= p.max_steps);
  RC_ASSERT(q->cyberank.size() == std::min<std::size_t>(g.n, r1::kCyberankPlaces));
  // cyberank: the leading places, each particle once, phi descending, ties by the lower index
  // (R1-FOC-070).
  std::vector<char> seen(g.n, 0);
  for (std::size_t k = 0; k < q->cyberank.size(); ++k) {
    const auto b = q->cyberank[k];
    RC_ASSERT(b < g.n && !seen[b]);
    seen[b] = 1;
    if (k > 0) {
      const auto a = q->cyberank[k - 1];
      RC_ASSERT(q->phi[a] > q->phi[b] || (q->phi[a] == q->phi[b] && a < b));
    }
  }
  const auto f = r1::compute_focus_f64(g, p, lambda2);
  RC_ASSERT(f.is_ok());
  RC_ASSERT(f->steps == q->steps);
  double fs = 0;
  for (const double x : f->phi) {
    RC_ASSERT(x > 0.0);
    fs += x;
  }
  RC_ASSERT(std::abs(fs - 1.0) < 1e-12);
}

// The local update (R1-INC-050..051) on random graphs (dangling sources, isolated particles,
// several components), random parameters, random regions and random positive starts: exact
// conservation, positivity, and the frozen particles' bits.
// The heat kernel on a region's operators runs its loops on the region's rows and carries the
// ring (empty rows, fixed points of the walk) in closed form: the result equals the plain
// Chebyshev recurrence over every local row bit for bit (R1-INC-052).
RC_GTEST_PROP(FocusUpdate, RegionHeatIsThePlainRecurrence, ()) {
  const Graph g = random_graph();
  const TriKernelParams p = random_params();
  std::vector<std::uint32_t> region;
  for (std::uint32_t i = 0; i < g.n; ++i)
    if (*rc::gen::inRange(0, 3) == 0) region.push_back(i);
  if (region.empty()) region.push_back(0);
  std::vector<Q32> phi(g.n);
  for (auto& x : phi) x = Q32::from_raw(*rc::gen::inRange<std::int64_t>(1, ONE));
  std::vector<std::uint32_t> global;
  const auto ops = r1::focus::OperatorsQ32::build_local(g, p, false, region, phi, global);
  RC_ASSERT(ops.is_ok());
  RC_ASSERT(ops->fixed_from() == region.size());
  std::vector<Q32> x(global.size());
  for (std::size_t a = 0; a < global.size(); ++a) x[a] = phi[global[a]];
  const r1::HeatCoefficients coeff = r1::heat_coefficients(p.tau, p.chebyshev_degree);
  std::vector<Q32> fast;
  r1::focus::heat_q32(*ops, coeff, x, fast);
  // The recurrence as R1-FOC-043 writes it, every row through walk_row.
  const std::size_t n = x.size();
  std::vector<Q32> t0 = x, t1(n), t2(n);
  for (std::uint32_t sub = 0; sub < coeff.substeps; ++sub) {
    std::vector<r1::i128> acc(n);
    for (std::size_t i = 0; i < n; ++i) acc[i] = static_cast<r1::i128>(coeff.q32[0].raw) * t0[i].raw;
    if (coeff.q32.size() > 1)
      for (std::uint32_t i = 0; i < n; ++i) {
        t1[i] = Q32::from_raw(r1::focus::round_q32(ops->walk_row(i, t0.data())));
        acc[i] += static_cast<r1::i128>(coeff.q32[1].raw) * t1[i].raw;
      }
    for (std::size_t k = 2; k < coeff.q32.size(); ++k) {
      for (std::uint32_t i = 0; i < n; ++i) {
        t2[i] = Q32::from_raw(r1::focus::round_q32(2 * ops->walk_row(i, t1.data()) - (static_cast<r1::i128>(t0[i].raw) << 32)));
        acc[i] += static_cast<r1::i128>(coeff.q32[k].raw) * t2[i].raw;
      }
      std::swap(t0, t1);
      std::swap(t1, t2);
    }
    for (std::size_t i = 0; i < n; ++i) t0[i] = Q32::from_raw(r1::focus::round_q32(acc[i]));
  }
  RC_ASSERT(fast == t0);
}

// The focus step forms S(phi) and N phi in one pass (R1-FOC-090): springs_and_walk gives
// springs()'s and walk()'s values, serially and on TBB rows, on the whole graph's operators and a
// region's (whose ring rows are empty), and the heat kernel given that N phi is the heat kernel.
RC_GTEST_PROP(FocusOperators, SpringsAndWalkInOnePassAreTheirOwnValues, ()) {
  const Graph g = random_graph();
  const TriKernelParams p = random_params();
  const bool local = *rc::gen::arbitrary<bool>();
  const bool parallel = *rc::gen::arbitrary<bool>();
  std::vector<Q32> phi(g.n);
  for (auto& x : phi) x = Q32::from_raw(*rc::gen::inRange<std::int64_t>(1, ONE));
  std::vector<std::uint32_t> region, global;
  for (std::uint32_t i = 0; i < g.n; ++i)
    if (*rc::gen::inRange(0, 2) == 0) region.push_back(i);
  if (region.empty()) region.push_back(0);
  const auto ops = local ? r1::focus::OperatorsQ32::build_local(g, p, parallel, region, phi, global)
                         : r1::focus::OperatorsQ32::build(g, p, parallel);
  RC_ASSERT(ops.is_ok());
  std::vector<Q32> x = phi;
  if (local) {
    x.resize(global.size());
    for (std::size_t a = 0; a < global.size(); ++a) x[a] = phi[global[a]];
  }
  std::vector<Q32> s, nx, s_alone, nx_alone;
  ops->springs_and_walk(x, s, nx);
  ops->springs(x, s_alone);
  ops->walk(x, nx_alone);
  RC_ASSERT(nx == nx_alone);
  for (std::uint32_t i = 0; i < ops->fixed_from(); ++i) RC_ASSERT(s[i] == s_alone[i]);
  const r1::HeatCoefficients coeff = r1::heat_coefficients(p.tau, p.chebyshev_degree);
  std::vector<Q32> h_given, h_alone;
  r1::focus::heat_q32(*ops, coeff, x, h_given, nullptr, &nx);
  r1::focus::heat_q32(*ops, coeff, x, h_alone);
  RC_ASSERT(h_given == h_alone);
}

RC_GTEST_PROP(FocusUpdate, ConservesPositiveAndFreezesOutside, ()) {
  const Graph g = random_graph();
  const TriKernelParams p = random_params();
  std::vector<Q32> raw(g.n);
  for (auto& x : raw) x = Q32::from_raw(*rc::gen::inRange<std::int64_t>(0, 1 << 20));
  const std::vector<Q32> start = r1::project_to_simplex_q32(raw);
  std::vector<std::uint32_t> region;
  for (std::uint32_t i = 0; i < g.n; ++i)
    if (*rc::gen::inRange(0, 3) == 0) region.push_back(i);
  if (region.empty()) region.push_back(g.n - 1);
  const double lambda2 = *rc::gen::inRange(0, 2001) / 1000.0;
  std::vector<Q32> heat;
  if (p.lambda_h.raw != 0) {
    auto h = r1::heat_term_q32(g, p, start);
    RC_ASSERT(h.is_ok());
    heat = std::move(*h);
  }
  // With the start's exact sum of phi ln phi carried (R1-INC-054) or without it.
  r1::Focus<Q32> from;
  from.phi = start;
  from.heat = heat;
  if (*rc::gen::arbitrary<bool>()) {
    from.plogp.emplace();
    for (const Q32 x : start) from.plogp->add_term(r1::phi_log_phi(x));
  }
  const auto f = r1::update_focus_q32(g, p, lambda2, std::move(from), region);
  RC_ASSERT(f.is_ok());
  // The result's sum is the exact sum over its own phi, carried or not.
  r1::fx::ExactSum plogp;
  for (const Q32 x : f->phi) plogp.add_term(r1::phi_log_phi(x));
  RC_ASSERT(f->plogp == std::optional<r1::fx::ExactSum>(plogp));
  std::vector<char> inside(g.n, 0);
  for (const auto i : region) inside[i] = 1;
  std::int64_t sum = 0;
  for (std::uint32_t i = 0; i < g.n; ++i) {
    RC_ASSERT(f->phi[i].raw >= 1);
    if (!inside[i]) RC_ASSERT(f->phi[i].raw == start[i].raw);
    sum += f->phi[i].raw;
  }
  RC_ASSERT(sum == ONE);
  RC_ASSERT(f->steps >= 1u && f->steps <= p.max_steps);
}

// lambda = (1, 0, 0) is personalised PageRank with the stake-weighted prior. Bound on
// ||phi - x*||_1 (derivation): truncation 2 (1 - t)^T (||phi_0 - x*||_1 <= 2, contraction 1 - t);
// per step the Q32 roundings move ||.||_1 by at most (4n + 2) ulp (y, D: n/2 ulp each; c: 1/2;
// Proj: |sum v - 1| + 2n ulp), accumulated over the contraction: / t; the apportioned P and u
// differ from the exact ones by < 1 ulp per entry, which moves the fixed point by at most
// ((1 - t) max out-degree + n) ulp / t.
struct PageRankError {
  double l1 = 0, bound = 0, max_abs = 0;
};

PageRankError pagerank_error(const Graph& g, const TriKernelParams& p) {
  PageRankError r;
  const auto q = r1::compute_focus_q32(g, p, 0.0);
  if (!q.is_ok()) {
    r.l1 = 1e300;
    return r;
  }
  const long double t = static_cast<long double>(p.teleport.to_double());
  const VecL ref = pagerank(g, t);
  std::uint64_t max_out = 0;
  for (std::uint32_t i = 0; i < g.n; ++i) max_out = std::max(max_out, g.out_ptr[i + 1] - g.out_ptr[i]);
  r.bound = 2 * std::pow(1 - static_cast<double>(t), q->steps) +
            (5.0 * g.n + static_cast<double>(max_out) + 2) * ULP / static_cast<double>(t);
  for (std::uint32_t i = 0; i < g.n; ++i) {
    const double e = std::abs(static_cast<double>(static_cast<long double>(q->phi[i].to_double()) - ref(i)));
    r.l1 += e;
    r.max_abs = std::max(r.max_abs, e);
  }
  return r;
}

TriKernelParams pagerank_params(Q32 eps) {
  TriKernelParams p;
  p.lambda_d = Q32::one();
  p.lambda_s = p.lambda_h = Q32::zero();
  p.eps = eps;
  return p;
}

TEST(FocusIteration, PageRankAgainstDenseSolve) {
  // eps = 2^-32: T = ceil(32 / log2(1 / 0.85)) = 137 steps, truncation 2 * 0.85^137 = 4.6e-10.
  const TriKernelParams p = pagerank_params(Q32::epsilon());
  double max_abs = 0;
  for (const Graph& g : {graph_of({{0, 1, 1}, {1, 2, 1}, {2, 0, 1}, {2, 3, 4}, {4, 3, 1}, {5, 5, 1}, {6, 7, 2}}),
                         generated(r1::GenKind::kBa, 200, 3), generated(r1::GenKind::kPath, 50),
                         generated(r1::GenKind::kStar, 40), generated(r1::GenKind::kRing, 30)}) {
    const auto e = pagerank_error(g, p);
    EXPECT_LE(e.l1, e.bound) << "n " << g.n;
    max_abs = std::max(max_abs, e.max_abs);
    RecordProperty("pagerank_l1_n" + std::to_string(g.n), sci(e.l1) + " <= " + sci(e.bound) + ", max abs " + sci(e.max_abs));
  }
  RecordProperty("pagerank_max_abs_diff", sci(max_abs));
  EXPECT_LT(max_abs, 1e-8);
}

RC_GTEST_PROP(FocusIteration, PageRankOnRandomGraphs, ()) {
  TriKernelParams p = pagerank_params(Q32::from_decimal("0.0000001"));
  p.teleport = Q32::from_raw(*rc::gen::inRange<std::int64_t>(ONE / 20, ONE / 2));
  const auto e = pagerank_error(random_graph(), p);
  RC_ASSERT(e.l1 <= e.bound);
}

// An exact product written from R1-FOC-092's definition alone (an exact i128 row sum, rounded
// once half to even), counting its applications; `fail_after` makes the n-th application fail.
class PlainProduct final : public r1::ExactProduct {
 public:
  PlainProduct(std::span<const std::uint64_t> ptr, std::span<const std::uint32_t> col, std::span<const std::int64_t> val,
               bool identity, int* applications, int fail_after)
      : ptr_(ptr.begin(), ptr.end()), col_(col.begin(), col.end()), val_(val.begin(), val.end()), identity_(identity),
        applications_(applications), fail_after_(fail_after) {}
  r1::Result<std::vector<std::int64_t>> apply(std::span<const std::int64_t> x) override {
    if (++*applications_ == fail_after_) return r1::Status::internal("plain product: failed as asked");
    std::vector<std::int64_t> y(ptr_.size() - 1);
    for (std::size_t i = 0; i + 1 < ptr_.size(); ++i) {
      if (ptr_[i] == ptr_[i + 1]) {
        y[i] = identity_ ? x[i] : 0;
        continue;
      }
      r1::i128 sum = 0;
      for (std::uint64_t k = ptr_[i]; k < ptr_[i + 1]; ++k) sum += static_cast<r1::i128>(val_[k]) * x[col_[k]];
      r1::i128 q = sum >> 32;  // floor
      const r1::i128 rem = sum - q * (r1::i128{1} << 32);
      if (rem > (r1::i128{1} << 31) || (rem == (r1::i128{1} << 31) && (q & 1) != 0)) ++q;
      y[i] = static_cast<std::int64_t>(q);
    }
    return y;
  }

 private:
  std::vector<std::uint64_t> ptr_;
  std::vector<std::uint32_t> col_;
  std::vector<std::int64_t> val_;
  bool identity_;
  int* applications_;
  int fail_after_;
};

r1::ExactProductFactory plain_products(int* applications, int fail_after = 0) {
  return [=](std::span<const std::uint64_t> ptr, std::span<const std::uint32_t> col, std::span<const std::int64_t> val,
             bool identity) -> r1::Result<std::unique_ptr<r1::ExactProduct>> {
    return std::unique_ptr<r1::ExactProduct>(std::make_unique<PlainProduct>(ptr, col, val, identity, applications, fail_after));
  };
}

// R1-FOC-092: the whole-graph products on a backend's exact product (here the plain one above)
// give the row loops' bits: phi, the heat term, cyberank, on graphs with isolated particles,
// dangling sources and several components, and on every parameter set (Chebyshev degree 1..11,
// several sub-steps).
RC_GTEST_PROP(FocusProducts, ABackendsExactProductGivesTheRowLoopsBits, ()) {
  const Graph g = random_graph();
  const TriKernelParams p = random_params();
  const double lambda2 = *rc::gen::inRange(0, 1000) / 1000.0;
  int applications = 0;
  r1::FocusOptions on;
  on.products = plain_products(&applications);
  on.parallel = *rc::gen::arbitrary<bool>();
  on.stop_at_repeat = false;  // every step runs, so every step's products are counted below
  const auto a = r1::compute_focus_q32(g, p, lambda2);
  const auto b = r1::compute_focus_q32(g, p, lambda2, {}, on);
  RC_ASSERT(a.is_ok());
  RC_ASSERT(b.is_ok());
  RC_ASSERT(a->phi == b->phi);
  RC_ASSERT(a->heat == b->heat);
  RC_ASSERT(a->cyberank == b->cyberank);
  RC_ASSERT(a->syntropy == b->syntropy);
  // Every step ran on the products: a diffusion, and K walks per heat sub-step (and the result's
  // heat term once more), when their weights are not 0.
  const std::uint32_t substeps = r1::heat_coefficients(p.tau, p.chebyshev_degree).substeps;
  const int per_heat = p.lambda_h.raw != 0 ? static_cast<int>(substeps * p.chebyshev_degree) : 0;
  RC_ASSERT(applications == static_cast<int>(a->steps) * ((p.lambda_d.raw != 0 ? 1 : 0) + per_heat) + per_heat);
  const auto ha = r1::heat_term_q32(g, p, a->phi);
  const auto hb = r1::heat_term_q32(g, p, a->phi, on);
  RC_ASSERT(ha.is_ok() && hb.is_ok());
  RC_ASSERT(*ha == *hb);
}

TEST(FocusProducts, ADeclinedMatrixKeepsTheRowLoops) {
  const Graph g = generated(r1::GenKind::kBa, 300, 3);
  int applications = 0;
  const r1::ExactProductFactory plain = plain_products(&applications);
  r1::FocusOptions on;
  // Declines the Chebyshev step's matrix (the only one with 2n columns): no product runs.
  on.products = [&](std::span<const std::uint64_t> ptr, std::span<const std::uint32_t> col, std::span<const std::int64_t> val,
                    bool identity) -> r1::Result<std::unique_ptr<r1::ExactProduct>> {
    if (col.size() == g.col.size() + g.n) return std::unique_ptr<r1::ExactProduct>();
    return plain(ptr, col, val, identity);
  };
  const auto a = r1::compute_focus_q32(g, TriKernelParams{}, 0.3);
  const auto b = r1::compute_focus_q32(g, TriKernelParams{}, 0.3, {}, on);
  ASSERT_TRUE(a.is_ok() && b.is_ok());
  EXPECT_EQ(a->phi, b->phi);
  EXPECT_EQ(a->heat, b->heat);
  EXPECT_EQ(applications, 0);
}

TEST(FocusProducts, AFailingProductIsTheStagesInternalError) {
  const Graph g = generated(r1::GenKind::kBa, 300, 3);
  int applications = 0;
  r1::FocusOptions on;
  on.products = plain_products(&applications, 5);
  const auto f = r1::compute_focus_q32(g, TriKernelParams{}, 0.3, {}, on);
  ASSERT_FALSE(f.is_ok());
  EXPECT_EQ(f.status().kind(), r1::ErrorKind::kInternal);
  EXPECT_EQ(f.status().message(), "focus: plain product: failed as asked");
  EXPECT_EQ(applications, 5);
}

TEST(FocusIteration, BitIdenticalRerunsAndParallel) {
  const Graph g = generated(r1::GenKind::kBa, 6000, 4);
  TriKernelParams p;
  const auto a = r1::compute_focus_q32(g, p, 0.3);
  const auto b = r1::compute_focus_q32(g, p, 0.3);
  r1::FocusOptions par;
  par.parallel = true;
  const auto c = r1::compute_focus_q32(g, p, 0.3, {}, par);
  ASSERT_TRUE(a.is_ok() && b.is_ok() && c.is_ok());
  EXPECT_EQ(a->phi, b->phi);
  EXPECT_EQ(a->phi, c->phi);
  EXPECT_EQ(a->cyberank, c->cyberank);
  EXPECT_EQ(a->syntropy, c->syntropy);
  const auto fa = r1::compute_focus_f64(g, p, 0.3);
  const auto fc = r1::compute_focus_f64(g, p, 0.3, {}, par);
  ASSERT_TRUE(fa.is_ok() && fc.is_ok());
  EXPECT_EQ(fa->phi, fc->phi);  // bitwise: the pairwise trees do not depend on threads
  EXPECT_EQ(fa->syntropy, fc->syntropy);
}

// Q32 and fp64 run the same algorithm; they differ by roundings (~ulp per entry and step) damped by
// the contraction, and by the apportioned matrices (< 1 ulp per entry). Measured L1 distances are
// a few 1e-8 (recorded); the bound allows 16 ulp per particle over 1 / (1 - kappa).
TEST(FocusIteration, Q32AgreesWithF64) {
  for (const auto& [g, lambda2] : {std::pair{generated(r1::GenKind::kBa, 2000, 3), 0.2},
                                   std::pair{generated(r1::GenKind::kSbm, 600), 0.0},
                                   std::pair{graph_of({{0, 1, 1}, {1, 2, 3}, {2, 0, 1}, {3, 4, 1}, {5, 5, 1}, {4, 6, 2}}), 0.0}}) {
    const auto q = r1::compute_focus_q32(g, TriKernelParams{}, lambda2);
    const auto f = r1::compute_focus_f64(g, TriKernelParams{}, lambda2);
    ASSERT_TRUE(q.is_ok() && f.is_ok());
    double l1 = 0;
    for (std::uint32_t i = 0; i < g.n; ++i) l1 += std::abs(q->phi[i].to_double() - f->phi[i]);
    const double bound = 16.0 * g.n * ULP / (1 - q->kappa);
    EXPECT_LE(l1, bound) << "n " << g.n;
    EXPECT_NEAR(q->syntropy, f->syntropy, 1e-6);
    RecordProperty("q32_f64_l1_n" + std::to_string(g.n), sci(l1) + " <= " + sci(bound));
  }
}

// Vertex-transitive graphs: every particle is alike, so phi is uniform. On a directed cycle of a
// power-of-two length every operation is exact on the uniform vector (P and N entries 1 and 1/2),
// so phi is exactly 2^32 / n. The generated undirected kinds emit links from the lower index to
// the higher (R1-GEN-009), which breaks the symmetry of diffusion, so they run without it; their
// apportioned N (shares of 1/6, 1/63) differs from the exact one by < 1 ulp per entry, which
// leaves phi uniform to within a few raws.
TEST(FocusIteration, SymmetricGraphsGiveSymmetricPhi) {
  std::vector<L> cycle;
  for (int i = 0; i < 1024; ++i) cycle.push_back({i, (i + 1) % 1024, 1});
  const Graph ring = graph_of(cycle);
  const auto q = r1::compute_focus_q32(ring, TriKernelParams{}, 0.1);
  ASSERT_TRUE(q.is_ok());
  for (const Q32 x : q->phi) ASSERT_EQ(x.raw, ONE / 1024);
  EXPECT_EQ(q->syntropy, 0.0);  // KL to uniform of the uniform vector
  std::vector<std::uint32_t> id(ring.n);
  std::iota(id.begin(), id.end(), 0u);
  EXPECT_EQ(q->cyberank, id);  // all ties: index order

  TriKernelParams undirected;
  undirected.lambda_d = Q32::zero();
  undirected.lambda_s = Q32::from_decimal("0.6");
  undirected.lambda_h = Q32::one() - undirected.lambda_s;
  r1::GenParams torus;
  torus.kind = r1::GenKind::kTorus;
  torus.dims = {8, 8, 8};
  auto torus_graph = r1::build_graph(*r1::generate(torus));
  ASSERT_TRUE(torus_graph.is_ok());
  for (const Graph& g : {*torus_graph, generated(r1::GenKind::kComplete, 64)}) {
    const auto u = r1::compute_focus_q32(g, undirected, 0.1);
    ASSERT_TRUE(u.is_ok());
    for (const Q32 x : u->phi) EXPECT_NEAR(x.raw, ONE / g.n, 4) << "n " << g.n;
  }

  // A path is symmetric under reversal (particles are numbered along it, so the mirror of i is
  // n-1-i), up to the index tie-breaks of the apportionment (<= 1 raw per step, damped).
  const Graph path = generated(r1::GenKind::kPath, 41);
  const auto pq = r1::compute_focus_q32(path, undirected, 0.0);
  ASSERT_TRUE(pq.is_ok());
  for (std::uint32_t i = 0; i < path.n; ++i) EXPECT_NEAR(pq->phi[i].raw, pq->phi[path.n - 1 - i].raw, 4) << i;
  // Springs pull towards uniform, heat towards the degree: the ends (degree 1) keep less.
  EXPECT_GT(pq->phi[20].raw, pq->phi[0].raw);
}

TEST(FocusIteration, SyntropyAndCyberank) {
  const Graph g = graph_of({{0, 1, 1}, {1, 2, 3}, {2, 0, 1}, {2, 3, 1}, {3, 4, 2}, {5, 5, 1}, {6, 1, 1}});
  const auto q = r1::compute_focus_q32(g, TriKernelParams{}, 0.0);
  ASSERT_TRUE(q.is_ok());
  long double j = 0;
  for (const Q32 x : q->phi) j += static_cast<long double>(x.to_double()) * std::log(static_cast<long double>(g.n) * static_cast<long double>(x.to_double()));
  // Each of n logarithms carries <= (1/2 + 2^-20) ulp, weighted by phi (sum 1), plus ln n's and
  // the final rounding: a few ulp.
  EXPECT_NEAR(q->syntropy, static_cast<double>(j), 4 * ULP);
  EXPECT_GT(q->syntropy, 0.0);
  for (std::size_t k = 1; k < q->cyberank.size(); ++k) {
    const auto a = q->cyberank[k - 1], b = q->cyberank[k];
    EXPECT_TRUE(q->phi[a] > q->phi[b] || (q->phi[a] == q->phi[b] && a < b));
  }
}

// Beyond kCyberankPlaces particles the order keeps its leading places: those of a full sort of
// phi (descending, ties to the lower index), in the Q32 and the fp64 domain.
TEST(FocusIteration, CyberankKeepsTheLeadingPlaces) {
  const Graph g = generated(r1::GenKind::kBa, 3000, 3);
  const auto q = r1::compute_focus_q32(g, TriKernelParams{}, 0.1);
  const auto f = r1::compute_focus_f64(g, TriKernelParams{}, 0.1);
  ASSERT_TRUE(q.is_ok() && f.is_ok());
  const auto sorted = [](const auto& phi) {
    std::vector<std::uint32_t> order(phi.size());
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(), [&phi](std::uint32_t a, std::uint32_t b) { return phi[b] < phi[a]; });
    order.resize(r1::kCyberankPlaces);
    return order;
  };
  EXPECT_EQ(q->cyberank, sorted(q->phi));
  EXPECT_EQ(f->cyberank, sorted(f->phi));
  // A ring's phi takes a few raws only: most places are ties, settled by index.
  const Graph ring = generated(r1::GenKind::kRing, 2000);
  const auto r = r1::compute_focus_q32(ring, TriKernelParams{}, 0.1);
  ASSERT_TRUE(r.is_ok());
  EXPECT_EQ(r->cyberank, sorted(r->phi));
  EXPECT_EQ(r->phi[r->cyberank[1]], r->phi[r->cyberank[2]]);
}

TEST(FocusIteration, ProgressCountsSteps) {
  const Graph g = generated(r1::GenKind::kRing, 16);
  for (const bool stop : {false, true}) {
    std::uint64_t calls = 0, last = 0, total = 0;
    r1::FocusOptions o;
    o.stop_at_repeat = stop;
    const auto q = r1::compute_focus_q32(
        g, TriKernelParams{}, 0.0,
        [&](std::string_view stage, std::uint64_t done, std::uint64_t of) {
          EXPECT_EQ(stage, "focus");
          EXPECT_GT(done, last);
          if (!stop) {
            EXPECT_EQ(done, last + 1);
          }
          last = done;
          total = of;
          ++calls;
        },
        o);
    ASSERT_TRUE(q.is_ok());
    EXPECT_EQ(last, q->steps);
    EXPECT_EQ(total, q->steps);
    // Every step reported; with stop_at_repeat the ring's iterates repeat well before the last of
    // its 96 steps, and the report jumps to the end (R1-FOC-093).
    if (stop) {
      EXPECT_LT(calls, q->steps);
    } else {
      EXPECT_EQ(calls, q->steps);
    }
  }
}

// R1-FOC-093 at every step count up to the plan's: the stop lands on either parity of a period-2
// repeat and on fixed points alike.
TEST(FocusIteration, EveryStepCountGivesTheSameBitsWithTheStop) {
  for (const Graph& g : {generated(r1::GenKind::kRing, 16), generated(r1::GenKind::kBa, 300, 3)}) {
    r1::FocusOptions all;
    all.stop_at_repeat = false;
    const std::uint32_t planned = r1::compute_focus_q32(g, TriKernelParams{}, 0.0)->steps;
    std::uint32_t stopped = 0;
    for (std::uint32_t t = 1; t <= planned; ++t) {
      TriKernelParams p;
      p.max_steps = t;
      std::uint64_t reports = 0;
      const auto a = r1::compute_focus_q32(g, p, 0.0, {}, all);
      const auto b = r1::compute_focus_q32(g, p, 0.0, [&](std::string_view, std::uint64_t, std::uint64_t) { ++reports; });
      ASSERT_TRUE(a.is_ok() && b.is_ok());
      ASSERT_EQ(a->steps, t);
      ASSERT_EQ(a->phi, b->phi) << t << " steps";
      ASSERT_EQ(a->heat, b->heat) << t << " steps";
      if (reports < t) ++stopped;
    }
    EXPECT_GT(stopped, planned / 4) << "the iterates never repeated";
  }
}

// R1-FOC-093: stopping at a repeated iterate gives every step's bits, for the full iteration and
// the local update, on random graphs and parameters (a step count often far past the repeat).
RC_GTEST_PROP(FocusIteration, StoppingAtARepeatGivesEveryStepsBits, ()) {
  const Graph g = random_graph();
  const TriKernelParams p = random_params();
  const double lambda2 = *rc::gen::inRange(0, 1000) / 1000.0;
  r1::FocusOptions all, stop;
  all.stop_at_repeat = false;
  stop.parallel = all.parallel = *rc::gen::arbitrary<bool>();
  std::uint64_t reports = 0;
  const auto a = r1::compute_focus_q32(g, p, lambda2, {}, all);
  const auto b = r1::compute_focus_q32(g, p, lambda2, [&](std::string_view, std::uint64_t, std::uint64_t) { ++reports; }, stop);
  RC_ASSERT(a.is_ok() && b.is_ok());
  RC_ASSERT(a->phi == b->phi);
  RC_ASSERT(a->heat == b->heat);
  RC_ASSERT(a->steps == b->steps);
  RC_ASSERT(a->cyberank == b->cyberank);
  RC_ASSERT(a->syntropy == b->syntropy);
  RC_TAG(reports < b->steps ? "stopped at a repeat" : "ran every step");
  // The local update from the result on a region around a random particle.
  const auto centre = *rc::gen::inRange<std::uint32_t>(0, g.n);
  std::vector<std::uint32_t> region{centre};
  for (std::uint64_t k = g.row_ptr[centre]; k < g.row_ptr[centre + 1]; ++k) region.push_back(g.col[k]);
  std::sort(region.begin(), region.end());
  region.erase(std::unique(region.begin(), region.end()), region.end());
  const auto c = r1::update_focus_q32(g, p, lambda2, *a, region, {}, all);
  const auto d = r1::update_focus_q32(g, p, lambda2, *a, region, {}, stop);
  RC_ASSERT(c.is_ok() && d.is_ok());
  RC_ASSERT(c->phi == d->phi);
  RC_ASSERT(c->heat == d->heat);
}

}  // namespace
