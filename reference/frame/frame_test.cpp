// The frame stage: sign convention, genesis scale against a 50-digit reference, alignment of a later epoch to its anchor (R1-FRM-001..013, R1-FRM-030..038).
#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <boost/multiprecision/cpp_bin_float.hpp>
#include <boost/multiprecision/cpp_int.hpp>
#include <cmath>
#include <cstring>

#include "r1/fixedpoint/counter_rng.hpp"
#include "r1/reference/frame.hpp"

namespace {

using r1::Q32;
using Big = boost::multiprecision::cpp_bin_float_50;
using Int = boost::multiprecision::cpp_int;

// n x 5 orthonormal columns (Gram-Schmidt on counter-based uniform entries), as a spectrum.
r1::Spectrum<Q32> random_spectrum(std::uint32_t n, std::uint64_t seed) {
  std::vector<std::vector<double>> cols;
  for (std::uint64_t k = 0; k < 5 && k + 1 < n; ++k) {
    std::vector<double> v(n);
    for (std::uint32_t i = 0; i < n; ++i) v[i] = 2 * r1::rng::uniform_double(seed, i, k) - 1;
    for (const auto& c : cols) {
      double d = 0;
      for (std::uint32_t i = 0; i < n; ++i) d += c[i] * v[i];
      for (std::uint32_t i = 0; i < n; ++i) v[i] -= d * c[i];
    }
    double nn = 0;
    for (double x : v) nn += x * x;
    nn = std::sqrt(nn);
    for (double& x : v) x /= nn;
    cols.push_back(v);
  }
  r1::Spectrum<Q32> s;
  s.n = n;
  s.found = static_cast<std::uint32_t>(cols.size());
  for (std::size_t k = 0; k < 5; ++k) {
    s.u[k].assign(n, Q32{});
    if (k < cols.size())
      for (std::uint32_t i = 0; i < n; ++i) s.u[k][i] = Q32::from_double(cols[k][i]);
  }
  return s;
}

r1::Snapshot snapshot_of(std::uint32_t n, const std::string& prefix = "p") {
  r1::Snapshot s;
  for (std::uint32_t i = 0; i < n; ++i) s.particles.push_back(r1::hemera::hash(prefix + std::to_string(i)));
  return s;
}

TEST(SignConvention, LargestMagnitudeMadePositiveTiesToLowestIndex) {
  r1::Spectrum<Q32> s;
  s.n = 4;
  auto q = [](double d) { return Q32::from_double(d); };
  s.u[0] = {q(0.1), q(-0.7), q(0.5), q(0.2)};   // largest |x| negative: flipped
  s.u[1] = {q(0.1), q(0.7), q(-0.5), q(0.2)};   // largest positive: kept
  s.u[2] = {q(0.5), q(-0.5), q(-0.5), q(0.5)};  // four-way tie: index 0 decides, positive: kept
  s.u[3] = {q(0), q(-0.5), q(0.5), q(0)};       // tie between 1 and 2: index 1 decides: flipped
  s.u[4] = {q(0), q(0), q(0), q(0)};            // zero vector: unchanged
  const auto flipped = r1::apply_sign_convention(s);
  EXPECT_EQ(flipped, (std::array<bool, 5>{true, false, false, true, false}));
  EXPECT_EQ(s.u[0][1], q(0.7));
  EXPECT_EQ(s.u[0][0], q(-0.1));
  EXPECT_EQ(s.u[2][1], q(-0.5));
  EXPECT_EQ(s.u[3][1], q(0.5));
  EXPECT_EQ(s.u[3][2], q(-0.5));
  EXPECT_EQ(r1::sign_pivot(s.u[4]), -1);
  EXPECT_EQ(r1::sign_pivot(std::span<const Q32>{}), -1);
}

// R1-FRM-001: entries within 2^-10 of the largest magnitude are ties, so noise on a symmetric
// pair (u(0) = -u(n-1) up to the solver's residual) cannot decide the sign.
TEST(SignConvention, NearTiesWithinTheWindowGoToTheLowestIndex) {
  r1::Spectrum<Q32> s;
  auto q = [](double d) { return Q32::from_double(d); };
  s.u[0] = {q(0.1), q(0.7), q(-0.7000001), q(0.2)};  // index 2 is larger by 1e-7: still a tie, index 1 decides
  s.u[1] = {q(0.1), q(0.69), q(-0.7), q(0.2)};       // 0.69 is 1.4% below: outside the window, index 2 decides
  const Q32 m = q(0.5);
  const Q32 edge = Q32::from_raw(m.raw - (m.raw >> 10));      // exactly at the window's floor: a tie
  const Q32 below = Q32::from_raw(m.raw - (m.raw >> 10) - 1);  // one raw below: not a tie
  s.u[2] = {edge, Q32::from_raw(-m.raw)};
  s.u[3] = {below, Q32::from_raw(-m.raw)};
  const auto f = r1::apply_sign_convention(s);
  EXPECT_EQ(r1::sign_pivot(s.u[0]), 1);
  EXPECT_EQ(r1::sign_pivot(s.u[1]), 2);
  EXPECT_EQ(r1::sign_pivot(s.u[2]), 0);
  EXPECT_EQ(r1::sign_pivot(s.u[3]), 1);
  EXPECT_EQ(f, (std::array<bool, 5>{false, true, false, true, false}));
  r1::Spectrum<double> d;
  d.u[0] = {0.3, 0.7, -0.7000001};
  EXPECT_EQ(r1::sign_pivot(d.u[0]), 1);
}

TEST(SignConvention, DoubleDomainFollowsTheSameRule) {
  r1::Spectrum<double> s;
  s.u[0] = {0.25, -0.25, 0.1};
  s.u[1] = {-0.0, -0.3, 0.3};
  const auto f = r1::apply_sign_convention(s);
  EXPECT_TRUE(!f[0] && f[1]);
  EXPECT_EQ(s.u[1][1], 0.3);
  EXPECT_EQ(s.u[1][2], -0.3);
}

RC_GTEST_PROP(SignConvention, IndependentOfTheInputSignAndIdempotent, ()) {
  const auto raws = *rc::gen::container<std::vector<std::int64_t>>(
      rc::gen::inRange<std::int64_t>(-(std::int64_t{1} << 32), std::int64_t{1} << 32));
  r1::Spectrum<Q32> a, b;
  for (auto r : raws) {
    a.u[0].push_back(Q32::from_raw(r));
    b.u[0].push_back(Q32::from_raw(-r));
  }
  r1::apply_sign_convention(a);
  r1::apply_sign_convention(b);
  RC_ASSERT(a.u[0] == b.u[0]);
  const auto p = r1::sign_pivot(a.u[0]);
  if (p >= 0) RC_ASSERT(a.u[0][static_cast<std::size_t>(p)].raw > 0);
  const auto again = r1::apply_sign_convention(a);
  RC_ASSERT(!again[0]);
}

// The rounding chain of R1-FRM-010 computed independently with arbitrary-precision integers:
// M exact, m = nearest integer to sqrt(M), s = RNE(1000 2^64 / m) raw, X' = RNE(x s / 2^32).
Int rne_div(const Int& num, const Int& den) {
  // den > 0; the quotient rounded to nearest, ties to even.
  const bool neg = num < 0;
  const Int a = neg ? Int(-num) : num;
  Int q = a / den;
  const Int r2 = 2 * (a % den);
  if (r2 > den || (r2 == den && (q & 1) != 0)) ++q;
  return neg ? Int(-q) : q;
}

TEST(Genesis, ScaleFollowsTheSpecRoundingChainExactly) {
  for (std::uint32_t n : {5u, 100u, 5000u}) {
    SCOPED_TRACE(n);
    auto s = random_spectrum(n, n);
    r1::apply_sign_convention(s);
    auto f = r1::genesis_frame(s, n);
    ASSERT_TRUE(f.is_ok()) << f.status().message();
    Int big_m = 0;
    for (std::uint32_t p = 0; p < n; ++p) {
      Int nn = 0;
      for (int c = 0; c < 3; ++c) nn += Int(s.u[c][p].raw) * Int(s.u[c][p].raw);
      big_m = std::max(big_m, nn);
    }
    Int m = boost::multiprecision::sqrt(big_m);
    // sqrt(M) >= m + 1/2 iff 4 M >= (2m + 1)^2 (equality impossible: the left side is even).
    if (4 * big_m >= (2 * m + 1) * (2 * m + 1)) ++m;
    const Int scale_raw = rne_div(Int(1000) << 64, m);
    EXPECT_EQ(f->scale, static_cast<double>(Big(scale_raw) / Big(4294967296.0)));
    for (std::uint32_t p = 0; p < n; ++p)
      for (int c = 0; c < 3; ++c)
        ASSERT_EQ(Int(f->position[p][c].raw), rne_div(Int(s.u[c][p].raw) * scale_raw, Int(1) << 32)) << p << " " << c;

    // Against the real value R_scene / max |X| (50 digits): m and s each carry one rounding to
    // half a raw unit, so the relative error is at most 0.5 / m + 0.5 / s_raw (+ a 2^-52 slack
    // for the final conversion to double).
    Big max_norm = 0;
    for (std::uint32_t p = 0; p < n; ++p) {
      Big nn = 0;
      for (int c = 0; c < 3; ++c) nn += Big(s.u[c][p].raw) * Big(s.u[c][p].raw);
      max_norm = std::max(max_norm, sqrt(nn));
    }
    const Big exact_scale = Big(1000) * Big(4294967296.0) / max_norm;  // R_scene / max |X| in value units
    const double rel = 0.5 / static_cast<double>(Big(m)) + 0.5 / static_cast<double>(Big(scale_raw)) + 0x1p-52;
    EXPECT_LE(std::fabs(f->scale - static_cast<double>(exact_scale)), rel * static_cast<double>(exact_scale));
    // R1-FRM-011: every |X'| <= R_scene + R_scene sqrt(n) 2^-32 + 2^-31, and the largest is that close to R_scene.
    const double bound = 1000.0 * std::sqrt(static_cast<double>(n)) * 0x1p-32 + 0x1p-31;
    double largest = 0;
    for (std::uint32_t p = 0; p < n; ++p) {
      double nn = 0;
      for (int c = 0; c < 3; ++c) {
        const Big exact = Big(s.u[c][p].raw) * Big(1000) / max_norm;
        EXPECT_LE(std::fabs(f->position[p][c].to_double() - static_cast<double>(exact)), bound);
        nn += f->position[p][c].to_double() * f->position[p][c].to_double();
      }
      largest = std::max(largest, std::sqrt(nn));
    }
    EXPECT_LE(largest, 1000.0 + bound);
    EXPECT_GE(largest, 1000.0 - bound);
    EXPECT_TRUE(f->alignment.genesis);
    EXPECT_EQ(f->alignment.rotation, (std::array<double, 9>{1, 0, 0, 0, 1, 0, 0, 0, 1}));
  }
}

TEST(Genesis, FewParticlesAndMissingVectors) {
  // One particle: no eigenvectors, the origin, scale 0.
  r1::Spectrum<Q32> one;
  one.n = 1;
  auto f1 = r1::genesis_frame(one, 1);
  ASSERT_TRUE(f1.is_ok());
  EXPECT_EQ(f1->position.size(), 1u);
  EXPECT_EQ(f1->position[0][0], Q32{});
  EXPECT_EQ(f1->scale, 0);
  // Three particles: u_2 and u_3 only; the layout lies in the plane z = 0.
  auto three = random_spectrum(3, 9);
  three.u[2].clear();
  auto f3 = r1::genesis_frame(three, 3);
  ASSERT_TRUE(f3.is_ok()) << f3.status().message();
  for (const auto& p : f3->position) EXPECT_EQ(p[2], Q32{});
  EXPECT_GT(f3->scale, 0);
  // Shapes that disagree are internal errors.
  EXPECT_EQ(r1::genesis_frame(three, 4).status().kind(), r1::ErrorKind::kInternal);
  three.u[0].resize(2);
  EXPECT_EQ(r1::genesis_frame(three, 3).status().kind(), r1::ErrorKind::kInternal);
}

// Positions of a later epoch whose eigenvectors differ by an orthogonal mix of u_2..u_4 (what a
// repeated eigenvalue or a sign flip does) plus a tiny perturbation.
r1::Spectrum<Q32> mixed(const r1::Spectrum<Q32>& s, const std::array<double, 9>& q, double noise) {
  r1::Spectrum<Q32> out = s;
  for (std::uint32_t p = 0; p < s.n; ++p)
    for (int r = 0; r < 3; ++r) {
      double acc = 0;
      for (int c = 0; c < 3; ++c) acc += q[r * 3 + c] * s.u[c][p].to_double();
      acc += noise * (2 * r1::rng::uniform_double(99, p, static_cast<std::uint64_t>(r)) - 1);
      out.u[r][p] = Q32::from_double(acc);
    }
  return out;
}

double det3(const std::array<double, 9>& a) {
  return a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6]) + a[2] * (a[3] * a[7] - a[4] * a[6]);
}

TEST(Alignment, LaterEpochLandsOnTheAnchor) {
  const std::uint32_t n = 2000;
  const auto snap = snapshot_of(n);
  auto s0 = random_spectrum(n, 1);
  r1::apply_sign_convention(s0);
  auto f0 = r1::compute_frame(snap, s0);
  ASSERT_TRUE(f0.is_ok());
  const auto anchor = r1::make_anchor(snap, *f0);
  ASSERT_EQ(anchor.entries.size(), 1024u);

  const double c = std::cos(0.7), s = std::sin(0.7);
  const std::array<double, 9> rot{c, -s, 0, s, c, 0, 0, 0, 1};
  const std::array<double, 9> refl{c, -s, 0, s, c, 0, 0, 0, -1};  // det -1: needs SC-R
  for (const auto& q : {rot, refl}) {
    SCOPED_TRACE(det3(q));
    auto s1 = mixed(s0, q, 0);
    const auto flips = r1::apply_sign_convention(s1);
    // The map from this epoch's coordinates back to the anchor's has det = det(q) x (-1)^flips.
    const bool improper = (det3(q) < 0) != ((flips[0] + flips[1] + flips[2]) % 2 == 1);
    auto f1 = r1::compute_frame(snap, s1, &anchor, "g.anchor");
    ASSERT_TRUE(f1.is_ok()) << f1.status().message();
    const auto& a = f1->alignment;
    EXPECT_FALSE(a.genesis);
    EXPECT_EQ(a.matched, 1024u);
    EXPECT_NEAR(det3(a.rotation), 1.0, 1e-12);
    EXPECT_EQ(a.reflected, improper);
    EXPECT_LE(a.rms, 1e-5);
    // Every particle, not only the anchor, comes back to its genesis position.
    double worst = 0;
    for (std::uint32_t p = 0; p < n; ++p)
      for (int k = 0; k < 3; ++k)
        worst = std::max(worst, std::fabs(f1->position[p][k].to_double() - f0->position[p][k].to_double()));
    EXPECT_LE(worst, 1e-4);
  }
}

TEST(Alignment, PartialMatchAndTooFewMatches) {
  const std::uint32_t n = 300;
  const auto snap = snapshot_of(n);
  auto s0 = random_spectrum(n, 2);
  r1::apply_sign_convention(s0);
  auto f0 = r1::compute_frame(snap, s0);
  ASSERT_TRUE(f0.is_ok());
  auto anchor = r1::make_anchor(snap, *f0);
  // Half of the anchor names particles this snapshot does not have.
  for (std::size_t e = 0; e < anchor.entries.size(); e += 2) anchor.entries[e].id = r1::hemera::hash("gone" + std::to_string(e));
  auto s1 = mixed(s0, {0, 1, 0, -1, 0, 0, 0, 0, 1}, 1e-8);
  r1::apply_sign_convention(s1);
  auto f1 = r1::compute_frame(snap, s1, &anchor, "g.anchor");
  ASSERT_TRUE(f1.is_ok()) << f1.status().message();
  EXPECT_EQ(f1->alignment.matched, 150u);
  EXPECT_LE(f1->alignment.rms, 1e-3);
  // Three matches: bad input naming the anchor file and the counts.
  r1::Anchor few = anchor;
  few.entries.resize(6);  // entries 1, 3, 5 match
  auto bad = r1::compute_frame(snap, s1, &few, "g.anchor");
  ASSERT_FALSE(bad.is_ok());
  EXPECT_EQ(bad.status().kind(), r1::ErrorKind::kInput);
  EXPECT_EQ(bad.status().message(),
            "g.anchor: only 3 of 6 anchor particles are in this snapshot; alignment needs at least 4");
}

TEST(Alignment, MatchesByIdWhateverTheParticleOrder) {
  const std::uint32_t n = 400;
  const auto snap = snapshot_of(n);
  auto s0 = random_spectrum(n, 3);
  r1::apply_sign_convention(s0);
  auto f0 = r1::compute_frame(snap, s0);
  ASSERT_TRUE(f0.is_ok());
  const auto anchor = r1::make_anchor(snap, *f0);
  // The same particles in reverse order, with the same per-particle spectrum.
  r1::Snapshot rev;
  r1::Spectrum<Q32> s1 = s0;
  for (std::uint32_t i = 0; i < n; ++i) {
    rev.particles.push_back(snap.particles[n - 1 - i]);
    for (int k = 0; k < 5; ++k) s1.u[k][i] = s0.u[k][n - 1 - i];
  }
  auto f1 = r1::compute_frame(rev, s1, &anchor);
  ASSERT_TRUE(f1.is_ok());
  EXPECT_EQ(f1->alignment.matched, n);
  EXPECT_LE(f1->alignment.rms, 1e-6);
  for (std::uint32_t i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(f1->position[i][k].to_double(), f0->position[n - 1 - i][k].to_double(), 1e-6);
}

TEST(Alignment, DeterministicBytes) {
  const std::uint32_t n = 1500;
  const auto snap = snapshot_of(n);
  auto s0 = random_spectrum(n, 4);
  r1::apply_sign_convention(s0);
  auto f0 = r1::compute_frame(snap, s0);
  const auto anchor = r1::make_anchor(snap, *f0);
  auto s1 = mixed(s0, {0.6, 0.8, 0, -0.8, 0.6, 0, 0, 0, 1}, 1e-6);
  r1::apply_sign_convention(s1);
  auto a = r1::compute_frame(snap, s1, &anchor);
  auto b = r1::compute_frame(snap, s1, &anchor);
  ASSERT_TRUE(a.is_ok() && b.is_ok());
  EXPECT_EQ(a->position, b->position);
  EXPECT_EQ(std::memcmp(&a->alignment.rms, &b->alignment.rms, sizeof(double)), 0);
  EXPECT_EQ(*r1::anchor_bytes(r1::make_anchor(snap, *a)), *r1::anchor_bytes(r1::make_anchor(snap, *b)));
}

}  // namespace
