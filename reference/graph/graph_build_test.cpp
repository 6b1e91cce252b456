// The layout graph: exact normalisation, symmetry, antisymmetric A2, degrees, components
// (decision 3, R1-IN-050..058).
#include "r1/reference/graph_build.hpp"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <boost/multiprecision/cpp_int.hpp>
#include <tbb/task_arena.h>

#include <map>
#include <random>

#include "r1/reference/snapshot_builder.hpp"
#include "graph_compare.hpp"

namespace {

using r1::u128;

struct L {
  const char* from;
  const char* to;
  std::uint64_t weight;  // whole units
  int valence;
};

r1::Snapshot make(const std::vector<L>& links) {
  r1::SnapshotBuilder b("test");
  b.snapshot().config = r1::text_input_config();
  for (const auto& l : links) {
    r1::Link k;
    k.height = 1;
    k.amount = static_cast<u128>(l.weight) << 32;
    k.valence = static_cast<std::int8_t>(l.valence);
    k.from = b.particle_by_name(l.from);
    k.to = b.particle_by_name(l.to);
    b.add_link(k);
  }
  return std::move(b.finish()).value();
}

std::int64_t entry(const r1::Graph& g, const std::vector<std::int64_t>& v, std::uint32_t i, std::uint32_t j) {
  for (std::uint64_t k = g.row_ptr[i]; k < g.row_ptr[i + 1]; ++k)
    if (g.col[k] == j) return v[k];
  return 0;
}

constexpr std::int64_t ONE = std::int64_t{1} << 32;

TEST(GraphBuild, SmallGraphExactValues) {
  // a->b 2 (+), b->a 1 (+), b->c 3 (-), c->c 5 (self-loop), c->a 1 (0)
  const auto s = make({{"a", "b", 2, 1}, {"b", "a", 1, 1}, {"b", "c", 3, -1}, {"c", "c", 5, 1}, {"c", "a", 1, 0}});
  auto r = r1::build_graph(s);
  ASSERT_TRUE(r.is_ok()) << r.status().message();
  const r1::Graph& g = *r;
  EXPECT_EQ(g.n, 3u);
  EXPECT_EQ(g.self_loops_dropped, 1u);
  EXPECT_EQ(g.nnz(), 6u);
  // A_sym: ab = 3, bc = 3, ca = 1; max 3 * 1000 (token per-mille) -> ab, bc = 1.0, ca = 1/3.
  EXPECT_EQ(entry(g, g.w, 0, 1), ONE);
  EXPECT_EQ(entry(g, g.w, 1, 2), ONE);
  EXPECT_EQ(entry(g, g.w, 2, 0), 1431655765);  // 2^32 / 3 = 1431655765.33 -> 1431655765
  EXPECT_EQ(g.weight_scale, (u128{3} << 32) * 1000);
  // A2(a, b) = +2 - (+1) = 1 -> 1/3; A2(b, c) = -3 -> -1; A2(c, a) = 0 (valence 0).
  EXPECT_EQ(entry(g, g.a2, 0, 1), 1431655765);
  EXPECT_EQ(entry(g, g.a2, 1, 0), -1431655765);
  EXPECT_EQ(entry(g, g.a2, 1, 2), -ONE);
  EXPECT_EQ(entry(g, g.a2, 2, 1), ONE);
  EXPECT_EQ(entry(g, g.a2, 2, 0), 0);
  // Directed A0: a->b = 2/3, b->a = 1/3, b->c = 1, c->a = 1/3.
  EXPECT_EQ(g.out_ptr, (std::vector<std::uint64_t>{0, 1, 3, 4}));
  EXPECT_EQ(g.out_w[0], 2863311531);  // 2^33 / 3 = 2863311530.67
  EXPECT_EQ(g.degree[0], static_cast<std::uint64_t>(ONE + 1431655765));
  EXPECT_EQ(g.component_size, (std::vector<std::uint32_t>{3}));
}

TEST(GraphBuild, ComponentsNumberedByLowestParticle) {
  const auto s = make({{"x", "y", 1, 0}, {"p", "q", 1, 0}, {"z", "z", 1, 0}, {"q", "r", 1, 0}, {"y", "w", 1, 0}});
  auto r = r1::build_graph(s);
  ASSERT_TRUE(r.is_ok());
  // Order: x y p q z r w.
  EXPECT_EQ(r->component, (std::vector<std::uint32_t>{0, 0, 1, 1, 2, 1, 0}));
  EXPECT_EQ(r->component_size, (std::vector<std::uint32_t>{3, 3, 1}));
}

TEST(GraphBuild, NoLinksAndOnlySelfLoopsAreErrors) {
  auto r = r1::build_graph(make({{"a", "a", 1, 0}}));
  ASSERT_FALSE(r.is_ok());
  EXPECT_NE(r.status().message().find("no links besides 1 self-loops"), std::string::npos);
}

// A_sym sums a pair's links in both directions exactly, from A0's weights; a sum that reaches
// 2^127 is an input error although each link's weight is below it.
TEST(GraphBuild, BothDirectionsSumExactlyAndTheirOverflowIsAnError) {
  const auto huge = [](u128 amount) {
    r1::SnapshotBuilder b("test");
    b.snapshot().config = r1::text_input_config();
    for (const auto& [from, to] : {std::pair{"a", "b"}, std::pair{"b", "a"}, std::pair{"b", "c"}}) {
      r1::Link k;
      k.height = 1;
      k.amount = amount;
      k.valence = 1;
      k.from = b.particle_by_name(from);
      k.to = b.particle_by_name(to);
      b.add_link(k);
    }
    return std::move(b.finish()).value();
  };
  // Each weight (amount x 1000 per mille) is just above 2^126: the pair a-b sums past 2^127.
  auto r = r1::build_graph(huge((u128{1} << 126) / 1000 + 1));
  ASSERT_FALSE(r.is_ok());
  EXPECT_NE(r.status().message().find("summed link weight of one particle pair reaches 2^127"), std::string::npos)
      << r.status().message();
  // Just below 2^125 each: the pair sums exactly to the scale (a-b is 1.0, b-c one half) and its
  // A2 cancels to 0.
  const u128 amount = (u128{1} << 125) / 1000 - 1;
  auto ok = r1::build_graph(huge(amount));
  ASSERT_TRUE(ok.is_ok()) << ok.status().message();
  EXPECT_EQ(ok->weight_scale, 2 * amount * 1000);
  EXPECT_EQ(entry(*ok, ok->w, 0, 1), ONE);
  EXPECT_EQ(entry(*ok, ok->w, 1, 2), ONE / 2);
  EXPECT_EQ(entry(*ok, ok->a2, 0, 1), 0);
  EXPECT_EQ(entry(*ok, ok->a2, 2, 1), -(ONE / 2));
}

TEST(GraphBuild, ScaleToQ32MatchesCppIntForHugeValues) {
  using boost::multiprecision::cpp_int;
  const u128 scale = (u128{1} << 126) + 12345;
  const u128 v = (u128{1} << 125) + 777;
  const std::int64_t q = r1::scale_to_q32(v, scale);
  const cpp_int num = ((cpp_int(1) << 125) + 777) << 32, den = (cpp_int(1) << 126) + 12345;
  cpp_int e = num / den;
  const cpp_int rem = num - e * den;
  if (rem * 2 > den || (rem * 2 == den && (e & 1) != 0)) ++e;
  EXPECT_EQ(cpp_int(q), e);
  EXPECT_EQ(r1::scale_to_q32(scale, scale), ONE);
  EXPECT_EQ(r1::scale_to_q32(1, 2), ONE / 2);
  EXPECT_EQ(r1::scale_to_q32(1, u128{1} << 33), 0);  // exactly half a unit: ties to even (0)
  EXPECT_EQ(r1::scale_to_q32(3, u128{1} << 33), 2);  // 1.5 units: ties to even (2)
}

// Random snapshots: the invariants every later stage relies on.
RC_GTEST_PROP(GraphBuild, InvariantsOnRandomSnapshots, ()) {
  const int n = *rc::gen::inRange(2, 12);
  const int m = *rc::gen::inRange(1, 40);
  r1::SnapshotBuilder b("rc");
  b.snapshot().config = r1::text_input_config();
  b.snapshot().config.tokens[1] = {"t1", 250};
  for (int i = 0; i < m; ++i) {
    r1::Link k;
    k.height = 1;
    k.amount = *rc::gen::inRange<std::uint64_t>(1, std::uint64_t{1} << 50);
    k.token = *rc::gen::inRange(0, 2);
    k.valence = static_cast<std::int8_t>(*rc::gen::inRange(-1, 2));
    k.from = b.particle_by_name("v" + std::to_string(*rc::gen::inRange(0, n)));
    k.to = b.particle_by_name("v" + std::to_string(*rc::gen::inRange(0, n)));
    b.add_link(k);
  }
  auto snap = b.finish();
  RC_ASSERT(snap.is_ok());
  auto r = r1::build_graph(*snap);
  if (!r.is_ok()) {
    RC_ASSERT(r.status().message().find("self-loops") != std::string::npos);
    return;
  }
  const r1::Graph& g = *r;
  std::int64_t wmax = 0;
  for (std::uint32_t i = 0; i < g.n; ++i) {
    std::uint64_t deg = 0;
    for (std::uint64_t k = g.row_ptr[i]; k < g.row_ptr[i + 1]; ++k) {
      const std::uint32_t j = g.col[k];
      RC_ASSERT(j != i);
      if (k > g.row_ptr[i]) RC_ASSERT(g.col[k - 1] < j);  // sorted, merged
      RC_ASSERT(g.w[k] >= 1);
      RC_ASSERT(g.w[k] <= ONE);
      RC_ASSERT(entry(g, g.w, j, i) == g.w[k]);     // symmetric
      RC_ASSERT(entry(g, g.a2, j, i) == -g.a2[k]);  // antisymmetric
      RC_ASSERT(std::abs(g.a2[k]) <= g.w[k]);
      RC_ASSERT(g.component[j] == g.component[i]);
      deg += static_cast<std::uint64_t>(g.w[k]);
      wmax = std::max(wmax, g.w[k]);
    }
    RC_ASSERT(g.degree[i] == deg);
    if (i > 0) RC_ASSERT(g.component[i] <= *std::max_element(g.component.begin(), g.component.begin() + i) + 1);
  }
  RC_ASSERT(wmax == ONE);  // the largest A_sym entry normalises to exactly 1.0
  // The same links in another order (particle table fixed) give the same graph.
  r1::Snapshot shuffled = *snap;
  std::reverse(shuffled.links.begin(), shuffled.links.end());
  auto r2 = r1::build_graph(shuffled);
  RC_ASSERT(r2.is_ok());
  RC_ASSERT(r2->col == g.col);
  RC_ASSERT(r2->w == g.w);
  RC_ASSERT(r2->a2 == g.a2);
  RC_ASSERT(r2->out_w == g.out_w);
}

// RNE(v 2^32 / scale) in cpp_int, v >= 0: the normalisation of R1-IN-052 computed apart from
// scale_to_q32.
std::int64_t rne_q32(const boost::multiprecision::cpp_int& v, const boost::multiprecision::cpp_int& scale) {
  using boost::multiprecision::cpp_int;
  const cpp_int num = v << 32;
  cpp_int q = num / scale;
  const cpp_int r = num - q * scale;
  if (r * 2 > scale || (r * 2 == scale && (q & 1) != 0)) ++q;
  return static_cast<std::int64_t>(q);
}

// A graph of many row blocks, built on four workers and on one, against the exact sums of an
// ordered map: parallel links, both directions, two tokens, every valence, a hub.
TEST(GraphBuild, ParallelRowsGiveTheSerialGraphAndTheExactSums) {
  using boost::multiprecision::cpp_int;
  constexpr int n = 40000, m = 200000;  // past spectral::kParallelMin rows: the blocks run on workers
  std::mt19937_64 rng(7);
  r1::SnapshotBuilder b("blocks");
  b.snapshot().config = r1::text_input_config();
  b.snapshot().config.tokens[1] = {"t1", 250};
  std::vector<std::uint32_t> ids(n);
  for (int i = 0; i < n; ++i) ids[static_cast<std::size_t>(i)] = b.particle_by_name("p" + std::to_string(i));
  // (from, to) -> exact A0 weight and signed A2 contribution.
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::pair<cpp_int, cpp_int>> a0;
  for (int k = 0; k < m; ++k) {
    r1::Link l;
    l.height = 1;
    l.amount = (static_cast<u128>(rng() >> 20) << 20) + (rng() & 0xFFFFF) + 1;
    l.token = static_cast<std::uint32_t>(rng() % 2);
    l.valence = static_cast<std::int8_t>(static_cast<int>(rng() % 3) - 1);
    // Particle 35000 is a hub, and its pair with 35001 (every 77th link) is the heaviest: the scale
    // comes from a late row block.
    const auto from = static_cast<std::uint32_t>(k % 7 == 0 ? 35000 : rng() % n);
    auto to = static_cast<std::uint32_t>(rng() % n);
    if (k % 11 == 0) to = (from + 1) % n;  // repeats: parallel links and reverse pairs
    l.from = ids[from];
    l.to = ids[to];
    b.add_link(l);
    if (from == to) continue;
    const cpp_int w = cpp_int(l.amount) * b.snapshot().config.tokens.at(l.token).weight_permille;
    auto& e = a0[{l.from, l.to}];
    e.first += w;
    e.second += l.valence > 0 ? w : l.valence < 0 ? cpp_int(-w) : cpp_int(0);
  }
  auto snap = b.finish();
  ASSERT_TRUE(snap.is_ok());
  auto serial = r1::build_graph(*snap, {}, false);
  std::optional<r1::Result<r1::Graph>> parallel;
  tbb::task_arena four(4);
  four.execute([&] { parallel.emplace(r1::build_graph(*snap, {}, true)); });
  ASSERT_TRUE(serial.is_ok()) << serial.status().message();
  ASSERT_TRUE(parallel->is_ok()) << parallel->status().message();
  const r1::Graph& g = *serial;
  r1::test::expect_same_graph(**parallel, g);
  // The build that releases the link records as soon as it holds them (R1-EPO-005): the same
  // graph, and no records left.
  r1::Snapshot spent = *snap;
  auto released = r1::build_graph_releasing_links(spent);
  ASSERT_TRUE(released.is_ok()) << released.status().message();
  r1::test::expect_same_graph(*released, g);
  EXPECT_TRUE(spent.links.empty());

  // A_sym = A0 + A0^T, A2 antisymmetric, normalised by the largest A_sym entry.
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::pair<cpp_int, cpp_int>> sym;
  for (const auto& [key, e] : a0) {
    auto& f = sym[key];
    f.first += e.first;
    f.second += e.second;
    auto& r = sym[{key.second, key.first}];
    r.first += e.first;
    r.second -= e.second;
  }
  cpp_int scale = 0;
  for (const auto& [key, e] : sym) scale = std::max(scale, e.first);
  EXPECT_TRUE(cpp_int(g.weight_scale) == scale);
  ASSERT_EQ(g.nnz(), sym.size());
  auto it = sym.begin();
  for (std::uint32_t i = 0; i < g.n; ++i)
    for (std::uint64_t k = g.row_ptr[i]; k < g.row_ptr[i + 1]; ++k, ++it) {
      ASSERT_EQ(it->first, std::make_pair(i, g.col[k]));
      ASSERT_EQ(g.w[k], std::max<std::int64_t>(1, rne_q32(it->second.first, scale))) << i << ' ' << g.col[k];
      const cpp_int& a2 = it->second.second;
      const std::int64_t mag = a2 == 0 ? 0 : rne_q32(a2 < 0 ? cpp_int(-a2) : a2, scale);
      ASSERT_EQ(g.a2[k], a2 < 0 ? -mag : mag) << i << ' ' << g.col[k];
    }
  auto ot = a0.begin();
  for (std::uint32_t i = 0; i < g.n; ++i)
    for (std::uint64_t k = g.out_ptr[i]; k < g.out_ptr[i + 1]; ++k, ++ot) {
      ASSERT_EQ(ot->first, std::make_pair(i, g.out_col[k]));
      ASSERT_EQ(g.out_w[k], std::max<std::int64_t>(1, rne_q32(ot->second.first, scale)));
    }
  EXPECT_TRUE(ot == a0.end());
}

// An overflowing pair deep in a graph of many row blocks is the same error on four workers.
TEST(GraphBuild, ParallelRowsReportTheOverflow) {
  r1::SnapshotBuilder b("overflow");
  b.snapshot().config = r1::text_input_config();
  constexpr int n = 40000;
  std::vector<std::uint32_t> ids(n);
  for (int i = 0; i < n; ++i) ids[static_cast<std::size_t>(i)] = b.particle_by_name("p" + std::to_string(i));
  for (int i = 0; i + 1 < n; ++i) {
    r1::Link l;
    l.height = 1;
    l.amount = 1;
    l.from = ids[static_cast<std::size_t>(i)];
    l.to = ids[static_cast<std::size_t>(i + 1)];
    b.add_link(l);
  }
  // Each direction alone stays below 2^127 (after the token's per-mille weight); their sum does not.
  for (const bool reverse : {false, true}) {
    r1::Link l;
    l.height = 1;
    l.amount = (u128{1} << 126) / 1000 + 1;
    l.from = ids[reverse ? 35001 : 35000];
    l.to = ids[reverse ? 35000 : 35001];
    b.add_link(l);
  }
  auto snap = b.finish();
  ASSERT_TRUE(snap.is_ok());
  std::optional<r1::Result<r1::Graph>> r;
  tbb::task_arena four(4);
  four.execute([&] { r.emplace(r1::build_graph(*snap, {}, true)); });
  ASSERT_FALSE(r->is_ok());
  EXPECT_EQ(r->status().message(), "overflow: summed link weight of one particle pair reaches 2^127");
  auto s1 = r1::build_graph(*snap, {}, false);
  ASSERT_FALSE(s1.is_ok());
  EXPECT_EQ(s1.status().message(), r->status().message());
}

}  // namespace
