// Betweenness against a brute-force all-pairs count, huge path counts, hashed pivots and their error bound, and role inference (R1-ENC-010..018).
#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <boost/multiprecision/cpp_int.hpp>
#include <tbb/task_arena.h>

#include <cmath>
#include <cstring>
#include <deque>

#include "r1/fixedpoint/counter_rng.hpp"
#include "r1/reference/encoding.hpp"
#include "r1/reference/generate.hpp"
#include "r1/reference/graph_build.hpp"
#include "r1/reference/snapshot_builder.hpp"

namespace {

using Edge = std::pair<std::uint32_t, std::uint32_t>;

// A snapshot whose particles are named "0", "1", ... in order and whose links are `edges`.
r1::Snapshot snapshot_of(std::uint32_t n, const std::vector<Edge>& edges) {
  r1::SnapshotBuilder b("test");
  b.snapshot().config = r1::text_input_config();
  for (std::uint32_t i = 0; i < n; ++i) b.particle_by_name(std::to_string(i));
  for (const auto& [u, v] : edges) {
    r1::Link l;
    l.height = 1;
    l.amount = r1::u128{1} << 32;
    l.from = u;
    l.to = v;
    b.add_link(l);
  }
  return std::move(b.finish()).value();
}

r1::Graph graph_of(const r1::Snapshot& s) { return std::move(r1::build_graph(s)).value(); }

// Brute force: BFS distances and path counts (exact integers) from every particle, then
// b(v) = sum over s < t with d(s,v) + d(v,t) = d(s,t) of sigma_sv sigma_vt / sigma_st.
std::vector<double> brute_force(const r1::Graph& g) {
  using boost::multiprecision::cpp_int;
  const std::uint32_t n = g.n;
  std::vector<std::vector<int>> d(n, std::vector<int>(n, -1));
  std::vector<std::vector<cpp_int>> sigma(n, std::vector<cpp_int>(n, 0));
  for (std::uint32_t s = 0; s < n; ++s) {
    std::deque<std::uint32_t> q{s};
    d[s][s] = 0;
    sigma[s][s] = 1;
    while (!q.empty()) {
      const auto v = q.front();
      q.pop_front();
      for (auto k = g.row_ptr[v]; k < g.row_ptr[v + 1]; ++k) {
        const auto w = g.col[k];
        if (d[s][w] < 0) {
          d[s][w] = d[s][v] + 1;
          q.push_back(w);
        }
        if (d[s][w] == d[s][v] + 1) sigma[s][w] += sigma[s][v];
      }
    }
  }
  std::vector<double> b(n, 0.0);
  for (std::uint32_t v = 0; v < n; ++v)
    for (std::uint32_t s = 0; s < n; ++s)
      for (std::uint32_t t = s + 1; t < n; ++t) {
        if (s == v || t == v || d[s][t] < 0 || d[s][v] < 0 || d[v][t] < 0) continue;
        if (d[s][v] + d[v][t] != d[s][t]) continue;
        const cpp_int num = sigma[s][v] * sigma[v][t];
        b[v] += static_cast<double>(num) / static_cast<double>(sigma[s][t]);
      }
  return b;
}

std::vector<Edge> clique(std::uint32_t first, std::uint32_t k) {
  std::vector<Edge> e;
  for (std::uint32_t i = 0; i < k; ++i)
    for (std::uint32_t j = i + 1; j < k; ++j) e.push_back({first + i, first + j});
  return e;
}

// Two K20 cliques (0..19, 23..42) joined through the path 19 - 20 - 21 - 22 - 23.
std::vector<Edge> barbell() {
  auto e = clique(0, 20);
  const auto b = clique(23, 20);
  e.insert(e.end(), b.begin(), b.end());
  e.insert(e.end(), {{19, 20}, {20, 21}, {21, 22}, {22, 23}});
  return e;
}

std::vector<Edge> grid(std::uint32_t w, std::uint32_t h) {
  std::vector<Edge> e;
  for (std::uint32_t y = 0; y < h; ++y)
    for (std::uint32_t x = 0; x < w; ++x) {
      if (x + 1 < w) e.push_back({y * w + x, y * w + x + 1});
      if (y + 1 < h) e.push_back({y * w + x, (y + 1) * w + x});
    }
  return e;
}

void expect_close(const std::vector<double>& got, const std::vector<double>& want) {
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t i = 0; i < got.size(); ++i) EXPECT_NEAR(got[i], want[i], 1e-12 * std::max(1.0, want[i])) << "particle " << i;
}

TEST(Betweenness, ExactAgreesWithBruteForce) {
  std::vector<std::pair<std::uint32_t, std::vector<Edge>>> cases = {
      {5, {{0, 1}, {1, 2}, {2, 3}, {3, 4}}},                   // path
      {6, {{0, 1}, {0, 2}, {0, 3}, {0, 4}, {0, 5}}},           // star
      {7, {{0, 1}, {1, 2}, {2, 3}, {3, 4}, {4, 5}, {5, 6}, {6, 0}}},  // ring
      {20, grid(4, 5)},
      {43, barbell()},
      {9, {{0, 1}, {1, 2}, {2, 0}, {3, 4}, {4, 5}, {6, 7}, {7, 8}, {8, 6}, {6, 3}}},  // components
  };
  // A random graph of 40 particles, 100 links.
  std::vector<Edge> rnd;
  for (std::uint64_t k = 0; k < 100; ++k) {
    const auto u = static_cast<std::uint32_t>(r1::rng::uniform_below(5, k, 0, 40));
    const auto v = static_cast<std::uint32_t>(r1::rng::uniform_below(5, k, 1, 40));
    rnd.push_back({u, v});
  }
  cases.push_back({40, rnd});
  for (const auto& [n, edges] : cases) {
    SCOPED_TRACE(n);
    const auto s = snapshot_of(n, edges);
    const auto g = graph_of(s);
    const auto b = r1::betweenness(g, s.particles);
    EXPECT_TRUE(b.exact);
    EXPECT_EQ(b.sources, g.n);
    expect_close(b.value, brute_force(g));
  }
}

TEST(Betweenness, PathCountsBeyondTheDoubleRange) {
  // From a corner of a 300 x 300 grid the path counts reach C(598, 299) ~ 2^593, beyond 2^512
  // and, in the far corner, beyond what a double's exponent could reach after a few more rows.
  // Identity: sum_v delta_s(v) = sum_t (d(s, t) - 1), every shortest path having d - 1 inner particles.
  const std::uint32_t w = 300;
  const auto s = snapshot_of(w * w, grid(w, w));
  const auto g = graph_of(s);
  const std::vector<std::uint32_t> src{0};
  const auto delta = r1::betweenness_from_sources(g, src, 1.0);
  double sum = 0, want = 0;
  for (std::uint32_t y = 0; y < w; ++y)
    for (std::uint32_t x = 0; x < w; ++x) {
      const double v = delta[y * w + x];
      ASSERT_TRUE(std::isfinite(v) && v >= 0) << x << "," << y;
      sum += v;
      if (x + y > 0) want += static_cast<double>(x + y - 1);
    }
  EXPECT_NEAR(sum, want, 1e-9 * want);
  // Mirror symmetry of the grid about its diagonal.
  for (std::uint32_t y = 0; y < w; y += 7)
    for (std::uint32_t x = 0; x < w; x += 11) EXPECT_NEAR(delta[y * w + x], delta[x * w + y], 1e-9 * (1 + delta[y * w + x]));
}

TEST(Betweenness, SourceGroupsAddUp) {
  const auto s = snapshot_of(43, barbell());
  const auto g = graph_of(s);
  const auto exact = r1::betweenness(g, s.particles);
  std::vector<double> total(g.n, 0.0);
  for (std::uint32_t start = 0; start < 3; ++start) {
    std::vector<std::uint32_t> group;
    for (std::uint32_t v = start; v < g.n; v += 3) group.push_back(v);
    const auto part = r1::betweenness_from_sources(g, group, 0.5);
    for (std::uint32_t v = 0; v < g.n; ++v) total[v] += part[v];
  }
  expect_close(total, exact.value);
}

TEST(Betweenness, SameBitsForAnyThreadCount) {
  // R1-ENC-013: the deltas are added in ascending source order whatever runs them in parallel;
  // the 300-wide grid corner also takes the (m, e) path next to plain-double sources.
  r1::GenParams gp;
  gp.kind = r1::GenKind::kBa;
  gp.n = 600;
  gp.m = 3;
  const auto s = std::move(r1::generate(gp)).value();
  const auto g = graph_of(s);
  std::vector<std::uint32_t> src(g.n);
  for (std::uint32_t i = 0; i < g.n; ++i) src[i] = g.n - 1 - i;  // any order in: sorted inside
  const r1::BetweennessRun par{.parallel = true, .batched = true};
  std::vector<double> one, many;
  tbb::task_arena(1).execute([&] { one = r1::betweenness_from_sources(g, src, 0.5, {}, par); });
  tbb::task_arena(4).execute([&] { many = r1::betweenness_from_sources(g, src, 0.5, {}, par); });
  ASSERT_EQ(one.size(), many.size());
  EXPECT_EQ(std::memcmp(one.data(), many.data(), one.size() * sizeof(double)), 0);
  const std::uint32_t w = 300;
  const auto gs = snapshot_of(w * w, grid(w, w));
  const auto gg = graph_of(gs);
  const std::vector<std::uint32_t> mixed{0, 1, w * w / 2, w * w - 1};
  std::vector<double> a, b;
  tbb::task_arena(1).execute([&] { a = r1::betweenness_from_sources(gg, mixed, 1.0, {}, par); });
  tbb::task_arena(3).execute([&] { b = r1::betweenness_from_sources(gg, mixed, 1.0, {}, par); });
  EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(double)), 0);
}

// R1-ENC-020..021: seven sources per traversal or one at a time, serial or parallel, the same
// bits. The graphs take every path of the batched traversal: plain batches (ba, rgg), particles
// some lanes never reach (sbm blocks without links between them), lanes redone alone because a
// count reaches 2^53 next to lanes that are not (the grid: its corner counts pass 2^53, its
// centre's do not), batches deeper than 254 levels (the path), and a source given twice.
TEST(Betweenness, BatchedAndParallelGiveTheSameBits) {
  struct Case {
    const char* name;
    r1::GenParams params;
  };
  auto gen = [](r1::GenKind kind, std::int64_t n) {
    r1::GenParams p;
    p.kind = kind;
    if (kind != r1::GenKind::kGrid) p.n = n;
    return p;
  };
  std::vector<Case> cases;
  cases.push_back({"ba", gen(r1::GenKind::kBa, 20000)});
  cases.back().params.m = 3;
  cases.push_back({"sbm", gen(r1::GenKind::kSbm, 20000)});
  cases.back().params.k = 4;
  cases.back().params.p_in = 0.001;
  cases.back().params.p_out = 0.0;
  cases.push_back({"rgg", gen(r1::GenKind::kRgg, 10000)});
  cases.back().params.radius = 0.05;
  cases.push_back({"grid", gen(r1::GenKind::kGrid, 0)});
  cases.back().params.dims = {40, 40};
  cases.push_back({"path", gen(r1::GenKind::kPath, 3000)});
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const auto s = std::move(r1::generate(c.params)).value();
    const auto g = graph_of(s);
    // 26 sources: four batches of 7, 7, 6 and 6 (R1-ENC-021); the corner and the centre for the grid.
    std::vector<std::uint32_t> src = r1::choose_pivots(s.particles, 23);
    src.push_back(0);
    src.push_back(g.n / 2 + 20);
    src.push_back(src[5]);
    std::vector<double> plain, batched, par, par_plain;
    plain = r1::betweenness_from_sources(g, src, 0.5, {}, {.parallel = false, .batched = false});
    batched = r1::betweenness_from_sources(g, src, 0.5, {}, {.parallel = false, .batched = true});
    tbb::task_arena(4).execute(
        [&] { par = r1::betweenness_from_sources(g, src, 0.5, {}, {.parallel = true, .batched = true}); });
    tbb::task_arena(3).execute(
        [&] { par_plain = r1::betweenness_from_sources(g, src, 0.5, {}, {.parallel = true, .batched = false}); });
    ASSERT_EQ(plain.size(), g.n);
    for (const auto* other : {&batched, &par, &par_plain}) {
      ASSERT_EQ(other->size(), plain.size());
      EXPECT_EQ(std::memcmp(other->data(), plain.data(), plain.size() * sizeof(double)), 0);
    }
    EXPECT_GT(*std::max_element(plain.begin(), plain.end()), 0.0);
  }
}

TEST(Pivots, DeterministicDistinctAndIndependentOfOrder) {
  std::vector<r1::ParticleId> ids;
  for (int i = 0; i < 500; ++i) ids.push_back(r1::hemera::hash("n" + std::to_string(i)));
  const auto p = r1::choose_pivots(ids, 40);
  ASSERT_EQ(p.size(), 40u);
  EXPECT_TRUE(std::is_sorted(p.begin(), p.end()));
  EXPECT_EQ(std::adjacent_find(p.begin(), p.end()), p.end());
  EXPECT_EQ(r1::choose_pivots(ids, 40), p);
  // The chosen ids do not depend on where the particles stand in the order.
  std::vector<r1::ParticleId> rev(ids.rbegin(), ids.rend());
  const auto q = r1::choose_pivots(rev, 40);
  std::vector<r1::ParticleId> a, b;
  for (auto i : p) a.push_back(ids[i]);
  for (auto i : q) b.push_back(rev[i]);
  std::sort(a.begin(), a.end());
  std::sort(b.begin(), b.end());
  EXPECT_EQ(a, b);
  // The first pivot is the smallest digest of id || "r1-pivot".
  auto key = [&](std::uint32_t i) {
    std::vector<std::uint8_t> m(ids[i].begin(), ids[i].end());
    for (char c : std::string("r1-pivot")) m.push_back(static_cast<std::uint8_t>(c));
    return r1::hemera::hash(m);
  };
  std::uint32_t best = 0;
  for (std::uint32_t i = 1; i < ids.size(); ++i)
    if (key(i) < key(best)) best = i;
  EXPECT_NE(std::find(p.begin(), p.end(), best), p.end());
  EXPECT_EQ(r1::choose_pivots(ids, 600).size(), 500u);
}

TEST(Pivots, EstimateWithinItsStatedBound) {
  r1::GenParams gp;
  gp.kind = r1::GenKind::kBa;
  gp.n = 2000;
  gp.m = 3;
  const auto s = std::move(r1::generate(gp)).value();
  const auto g = graph_of(s);
  const auto exact = r1::betweenness(g, s.particles);
  ASSERT_TRUE(exact.exact);
  r1::BetweennessOptions opt;
  opt.pivots = 64;
  const auto est = r1::betweenness(g, s.particles, opt);
  ASSERT_FALSE(est.exact);
  ASSERT_EQ(est.sources, 64u);
  // delta = 1e-6 per particle: all 2000 hold together with probability >= 0.998 for random
  // pivots; the hashed pivots are fixed, so this either always or never passes.
  const double bound = r1::betweenness_error_bound(g.n, 64, 1e-6);
  double worst = 0, top = 0;
  std::uint32_t top_v = 0;
  for (std::uint32_t v = 0; v < g.n; ++v) {
    worst = std::max(worst, std::fabs(est.value[v] - exact.value[v]));
    if (exact.value[v] > top) top = exact.value[v], top_v = v;
  }
  EXPECT_LE(worst, bound);
  // The quantity the bridge rule uses, the largest values, is estimated well in relative terms.
  EXPECT_NEAR(est.value[top_v], top, 0.25 * top);
  // The budget rule: this graph needs n (n + nnz) > budget to switch to pivots.
  r1::BetweennessOptions small;
  small.budget = 1000;
  small.min_pivots = 10;
  const auto auto_est = r1::betweenness(g, s.particles, small);
  EXPECT_FALSE(auto_est.exact);
  EXPECT_EQ(auto_est.sources, 10u);
}

TEST(Roles, StarCentreIsHubAndLeavesAreLeaves) {
  std::vector<Edge> e;
  for (std::uint32_t i = 1; i < 10; ++i) e.push_back({0, i});
  const auto s = snapshot_of(10, e);
  const auto g = graph_of(s);
  const auto b = r1::betweenness(g, s.particles);
  r1::RoleStats st;
  const auto roles = r1::infer_roles(g, b.value, &st);
  EXPECT_EQ(roles[0], r1::Role::kHub);  // also the highest betweenness: hub takes precedence
  for (std::uint32_t i = 1; i < 10; ++i) EXPECT_EQ(roles[i], r1::Role::kLeaf);
  EXPECT_EQ(st.count[static_cast<int>(r1::Role::kHub)], 1u);
  EXPECT_EQ(st.count[static_cast<int>(r1::Role::kLeaf)], 9u);
}

TEST(Roles, PathBetweenCliquesIsBridges) {
  const auto s = snapshot_of(43, barbell());
  const auto g = graph_of(s);
  const auto b = r1::betweenness(g, s.particles);
  const auto roles = r1::infer_roles(g, b.value);
  for (std::uint32_t v : {19u, 20u, 21u, 22u, 23u}) EXPECT_EQ(roles[v], r1::Role::kBridge) << v;
  for (std::uint32_t v = 0; v < 19; ++v) EXPECT_EQ(roles[v], r1::Role::kNone) << v;
  for (std::uint32_t v = 24; v < 43; ++v) EXPECT_EQ(roles[v], r1::Role::kNone) << v;
}

TEST(Roles, UniformGraphsHaveNoHubsOrBridges) {
  std::vector<Edge> ring;
  for (std::uint32_t i = 0; i < 50; ++i) ring.push_back({i, (i + 1) % 50});
  r1::GenParams torus;
  torus.kind = r1::GenKind::kTorus;
  torus.dims = {5, 5, 5};
  for (const auto& s : {snapshot_of(50, ring), snapshot_of(10, clique(0, 10)), std::move(r1::generate(torus)).value()}) {
    const auto g = graph_of(s);
    const auto b = r1::betweenness(g, s.particles);
    for (const auto r : r1::infer_roles(g, b.value)) EXPECT_EQ(r, r1::Role::kNone);
  }
}

TEST(Roles, HubTestIsExactAtTheTie) {
  // Degrees (1, 1, 1, 1, x): x = mean + 2 sigma exactly for every x (A^2 = 4B), so never a hub.
  for (std::uint64_t x : {2u, 5u, 100u}) {
    const r1::u128 s1 = 4 + x, s2 = 4 + x * x;
    EXPECT_FALSE(r1::is_hub(x, 5, s1, s2)) << x;
  }
  // One more 1: now x exceeds mean + 2 sigma (A^2 = 25 (x-1)^2 > 4B = 20 (x-1)^2).
  for (std::uint64_t x : {2u, 5u, 100u}) EXPECT_TRUE(r1::is_hub(x, 6, 5 + x, 5 + x * x)) << x;
}

RC_GTEST_PROP(Roles, HubTestMatchesRealArithmeticAwayFromTies, ()) {
  const auto degrees = *rc::gen::nonEmpty(rc::gen::container<std::vector<std::uint32_t>>(rc::gen::inRange<std::uint32_t>(0, 1000)));
  r1::u128 s1 = 0, s2 = 0;
  long double m1 = 0, m2 = 0;
  for (auto d : degrees) {
    s1 += d;
    s2 += static_cast<r1::u128>(d) * d;
    m1 += d;
    m2 += static_cast<long double>(d) * d;
  }
  const long double n = static_cast<long double>(degrees.size());
  const long double mean = m1 / n, sd = std::sqrt(std::max(0.0L, m2 / n - mean * mean));
  for (auto d : degrees) {
    const long double margin = d - (mean + 2 * sd);
    if (std::fabs(margin) < 1e-6L) continue;
    RC_ASSERT(r1::is_hub(d, degrees.size(), s1, s2) == (margin > 0));
  }
}

}  // namespace
