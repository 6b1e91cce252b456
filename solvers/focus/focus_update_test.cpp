// The local focus update of incremental epochs (R1-INC-050..053): with the region every particle it
// is the full iteration bit for bit; after an edit it moves phi toward the edited graph's fixed
// point; threads do not change its bits; bad input is an input error. The conservation property
// on random graphs is with the other properties in focus_test.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "focus_operators.hpp"
#include "r1/reference/edits.hpp"
#include "r1/reference/generate.hpp"
#include "r1/reference/graph_build.hpp"
#include "r1/reference/incremental.hpp"
#include "r1/solvers/focus.hpp"

namespace {

using r1::Graph;
using r1::Q32;
using r1::TriKernelParams;
using r1::u128;

constexpr std::int64_t ONE = std::int64_t{1} << 32;

Graph graph_of(const r1::Snapshot& s) {
  auto g = r1::build_graph(s);
  EXPECT_TRUE(g.is_ok()) << g.status().message();
  return std::move(g).value();
}

r1::Snapshot generated(r1::GenKind kind, std::int64_t n, std::uint64_t seed, std::optional<std::int64_t> m = {}) {
  r1::GenParams p;
  p.kind = kind;
  p.n = n;
  p.m = m;
  p.seed = seed;
  auto s = r1::generate(p);
  EXPECT_TRUE(s.is_ok()) << s.status().message();
  return std::move(s).value();
}

std::vector<Q32> start_of(const Graph& g, const TriKernelParams& p) {
  auto ops = r1::focus::OperatorsQ32::build(g, p, false);
  EXPECT_TRUE(ops.is_ok());
  return r1::project_to_simplex_q32(ops->prior());  // R1-FOC-012
}

// The exact heat term of the start (what an epoch carries for its own phi, R1-INC-052).
std::vector<Q32> heat_of(const Graph& g, const TriKernelParams& p, const std::vector<Q32>& x) {
  auto h = r1::heat_term_q32(g, p, x);
  EXPECT_TRUE(h.is_ok()) << h.status().message();
  return std::move(h).value();
}

// The start of an update: phi and its heat, with the exact sum of phi ln phi when `carried`
// (R1-INC-054).
r1::Focus<Q32> start_focus(const std::vector<Q32>& phi, const std::vector<Q32>& heat, bool carried = true) {
  r1::Focus<Q32> f;
  f.phi = phi;
  f.heat = heat;
  if (carried) {
    f.plogp.emplace();
    for (const Q32 x : phi) f.plogp->add_term(r1::phi_log_phi(x));
  }
  return f;
}

double l1(const std::vector<Q32>& a, const std::vector<Q32>& b) {
  double s = 0;
  for (std::size_t i = 0; i < a.size(); ++i) s += std::fabs(static_cast<double>(a[i].raw - b[i].raw)) * 0x1p-32;
  return s;
}

std::string sci(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3e", x);
  return buf;
}

TEST(FocusUpdate, WholeRegionIsTheFullIteration) {
  for (const auto& [kind, n, m] : {std::tuple{r1::GenKind::kBa, 2000, 3}, std::tuple{r1::GenKind::kRgg, 1500, 0},
                                   std::tuple{r1::GenKind::kSbm, 600, 0}}) {
    const Graph g = graph_of(generated(kind, n, 5, m ? std::optional<std::int64_t>(m) : std::nullopt));
    TriKernelParams p;
    std::vector<std::uint32_t> all(g.n);
    for (std::uint32_t i = 0; i < g.n; ++i) all[i] = i;
    r1::FocusOptions par;
    par.parallel = true;
    const auto full = r1::compute_focus_q32(g, p, 0.25);
    const std::vector<Q32> start = start_of(g, p), heat = heat_of(g, p, start);
    const auto local = r1::update_focus_q32(g, p, 0.25, start_focus(start, heat), all);
    const auto local_par = r1::update_focus_q32(g, p, 0.25, start_focus(start, heat, false), all, {}, par);
    ASSERT_TRUE(full.is_ok() && local.is_ok() && local_par.is_ok()) << local.status().message();
    EXPECT_EQ(local->phi, full->phi) << "n " << g.n;
    EXPECT_EQ(local_par->phi, full->phi);
    EXPECT_EQ(local->steps, full->steps);
    // The syntropy's exact sum, carried from the start's or summed over every particle.
    EXPECT_EQ(local->plogp, full->plogp);
    EXPECT_EQ(local_par->plogp, full->plogp);
    EXPECT_EQ(local->syntropy, full->syntropy);
    EXPECT_EQ(local_par->syntropy, full->syntropy);
    EXPECT_EQ(local->cyberank, full->cyberank);
    // The carried heat is the heat of the result, as a full epoch's.
    EXPECT_EQ(local->heat, full->heat);
    EXPECT_EQ(full->heat, heat_of(g, p, full->phi));
  }
}

// A reweighted link and an added one in a 3000-particle geometric graph: the update on the h-hop
// region, from the earlier epoch's phi and carried heat, moves phi toward the edited graph's fixed
// point, more than half the way at h = 4 (L1 distances recorded).
// The summary build_graph files in the graph (R1-IN-059) against an independent largest-remainder
// apportionment (u128 quotients, a full sort of the remainders), a scan of the out-rows and of the
// degrees; and the focus, full and local, gives the same bits with it as without it.
TEST(FocusUpdate, TheGraphsSummaryIsItsArraysAndChangesNoBit) {
  for (const auto& [kind, seed] : {std::pair{r1::GenKind::kBa, 4ull}, std::pair{r1::GenKind::kSbm, 5ull}}) {
    const Graph g = graph_of(generated(kind, 1500, seed));
    ASSERT_TRUE(g.summarised());
    u128 total = 0;
    for (const std::uint64_t d : g.degree) total += d;
    std::vector<std::int64_t> share(g.n);
    std::vector<std::pair<u128, std::uint32_t>> rem(g.n);
    u128 given = 0;
    for (std::uint32_t i = 0; i < g.n; ++i) {
      const u128 num = static_cast<u128>(g.degree[i]) << 32;
      share[i] = static_cast<std::int64_t>(num / total);
      given += num / total;
      rem[i] = {num % total, i};
    }
    std::sort(rem.begin(), rem.end(),
              [](const auto& x, const auto& y) { return x.first != y.first ? x.first > y.first : x.second < y.second; });
    for (u128 k = 0; k < (u128{1} << 32) - given; ++k) ++share[rem[static_cast<std::size_t>(k)].second];
    EXPECT_EQ(g.prior, share);
    std::vector<std::uint32_t> dangling;
    for (std::uint32_t i = 0; i < g.n; ++i)
      if (g.out_ptr[i] == g.out_ptr[i + 1]) dangling.push_back(i);
    EXPECT_EQ(g.dangling, dangling);
    EXPECT_EQ(g.max_degree, *std::max_element(g.degree.begin(), g.degree.end()));

    Graph bare = g;
    bare.prior.clear();
    bare.dangling.clear();
    bare.max_degree = 0;
    ASSERT_FALSE(bare.summarised());
    TriKernelParams p;
    const auto full = r1::compute_focus_q32(g, p, 0.2), full_bare = r1::compute_focus_q32(bare, p, 0.2);
    ASSERT_TRUE(full.is_ok() && full_bare.is_ok());
    EXPECT_EQ(full->phi, full_bare->phi);
    EXPECT_EQ(full->steps, full_bare->steps);
    const std::vector<std::uint32_t> region = r1::neighbourhood(g, {dangling.empty() ? 7u : dangling[0], 40u}, 1);
    const auto local = r1::update_focus_q32(g, p, 0.2, *full, region);
    const auto local_bare = r1::update_focus_q32(bare, p, 0.2, *full, region);
    ASSERT_TRUE(local.is_ok() && local_bare.is_ok());
    EXPECT_EQ(local->phi, local_bare->phi);
    EXPECT_EQ(local->heat, local_bare->heat);

    // A start known to be on the simplex, with its places (R1-INC-051, R1-FOC-072), against one
    // that is not: the same phi, and the places a full ranking of the result finds; with the
    // region far from the top places (their update is local) and holding the first of them (one
    // pass over phi).
    ASSERT_TRUE(full->on_simplex);
    ASSERT_EQ(full->cyberank, r1::cyberank_places(full->phi));
    r1::Focus<Q32> unknown = *full;
    unknown.on_simplex = false;
    unknown.cyberank.clear();
    // The particle of least phi: far from the places.
    const auto low = static_cast<std::uint32_t>(std::min_element(full->phi.begin(), full->phi.end()) - full->phi.begin());
    for (const std::vector<std::uint32_t>& r : {std::vector<std::uint32_t>{low}, r1::neighbourhood(g, {full->cyberank[0]}, 1)}) {
      const auto known = r1::update_focus_q32(g, p, 0.2, *full, r), plain = r1::update_focus_q32(g, p, 0.2, unknown, r);
      ASSERT_TRUE(known.is_ok() && plain.is_ok());
      EXPECT_EQ(known->phi, plain->phi);
      EXPECT_EQ(known->cyberank, r1::cyberank_places(known->phi));
      EXPECT_EQ(plain->cyberank, known->cyberank);
      EXPECT_TRUE(known->on_simplex);
    }
  }
}

TEST(FocusUpdate, ApproachesTheEditedFixedPoint) {
  const r1::Snapshot s = generated(r1::GenKind::kRgg, 3000, 3);
  const Graph g0 = graph_of(s);
  // The first link of particle 0, reweighted to a tenth, and a new link between two neighbours of
  // neighbours: particles keep their order (both endpoints exist).
  const std::uint32_t a = 0, b = g0.col[g0.row_ptr[0]];
  const std::uint32_t c = g0.col[g0.row_ptr[b + 1] - 1];
  const std::string edits = "reweight\t" + s.names[a] + "\t" + s.names[b] + "\t0.1\n" + "add\t" + s.names[a] + "\t" +
                            s.names[c == a ? b : c] + "\t1\n";
  auto parsed = r1::parse_edits(edits, "batch");
  ASSERT_TRUE(parsed.is_ok()) << parsed.status().message();
  auto next = r1::apply_edits(s, *parsed, "batch");
  ASSERT_TRUE(next.is_ok()) << next.status().message();
  ASSERT_EQ(next->particles, s.particles);
  const Graph g1 = graph_of(*next);
  TriKernelParams p;
  // Converged well past the edit's effect, so that the distances measure the locality alone.
  p.eps = Q32::from_raw(4);
  const auto before = r1::compute_focus_q32(g0, p, 0.01);
  const auto after = r1::compute_focus_q32(g1, p, 0.01);
  ASSERT_TRUE(before.is_ok() && after.is_ok());
  std::vector<std::uint32_t> touched;
  for (std::uint32_t i = 0; i < g1.n; ++i)
    if (g1.degree[i] != g0.degree[i]) touched.push_back(i);
  ASSERT_FALSE(touched.empty());
  const double moved = l1(before->phi, after->phi);
  for (const std::uint32_t h : {1u, 2u, 4u}) {
    const auto region = r1::neighbourhood(g1, touched, h);
    // The heat the earlier epoch carries: its own phi's on its own graph.
    const auto local = r1::update_focus_q32(g1, p, 0.01, *before, region);
    ASSERT_TRUE(local.is_ok()) << local.status().message();
    // The carried sum equals a pass over the result (R1-INC-054).
    const auto whole = r1::update_focus_q32(g1, p, 0.01, start_focus(local->phi, local->heat, false), {});
    ASSERT_TRUE(whole.is_ok());
    EXPECT_EQ(local->plogp, whole->plogp);
    EXPECT_EQ(local->syntropy, whole->syntropy);
    const double left = l1(local->phi, after->phi);
    RecordProperty("l1_left_h" + std::to_string(h), sci(left) + " of " + sci(moved) + ", region " + std::to_string(region.size()));
    // Measured: 53% (h = 1), 48% (h = 2), 41% (h = 4) of the distance is left: mass that the new
    // link draws from the frozen particles, which keep their bits by R1-INC-050, and the edit's
    // direct effect on the heat term at the start, which the carried heat does not see
    // (R1-INC-052; with the exact heat of the start over its whole reach: 38%, 33%, 25%).
    EXPECT_LT(left, 0.6 * moved) << "h " << h;
    if (h == 4) {
      EXPECT_LT(left, 0.45 * moved);
    }
    r1::FocusOptions par;
    par.parallel = true;
    const auto again = r1::update_focus_q32(g1, p, 0.01, *before, region, {}, par);
    ASSERT_TRUE(again.is_ok());
    EXPECT_EQ(again->phi, local->phi);
  }
}

TEST(FocusUpdate, BadInputIsAnInputError) {
  const Graph g = graph_of(generated(r1::GenKind::kRing, 12, 1));
  TriKernelParams p;
  const std::vector<Q32> start = start_of(g, p), heat = heat_of(g, p, start);
  const auto bad_order = r1::update_focus_q32(g, p, 0.1, start_focus(start, heat), std::vector<std::uint32_t>{3, 2});
  ASSERT_FALSE(bad_order.is_ok());
  EXPECT_NE(bad_order.status().message().find("out of order"), std::string::npos);
  // No region (an empty batch): the start, bit for bit, when it is a focus; else an input error.
  const auto none = r1::update_focus_q32(g, p, 0.1, start_focus(start, heat), std::vector<std::uint32_t>{});
  ASSERT_TRUE(none.is_ok()) << none.status().message();
  EXPECT_EQ(none->phi, start);
  std::vector<Q32> short_start = start;
  short_start[0] = Q32::from_raw(short_start[0].raw - 1);
  EXPECT_FALSE(r1::update_focus_q32(g, p, 0.1, start_focus(short_start, heat), std::vector<std::uint32_t>{}).is_ok());
  EXPECT_FALSE(r1::update_focus_q32(g, p, 0.1, start_focus(start, heat), std::vector<std::uint32_t>{12}).is_ok());
  EXPECT_FALSE(r1::update_focus_q32(g, p, 0.1, start_focus(std::vector<Q32>(11, Q32::from_raw(1)), heat), std::vector<std::uint32_t>{0}).is_ok());
  // Frozen particles that hold all 2^32 raws leave nothing for the region.
  std::vector<Q32> greedy(g.n, Q32::from_raw(1));
  greedy[0] = Q32::from_raw(ONE - static_cast<std::int64_t>(g.n) + 2);
  const auto starved = r1::update_focus_q32(g, p, 0.1, start_focus(greedy, heat), std::vector<std::uint32_t>{5, 6});
  ASSERT_FALSE(starved.is_ok());
  EXPECT_NE(starved.status().message().find("fewer than one"), std::string::npos);
  // The heat must come with every particle.
  const auto no_heat = r1::update_focus_q32(g, p, 0.1, start_focus(start, std::vector<Q32>(3)), std::vector<std::uint32_t>{5});
  ASSERT_FALSE(no_heat.is_ok());
  EXPECT_NE(no_heat.status().message().find("3 start heat values for 12 particles"), std::string::npos) << no_heat.status().message();
  // A frozen raw below 1 is not a focus.
  std::vector<Q32> zero = start;
  zero[1] = Q32::from_raw(0);
  EXPECT_FALSE(r1::update_focus_q32(g, p, 0.1, start_focus(zero, heat), std::vector<std::uint32_t>{5}).is_ok());
}

}  // namespace
