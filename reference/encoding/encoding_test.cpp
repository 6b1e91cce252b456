// The encoding stage: exact luminosity, monotone radius, hue angles, the saturation rule, overlays that touch only style, determinism, input checks (R1-ENC-001..005, R1-ENC-019, R1-ENC-030, R1-ENC-041, R1-ENC-050).
#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <boost/math/constants/constants.hpp>
#include <boost/multiprecision/cpp_bin_float.hpp>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cstring>

#include "r1/fixedpoint/counter_rng.hpp"
#include "r1/fixedpoint/exact_sum.hpp"
#include "r1/reference/encoding.hpp"
#include "r1/reference/generate.hpp"
#include "r1/reference/graph_build.hpp"
#include "r1/reference/snapshot_builder.hpp"
#include "test_support.hpp"

namespace {

using r1::Q32;
using Big = boost::multiprecision::cpp_bin_float_50;

struct L {
  std::uint32_t from, to;
  int valence;
  std::uint64_t weight = 1;
};

r1::Snapshot snapshot_of(std::uint32_t n, const std::vector<L>& links) {
  r1::SnapshotBuilder b("test");
  b.snapshot().config = r1::text_input_config();
  for (std::uint32_t i = 0; i < n; ++i) b.particle_by_name("n" + std::to_string(i));
  for (const auto& x : links) {
    r1::Link l;
    l.height = 1;
    l.amount = static_cast<r1::u128>(x.weight) << 32;
    l.valence = static_cast<std::int8_t>(x.valence);
    l.from = x.from;
    l.to = x.to;
    b.add_link(l);
  }
  return std::move(b.finish()).value();
}

// phi proportional to 1 + (i mod 7), raws summing to exactly 2^32.
r1::Focus<Q32> focus_of(std::uint32_t n) {
  r1::Focus<Q32> f;
  std::int64_t total_w = 0;
  for (std::uint32_t i = 0; i < n; ++i) total_w += 1 + i % 7;
  std::int64_t used = 0;
  for (std::uint32_t i = 0; i < n; ++i) {
    const std::int64_t raw = Q32::kOneRaw * (1 + i % 7) / total_w;
    f.phi.push_back(Q32::from_raw(raw));
    used += raw;
  }
  f.phi.back().raw += Q32::kOneRaw - used;
  return f;
}

r1::Spectrum<Q32> spectrum_of(std::uint32_t n, std::uint64_t seed) {
  r1::Spectrum<Q32> s;
  s.n = n;
  for (int k = 0; k < 5; ++k)
    for (std::uint32_t i = 0; i < n; ++i)
      s.u[k].push_back(Q32::from_raw(static_cast<std::int64_t>(r1::rng::uniform_below(seed, i, static_cast<std::uint64_t>(k), 1u << 26)) - (1 << 25)));
  return s;
}

// A ring of 30 with chords to 0 (a hub), a tail (leaves) and some valence.
r1::Snapshot sample_graph() {
  std::vector<L> links;
  for (std::uint32_t i = 0; i < 30; ++i) links.push_back({i, (i + 1) % 30, static_cast<int>(i % 3) - 1});
  for (std::uint32_t i = 2; i < 30; i += 3) links.push_back({0, i, 1});
  links.push_back({5, 30, 0});
  links.push_back({6, 31, 0});
  return snapshot_of(32, links);
}

TEST(Luminosity, SumsExactlyToL0) {
  const auto f = focus_of(1001);
  EXPECT_EQ(r1::apportion_luminosity(f.phi), f.phi);  // L0 = 1: phi itself
  for (const char* total : {"0.7", "3", "1000", "0.0000001"}) {
    SCOPED_TRACE(total);
    const Q32 t = Q32::from_decimal(total);
    const auto l = r1::apportion_luminosity(f.phi, t);
    r1::fx::ExactSum sum;
    for (std::size_t p = 0; p < l.size(); ++p) {
      sum.add(l[p]);
      // Within one unit of the exact product: floor, or floor + 1.
      const r1::i128 prod = static_cast<r1::i128>(t.raw) * f.phi[p].raw;
      const auto fl = static_cast<std::int64_t>(prod >> 32);
      EXPECT_TRUE(l[p].raw == fl || l[p].raw == fl + 1);
    }
    EXPECT_EQ(sum.round(), t);
  }
}

RC_GTEST_PROP(Luminosity, AnyFocusAnyTotal, ()) {
  const auto weights = *rc::gen::nonEmpty(rc::gen::container<std::vector<std::uint32_t>>(rc::gen::inRange<std::uint32_t>(1, 1000)));
  std::int64_t w = 0;
  for (auto x : weights) w += x;
  std::vector<Q32> phi;
  std::int64_t used = 0;
  for (auto x : weights) {
    phi.push_back(Q32::from_raw(Q32::kOneRaw * x / w));
    used += phi.back().raw;
  }
  phi.back().raw += Q32::kOneRaw - used;
  const Q32 t = Q32::from_raw(*rc::gen::inRange<std::int64_t>(0, std::int64_t{1} << 50));
  const auto l = r1::apportion_luminosity(phi, t);
  r1::fx::ExactSum sum;
  for (auto x : l) sum.add(x);
  RC_ASSERT(sum.round() == t);
}

TEST(Radius, MonotoneAndCorrectlyRounded) {
  EXPECT_EQ(r1::radius_of(Q32::one()), Q32::from_int(1000));
  EXPECT_EQ(r1::radius_of(Q32::from_decimal("0.25")), Q32::from_int(500));
  EXPECT_EQ(r1::radius_of(Q32::from_decimal("0.25"), Q32::from_decimal("1.5")), Q32::from_int(750));
  Q32 prev = Q32::zero();
  for (std::int64_t raw = 1; raw < Q32::kOneRaw; raw = raw * 3 + 1) {
    const Q32 r = r1::radius_of(Q32::from_raw(raw));
    EXPECT_GE(r, prev);
    prev = r;
    const Big exact = sqrt(Big(raw) / Big(4294967296.0)) * 1000;
    EXPECT_LE(abs(Big(r.raw) / Big(4294967296.0) - exact), Big(0.5) / Big(4294967296.0));
  }
}

RC_GTEST_PROP(Radius, NonDecreasingInPhi, ()) {
  const auto a = *rc::gen::inRange<std::int64_t>(1, Q32::kOneRaw + 1);
  const auto b = *rc::gen::inRange<std::int64_t>(1, Q32::kOneRaw + 1);
  const Q32 m = Q32::from_raw(*rc::gen::inRange<std::int64_t>(1, 16 * Q32::kOneRaw + 1));
  const Q32 ra = r1::radius_of(Q32::from_raw(a), m), rb = r1::radius_of(Q32::from_raw(b), m);
  const bool ordered = (a <= b) ? ra <= rb : ra >= rb;
  RC_ASSERT(ordered);
}

RC_GTEST_PROP(Radius, NonDecreasingInPhiForAnyR0, ()) {
  const auto a = *rc::gen::inRange<std::int64_t>(1, Q32::kOneRaw + 1);
  const auto b = *rc::gen::inRange<std::int64_t>(1, Q32::kOneRaw + 1);
  const auto r0sq = *rc::gen::inRange<std::int64_t>(1, r1::kSceneR0SquaredRaw + 1);
  const Q32 ra = r1::radius_of(Q32::from_raw(a), Q32::one(), r0sq), rb = r1::radius_of(Q32::from_raw(b), Q32::one(), r0sq);
  const bool ordered = (a <= b) ? ra <= rb : ra >= rb;
  RC_ASSERT(ordered);
  // R1-ENC-001's two roundings, each checked on its own: the product r0^2 phi rounds to the
  // nearest raw (ties to even), then its root rounds to the nearest raw, within half a unit of
  // the root (50 digits) of that rounded product.
  const unsigned __int128 full = static_cast<unsigned __int128>(r0sq) * static_cast<unsigned __int128>(a);
  std::uint64_t prod = static_cast<std::uint64_t>(full >> 32);
  const std::uint64_t rest = static_cast<std::uint64_t>(full & 0xFFFFFFFFu);
  if (rest > 0x80000000u || (rest == 0x80000000u && (prod & 1) != 0)) ++prod;
  RC_ASSERT(abs(Big(ra.raw) - Big(65536) * sqrt(Big(prod))) <= Big(0.5));
  // Once the product is at least 2^30 raws its rounding moves the root by under half a unit, so
  // the radius is within one unit of sqrt(r0^2 phi) itself; below that the product's rounding
  // dominates (r0^2 phi = 2 raws gives 0, not 1.41), which is R1-ENC-001's rule, not an error.
  if (prod >= (std::uint64_t{1} << 30)) {
    const Big exact = sqrt(Big(r0sq) * Big(a) / Big(4294967296.0) / Big(4294967296.0));
    RC_ASSERT(abs(Big(ra.raw) / Big(4294967296.0) - exact) <= Big(1) / Big(4294967296.0));
  }
}

// The case the property once drew: r0^2 = 2 raws and phi = 1 raw round the product to 0.
// R1-ENC-001 rounds the product before the root.
TEST(Radius, TinyProductsRoundToZeroFirst) {
  EXPECT_EQ(r1::radius_of(Q32::from_raw(1), Q32::one(), 2), Q32::zero());
  // 1.25 raws round down to 1 (root 2^16 raws); 1.5 raws tie to even, 2 (root 2^16 sqrt 2).
  EXPECT_EQ(r1::radius_of(Q32::from_raw(1), Q32::one(), std::int64_t{5} << 30), Q32::from_raw(65536));
  EXPECT_EQ(r1::radius_of(Q32::from_raw(1), Q32::one(), std::int64_t{3} << 31), Q32::from_raw(92682));
}

// R1-ENC-007: particles 2 units apart on a line with equal focus: r_0^2 = (2/2)^2 / (1/n) = n,
// so every radius is exactly 1 (half the spacing).
TEST(RadiusScale, ClosedFormOnALine) {
  const std::uint32_t n = 64;
  std::vector<std::array<Q32, 3>> pos(n);
  for (std::uint32_t i = 0; i < n; ++i) pos[i] = {Q32::from_int(2 * static_cast<std::int64_t>(i) - 64), Q32{}, Q32{}};
  std::vector<Q32> phi(n, Q32::from_raw(Q32::kOneRaw / n));
  const r1::RadiusScale s = r1::radius_scale_from_layout(pos, phi);
  EXPECT_EQ(s.distinct, n);
  EXPECT_EQ(s.spacing2, static_cast<r1::u128>(4) << 64);
  EXPECT_EQ(s.r0_squared_raw, std::int64_t{n} << 32);
  EXPECT_EQ(r1::radius_of(phi[0], Q32::one(), s.r0_squared_raw), Q32::one());
  // Coincident copies change neither the spacing nor (with the same median focus) r_0.
  std::vector<std::array<Q32, 3>> doubled = pos;
  doubled.insert(doubled.end(), pos.begin(), pos.end());
  std::vector<Q32> phi2(2 * n, Q32::from_raw(Q32::kOneRaw / n / 2));
  const r1::RadiusScale d = r1::radius_scale_from_layout(doubled, phi2);
  EXPECT_EQ(d.distinct, n);
  EXPECT_EQ(d.spacing2, s.spacing2);
  EXPECT_EQ(d.r0_squared_raw, std::int64_t{2 * n} << 32);  // half the focus each: r_0^2 doubles
}

TEST(RadiusScale, DegenerateLayoutsKeepRScene) {
  std::vector<std::array<Q32, 3>> one(5, {Q32::from_int(3), Q32::from_int(-1), Q32{}});
  std::vector<Q32> phi(5, Q32::from_raw(Q32::kOneRaw / 5));
  EXPECT_EQ(r1::radius_scale_from_layout(one, phi).r0_squared_raw, r1::kSceneR0SquaredRaw);
  EXPECT_EQ(r1::radius_scale_from_layout({}, {}).r0_squared_raw, r1::kSceneR0SquaredRaw);
  // Two particles 2000 apart with all the focus on one: the rule asks for more than R_scene.
  std::vector<std::array<Q32, 3>> two = {{Q32::from_int(-1000), Q32{}, Q32{}}, {Q32::from_int(1000), Q32{}, Q32{}}};
  std::vector<Q32> tiny = {Q32::from_raw(1), Q32::from_raw(Q32::kOneRaw - 1)};
  EXPECT_EQ(r1::radius_scale_from_layout(two, tiny).r0_squared_raw, r1::kSceneR0SquaredRaw);
}

// The median spacing against brute force, serial and parallel alike, on random layouts with
// repeated positions.
RC_GTEST_PROP(RadiusScale, MedianSpacingMatchesBruteForce, ()) {
  const auto n = *rc::gen::inRange<std::uint32_t>(2, 200);
  std::vector<std::array<Q32, 3>> pos(n);
  std::vector<Q32> phi(n);
  for (auto& p : pos)
    for (auto& c : p) c = Q32::from_raw(*rc::gen::inRange<std::int64_t>(-40, 40) << 30);
  for (auto& f : phi) f = Q32::from_raw(*rc::gen::inRange<std::int64_t>(1, Q32::kOneRaw / n));
  std::vector<std::array<std::int64_t, 3>> d;
  for (const auto& p : pos) d.push_back({p[0].raw, p[1].raw, p[2].raw});
  std::sort(d.begin(), d.end());
  d.erase(std::unique(d.begin(), d.end()), d.end());
  const r1::RadiusScale s = r1::radius_scale_from_layout(pos, phi);
  RC_ASSERT(s.distinct == d.size());
  if (d.size() < 2) return;
  std::vector<r1::u128> nn;
  for (std::size_t i = 0; i < d.size(); ++i) {
    r1::u128 best = r1::u128_max;
    for (std::size_t j = 0; j < d.size(); ++j) {
      if (i == j) continue;
      r1::u128 sum = 0;
      for (int k = 0; k < 3; ++k) {
        const r1::i128 e = d[i][k] - d[j][k];
        sum += static_cast<r1::u128>(e * e);
      }
      best = std::min(best, sum);
    }
    nn.push_back(best);
  }
  std::sort(nn.begin(), nn.end());
  RC_ASSERT(s.spacing2 == nn[nn.size() / 2]);
  RC_ASSERT(r1::radius_scale_from_layout(pos, phi, true).r0_squared_raw == s.r0_squared_raw);
}

TEST(Hue, KnownAngles) {
  const Q32 one = Q32::one(), zero = Q32::zero();
  auto near = [](Q32 got, double want) { EXPECT_NEAR(got.to_double(), want, 3e-10); };
  EXPECT_EQ(r1::hue_of(one, zero), zero);
  EXPECT_EQ(r1::hue_of(zero, zero), zero);  // (0, 0): 0 by definition
  near(r1::hue_of(zero, one), 0.25);
  near(r1::hue_of(-one, zero), 0.5);
  near(r1::hue_of(zero, -one), 0.75);
  near(r1::hue_of(one, one), 0.125);
  near(r1::hue_of(-one, -one), 0.625);
  // Below the positive x axis: close to 1 but below it (-2^-8 rad = -0.000622 turns).
  const Q32 h = r1::hue_of(one, Q32::from_raw(-(std::int64_t{1} << 24)));
  EXPECT_LT(h, one);
  EXPECT_GT(h.to_double(), 0.999);
  // So close below that q = RNE(a / 2 pi) is 0 (|q| < 2^-33 turns): the hue is 0, never 1 (R1-ENC-003).
  EXPECT_EQ(r1::hue_of(one, Q32::from_raw(-1)), zero);
  for (std::uint64_t k = 0; k < 200; ++k) {
    const Q32 x = Q32::from_raw(static_cast<std::int64_t>(r1::rng::uniform_below(3, k, 0, 1u << 31)) - (1 << 30));
    const Q32 y = Q32::from_raw(static_cast<std::int64_t>(r1::rng::uniform_below(3, k, 1, 1u << 31)) - (1 << 30));
    const Q32 got = r1::hue_of(x, y);
    ASSERT_GE(got.raw, 0);
    ASSERT_LT(got.raw, Q32::kOneRaw);
    Big turns = atan2(Big(y.raw), Big(x.raw)) / (2 * boost::math::constants::pi<Big>());
    if (turns < 0) turns += 1;
    EXPECT_LE(abs(Big(got.raw) / Big(4294967296.0) - turns), Big(2) / Big(4294967296.0));
  }
}

TEST(Saturation, RuleCases) {
  // 0 -> 1 (+), 0 -> 2 (+): one-way valence. 3 -> 4 (+), 5 -> 3 (+): 3 sees its signed weight
  // pointing both ways (out to 4, in from 5) and balanced: 0. 6: 6 -> 7 (+), 8 -> 6 (+), 6 -> 9
  // without valence: W = 3, min(P, N) = 1 -> 1/3. 10 - 11 without valence: 1.
  const auto s = snapshot_of(12, {{0, 1, 1}, {0, 2, 1}, {3, 4, 1}, {5, 3, 1}, {6, 7, 1}, {8, 6, 1}, {6, 9, 0}, {10, 11, 0}});
  const auto g = std::move(r1::build_graph(s)).value();
  const auto sat = r1::saturation_from_a2(g);
  EXPECT_EQ(sat[0], Q32::one());
  EXPECT_EQ(sat[3], Q32::zero());
  EXPECT_EQ(sat[6], Q32::from_raw(1431655765));  // RNE(2^32 / 3)
  EXPECT_EQ(sat[10], Q32::one());
  EXPECT_EQ(sat[1], Q32::one());  // a single valenced link points one way
  // Heavier disagreement desaturates more: 3 gets a 3x heavier second in-link.
  const auto s2 = snapshot_of(3, {{0, 1, 1, 1}, {2, 0, 1, 3}});
  const auto g2 = std::move(r1::build_graph(s2)).value();
  // W = 1/3 + 1 (normalised by the max 3), P = 1/3, N = 1: (W - 2/3) / W = 1/2.
  EXPECT_NEAR(r1::saturation_from_a2(g2)[0].to_double(), 0.5, 1e-9);
}

TEST(Encode, FieldsRolesAndColour) {
  const auto s = sample_graph();
  const auto g = std::move(r1::build_graph(s)).value();
  const auto f = focus_of(g.n);
  const auto sp = spectrum_of(g.n, 1);
  r1::EncodingInfo info;
  auto e = r1::encode(s, g, f, sp, {}, &info);
  ASSERT_TRUE(e.is_ok()) << e.status().message();
  EXPECT_EQ(e->overlay, "none");
  EXPECT_EQ(e->luminosity, f.phi);
  EXPECT_TRUE(info.betweenness_exact);
  EXPECT_EQ(e->role[0], r1::Role::kHub);
  EXPECT_EQ(e->shape[0], r1::Shape::kSphere);
  EXPECT_EQ(e->role[30], r1::Role::kLeaf);
  EXPECT_EQ(e->shape[30], r1::Shape::kTetrahedron);
  for (std::uint32_t p = 0; p < g.n; ++p) {
    EXPECT_EQ(e->hue[p], r1::hue_of(sp.u[3][p], sp.u[4][p]));
    EXPECT_EQ(e->radius[p], r1::radius_of(f.phi[p]));
    EXPECT_EQ(e->color[p], r1::hsl_to_srgb8(Q32::from_raw(6 * e->hue[p].raw), e->saturation[p], 550));
    if (e->role[p] == r1::Role::kBridge) {
      EXPECT_EQ(e->shape[p], r1::Shape::kTorus);
    }
  }
  // Role shapes off: every particle a sphere, no roles computed.
  r1::EncodingOptions off;
  off.role_shapes = false;
  auto e2 = r1::encode(s, g, f, sp, off);
  ASSERT_TRUE(e2.is_ok());
  for (std::uint32_t p = 0; p < g.n; ++p) {
    EXPECT_EQ(e2->shape[p], r1::Shape::kSphere);
    EXPECT_EQ(e2->role[p], r1::Role::kNone);
  }
}

TEST(Encode, OverlaysChangeOnlyStyle) {
  auto s = sample_graph();
  s.crystal.assign(s.particles.size(), r1::CrystalTag{});
  for (std::size_t p = 0; p < s.particles.size(); p += 2)
    s.crystal[p] = r1::CrystalTag{static_cast<std::uint8_t>(p % 6), static_cast<std::uint8_t>(p % 21), static_cast<std::uint8_t>(p % 5)};
  const auto g = std::move(r1::build_graph(s)).value();
  const auto f = focus_of(g.n);
  const auto sp = spectrum_of(g.n, 2);
  auto base = r1::encode(s, g, f, sp);
  r1::EncodingOptions v5;
  v5.overlay = "crystal-v5";
  r1::EncodingInfo info;
  auto over = r1::encode(s, g, f, sp, v5, &info);
  ASSERT_TRUE(base.is_ok() && over.is_ok());
  EXPECT_EQ(over->overlay, "crystal-v5");
  EXPECT_EQ(info.overlay_particles, 16u);
  // Data fields are untouched (overlays never see positions, which are not an input at all).
  EXPECT_EQ(over->luminosity, base->luminosity);
  EXPECT_EQ(over->hue, base->hue);
  EXPECT_EQ(over->saturation, base->saturation);
  EXPECT_EQ(over->role, base->role);
  const auto& o = r1::crystal_v5_overlay();
  for (std::size_t p = 0; p < s.particles.size(); ++p) {
    if (p % 2 == 1) {
      EXPECT_EQ(over->color[p], base->color[p]);  // no metadata: schemaless
      EXPECT_EQ(over->shape[p], base->shape[p]);
      EXPECT_EQ(over->radius[p], base->radius[p]);
      continue;
    }
    EXPECT_EQ(over->shape[p], o.type_shape[p % 6]);
    EXPECT_EQ(over->color[p], *o.domain_color[p % 21]);
    EXPECT_EQ(over->radius[p], r1::radius_of(f.phi[p], *o.size_multiplier[p % 5]));
  }
}

TEST(Encode, CustomOverlayResolvesNamesAndIds) {
  const auto s = sample_graph();
  const auto g = std::move(r1::build_graph(s)).value();
  const auto f = focus_of(g.n);
  const auto sp = spectrum_of(g.n, 3);
  r1::test::TempDir dir;
  const std::string text = "[particle]\nn3 = { shape = \"cube\" }\n'" + r1::hemera::to_hex(s.particles[4]) +
                           "' = { color = \"#010203\", size = 2 }\nnobody = { size = 3 }\n";
  r1::test::write_file(dir / "o.toml", text);
  r1::EncodingOptions opt;
  opt.overlay = "custom";
  ASSERT_TRUE(r1::load_custom_overlay(opt, (dir / "o.toml").string()).is_ok());
  r1::EncodingInfo info;
  auto e = r1::encode(s, g, f, sp, opt, &info);
  ASSERT_TRUE(e.is_ok()) << e.status().message();
  EXPECT_EQ(e->overlay, "custom");
  EXPECT_EQ(info.overlay_particles, 2u);
  EXPECT_EQ(e->shape[3], r1::Shape::kCube);
  EXPECT_EQ(e->color[4], (r1::Rgb8{1, 2, 3}));
  EXPECT_EQ(e->radius[4], r1::radius_of(f.phi[4], Q32::from_int(2)));
  // A name and an id reaching the same particle: the later line is named.
  r1::test::write_file(dir / "dup.toml", "[particle]\nn4 = { size = 2 }\n'" + r1::hemera::to_hex(s.particles[4]) + "' = { size = 3 }\n");
  ASSERT_TRUE(r1::load_custom_overlay(opt, (dir / "dup.toml").string()).is_ok());
  auto dup = r1::encode(s, g, f, sp, opt);
  ASSERT_FALSE(dup.is_ok());
  EXPECT_EQ(dup.status().kind(), r1::ErrorKind::kInput);
  EXPECT_NE(dup.status().message().find("dup.toml:3: a second entry for particle"), std::string::npos) << dup.status().message();
}


// Every per-particle array of two encodings, byte for byte.
void expect_same_encoding(const r1::Encoding& a, const r1::Encoding& b) {
  EXPECT_EQ(a.radius, b.radius);
  EXPECT_EQ(a.luminosity, b.luminosity);
  EXPECT_EQ(a.hue, b.hue);
  EXPECT_EQ(a.saturation, b.saturation);
  EXPECT_EQ(a.role, b.role);
  EXPECT_EQ(a.shape, b.shape);
  EXPECT_EQ(a.color, b.color);
}

TEST(Encode, Deterministic) {
  const auto s = sample_graph();
  const auto g = std::move(r1::build_graph(s)).value();
  const auto f = focus_of(g.n);
  const auto sp = spectrum_of(g.n, 4);
  r1::EncodingOptions opt;
  opt.betweenness.pivots = 8;
  opt.parallel = true;  // the pivots hash and the batches run on workers: same result on one thread
  auto a = r1::encode(s, g, f, sp, opt);
  r1::Result<r1::Encoding> b = r1::Status::internal("unset");
  tbb::task_arena one(1);
  one.execute([&] { b = r1::encode(s, g, f, sp, opt); });
  ASSERT_TRUE(a.is_ok() && b.is_ok());
  expect_same_encoding(*a, *b);
}

// R1-ENC-020: the parallel switch changes how the stage runs, not a byte of what it computes, on
// generated graphs large enough to split (several betweenness batches, many per-particle blocks).
TEST(Encode, ParallelGivesTheSameBytes) {
  std::vector<r1::GenParams> graphs(3);
  graphs[0].kind = r1::GenKind::kBa;
  graphs[0].n = 30000;
  graphs[0].m = 4;
  graphs[1].kind = r1::GenKind::kSbm;
  graphs[1].n = 20000;
  graphs[1].k = 8;
  graphs[1].p_in = 0.002;
  graphs[1].p_out = 0.00002;
  graphs[2].kind = r1::GenKind::kRgg;
  graphs[2].n = 20000;
  graphs[2].radius = 0.04;
  for (const auto& gp : graphs) {
    const auto s = std::move(r1::generate(gp)).value();
    const auto g = std::move(r1::build_graph(s)).value();
    SCOPED_TRACE(g.n);
    const auto f = focus_of(g.n);
    const auto sp = spectrum_of(g.n, 9);
    r1::EncodingOptions serial;
    serial.betweenness.pivots = 40;  // six batches, kept small for the test's time
    r1::EncodingOptions par = serial;
    par.parallel = true;
    r1::EncodingInfo si, pi;
    auto a = r1::encode(s, g, f, sp, serial, &si);
    r1::Result<r1::Encoding> b = r1::Status::internal("unset");
    tbb::task_arena(4).execute([&] { b = r1::encode(s, g, f, sp, par, &pi); });
    ASSERT_TRUE(a.is_ok() && b.is_ok());
    expect_same_encoding(*a, *b);
    EXPECT_EQ(std::memcmp(&si.roles, &pi.roles, sizeof(si.roles)), 0);
    EXPECT_EQ(si.betweenness_sources, pi.betweenness_sources);
    EXPECT_GT(si.roles.count[static_cast<std::size_t>(r1::Role::kBridge)] + si.roles.count[static_cast<std::size_t>(r1::Role::kHub)], 0u);
  }
}

TEST(Encode, ChecksItsInputs) {
  const auto s = sample_graph();
  const auto g = std::move(r1::build_graph(s)).value();
  const auto sp = spectrum_of(g.n, 5);
  auto f = focus_of(g.n);
  f.phi[0].raw += 1;  // sums to 1 + 2^-32
  EXPECT_EQ(r1::encode(s, g, f, sp).status().kind(), r1::ErrorKind::kInternal);
  f = focus_of(g.n);
  f.phi[1].raw += f.phi[0].raw;
  f.phi[0].raw = 0;  // not positive
  EXPECT_EQ(r1::encode(s, g, f, sp).status().kind(), r1::ErrorKind::kInternal);
  f = focus_of(g.n);
  f.phi.pop_back();
  EXPECT_EQ(r1::encode(s, g, f, sp).status().kind(), r1::ErrorKind::kInternal);
  auto short_u = sp;
  short_u.u[3].resize(3);
  EXPECT_EQ(r1::encode(s, g, focus_of(g.n), short_u).status().kind(), r1::ErrorKind::kInternal);
  r1::EncodingOptions bad;
  bad.overlay = "crystal-v6";
  EXPECT_EQ(r1::encode(s, g, focus_of(g.n), sp, bad).status().kind(), r1::ErrorKind::kInput);
  bad.overlay = "custom";
  EXPECT_EQ(r1::encode(s, g, focus_of(g.n), sp, bad).status().kind(), r1::ErrorKind::kInput);
  // Missing u5/u6: every hue 0.
  auto none = sp;
  none.u[3].clear();
  none.u[4].clear();
  auto e = r1::encode(s, g, focus_of(g.n), none);
  ASSERT_TRUE(e.is_ok());
  for (auto h : e->hue) EXPECT_EQ(h, Q32::zero());
}

}  // namespace
