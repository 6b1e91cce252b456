// Parking the layout graph during the spectral solve (R1-EPO-006): the arrays come back bit for
// bit, the solve's own arrays are never touched, and an epoch that parks gives the same bytes.
#include "r1/reference/graph_park.hpp"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <random>

#include "r1/reference/epoch.hpp"
#include "r1/reference/epoch_io.hpp"
#include "r1/reference/generate.hpp"
#include "r1/reference/graph_build.hpp"
#include "r1/reference/snapshot_builder.hpp"
#include "r1/solvers/spectral.hpp"
#include "graph_compare.hpp"

namespace {

r1::Snapshot ba_snapshot(std::int64_t n, std::int64_t m) {
  r1::GenParams p;
  p.kind = r1::GenKind::kBa;
  p.n = n;
  p.m = m;
  auto s = r1::generate(p);
  EXPECT_TRUE(s.is_ok()) << s.status().message();
  return std::move(*s);
}

r1::Graph graph_of(const r1::Snapshot& s) {
  auto g = r1::build_graph(s);
  EXPECT_TRUE(g.is_ok()) << g.status().message();
  return std::move(*g);
}

TEST(GraphPark, RestoresEveryArrayBitForBitAndKeepsWhatTheSolveReads) {
  for (const bool parallel : {false, true}) {
    const r1::Graph original = graph_of(ba_snapshot(20000, 4));  // several chunks per parked array
    r1::Graph g = original;
    auto parked = r1::ParkedGraph::park(g, parallel);
    ASSERT_TRUE(parked.is_ok()) << parked.status().message();
    // Released: the parked arrays hold nothing; the solve's arrays are untouched.
    EXPECT_TRUE(g.w.empty() && g.a2.empty() && g.out_ptr.empty() && g.out_col.empty() && g.out_w.empty() &&
                g.prior.empty() && g.dangling.empty() && g.component.empty());
    EXPECT_EQ(g.row_ptr, original.row_ptr);
    EXPECT_EQ(g.col, original.col);
    EXPECT_EQ(g.degree, original.degree);
    EXPECT_EQ(g.component_size, original.component_size);
    const std::uint64_t raw = 8 * (original.w.size() + original.a2.size() + original.out_ptr.size() +
                                   original.out_w.size() + original.prior.size()) +
                              4 * (original.out_col.size() + original.dangling.size() + original.component.size());
    EXPECT_EQ(parked->raw_bytes(), raw);
    // A BA graph's weights are all one and its A2 is +-w: far below a tenth of the raw bytes.
    EXPECT_LT(parked->packed_bytes() * 4, parked->raw_bytes()) << parked->packed_bytes();
    ASSERT_TRUE(parked->restore(g, parallel).is_ok());
    EXPECT_TRUE(parked->empty());
    r1::test::expect_same_graph(g, original);
    // Restoring again changes nothing.
    ASSERT_TRUE(parked->restore(g, parallel).is_ok());
    r1::test::expect_same_graph(g, original);
  }
}

// Arrays of random raws (the worst case for compression) and of every length around a chunk's
// boundary come back exactly.
RC_GTEST_PROP(GraphPark, RandomArraysComeBackExactly, ()) {
  const auto seed = *rc::gen::arbitrary<std::uint64_t>();
  const std::size_t len = *rc::gen::oneOf(rc::gen::inRange<std::size_t>(0, 300),
                                          rc::gen::inRange<std::size_t>((1 << 17) - 3, (1 << 17) + 3),
                                          rc::gen::inRange<std::size_t>((1 << 18) - 3, (1 << 18) + 3));
  std::mt19937_64 rng(seed);
  r1::Graph g;
  g.n = 3;
  g.w.resize(len);
  g.a2.resize(len / 2 + 1);
  g.out_col.resize(len);
  g.dangling.resize(len % 7);
  for (auto& x : g.w) x = static_cast<std::int64_t>(rng());
  for (auto& x : g.a2) x = static_cast<std::int64_t>(rng() % 1000) - 500;
  for (auto& x : g.out_col) x = static_cast<std::uint32_t>(rng());
  for (auto& x : g.dangling) x = static_cast<std::uint32_t>(rng() % 5);
  const r1::Graph original = g;
  auto parked = r1::ParkedGraph::park(g, (seed & 1) != 0);
  RC_ASSERT(parked.is_ok());
  RC_ASSERT(g.w.empty());
  RC_ASSERT(parked->restore(g, (seed & 2) != 0).is_ok());
  RC_ASSERT(g.w == original.w);
  RC_ASSERT(g.a2 == original.a2);
  RC_ASSERT(g.out_col == original.out_col);
  RC_ASSERT(g.dangling == original.dangling);
}

// An epoch whose caller parks the graph while the spectral stage solves writes the same bytes as
// one that does not, and the hooks run once each, in order.
TEST(GraphPark, AnEpochThatParksWritesTheSameBytes) {
  const r1::Snapshot s = ba_snapshot(3000, 3);
  const r1::Graph g0 = graph_of(s);
  r1::Graph g = g0;
  r1::EpochOptions o;
  o.parallel = true;
  auto plain = r1::run_epoch(s, g0, o);
  ASSERT_TRUE(plain.is_ok()) << plain.status().message();

  r1::ParkedGraph parked;
  int ready = 0, done = 0;
  bool parked_when_done = false;
  o.spectral_operator_ready = [&] {
    ++ready;
    auto got = r1::ParkedGraph::park(g, true);
    ASSERT_TRUE(got.is_ok());
    parked = std::move(*got);
  };
  o.spectral_done = [&] {
    ++done;
    parked_when_done = g.w.empty() && !parked.empty();
    return parked.restore(g, true);
  };
  auto e = r1::run_epoch(s, g, o);
  ASSERT_TRUE(e.is_ok()) << e.status().message();
  EXPECT_EQ(ready, 1);
  EXPECT_EQ(done, 1);
  EXPECT_TRUE(parked_when_done);
  r1::test::expect_same_graph(g, g0);
  plain->timings.clear();  // the manifest's timings differ from run to run
  e->timings.clear();
  auto a = r1::epoch_files(*plain);
  auto b = r1::epoch_files(*e);
  ASSERT_TRUE(a.is_ok() && b.is_ok());
  EXPECT_EQ(*a, *b);

  // A spectral_done error ends the epoch with that error.
  o.spectral_operator_ready = nullptr;
  o.spectral_done = [] { return r1::Status::internal("graph park: test"); };
  auto failed = r1::run_epoch(s, g, o);
  ASSERT_FALSE(failed.is_ok());
  EXPECT_NE(failed.status().message().find("graph park: test"), std::string::npos);
}

// `r1 spectrum` lets the arrays park() would park go once the operator is formed (R1-SPEC-077):
// the solve must give the same spectrum without them, in both domains, serial and parallel.
TEST(GraphPark, TheSpectralSolveReadsNoReleasedArray) {
  const r1::Graph g0 = graph_of(ba_snapshot(3000, 3));
  r1::SpectralParams p;
  for (const bool parallel : {false, true}) {
    r1::SpectralOptions plain;
    plain.parallel = parallel;
    r1::Graph g = g0;
    r1::SpectralOptions releasing = plain;
    int ready = 0;
    releasing.operator_ready = [&] {
      ++ready;
      r1::release_unread_by_spectral(g);
    };
    auto a = r1::spectral_embedding_q32(g0, p, {}, plain);
    auto b = r1::spectral_embedding_q32(g, p, {}, releasing);
    ASSERT_TRUE(a.is_ok() && b.is_ok());
    EXPECT_EQ(ready, 1);
    EXPECT_TRUE(g.w.empty() && g.a2.empty() && g.out_ptr.empty() && g.out_col.empty() && g.out_w.empty() &&
                g.prior.empty() && g.dangling.empty() && g.component.empty());
    EXPECT_EQ(a->eigenvalues, b->eigenvalues);
    EXPECT_EQ(a->residuals, b->residuals);
    EXPECT_EQ(a->u, b->u);
    EXPECT_EQ(a->image, b->image);

    g = g0;
    auto c = r1::spectral_embedding_f64(g0, p, {}, plain);
    auto d = r1::spectral_embedding_f64(g, p, {}, releasing);
    ASSERT_TRUE(c.is_ok() && d.is_ok());
    EXPECT_EQ(ready, 2);
    EXPECT_TRUE(g.w.empty() && g.out_col.empty());
    EXPECT_EQ(c->eigenvalues, d->eigenvalues);
    EXPECT_EQ(c->u, d->u);
  }
}

}  // namespace
