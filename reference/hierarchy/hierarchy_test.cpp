// The spatial hierarchy: the k-d tree and the leader rule against brute force, nesting, caps,
// partitions, tight AABBs, exact phi, canonical ids, colours, radii, the r_0 bisection,
// determinism and permutation invariance, counts per level, the parallel switch and the fast
// paths (R1-HIER-001..061, R1-HIER-070..071).
#include "r1/reference/hierarchy.hpp"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <boost/multiprecision/cpp_bin_float.hpp>
#include <boost/multiprecision/cpp_int.hpp>
#include <map>
#include <numeric>
#include <optional>
#include <set>

#include "hierarchy_test_data.hpp"
#include "kd_tree.hpp"
#include "levels.hpp"
#include "radius_search.hpp"

namespace {

using r1::Color;
using r1::Hierarchy;
using r1::i128;
using r1::ParticleId;
using r1::Q32;
using r1::u128;
using r1::hier_test::kUnit;
using r1::hier_test::Layout;
using r1::hier_test::make_layout;
using r1::hier_test::Shape;

r1::Result<Hierarchy> build(const Layout& L, r1::HierarchyOptions opt = {}) {
  return r1::build_hierarchy(L.pos, L.phi, L.color, L.ids, opt);
}

Hierarchy build_ok(const Layout& L, r1::HierarchyOptions opt = {}) {
  auto h = build(L, opt);
  EXPECT_TRUE(h.is_ok()) << h.status().message();
  return h.is_ok() ? std::move(h).value() : Hierarchy{};
}

// The invariants the brief names, asserted directly (check_hierarchy is a second, shared checker).
void expect_structure(const Hierarchy& h, const Layout& L) {
  const std::size_t n = L.pos.size();
  for (std::size_t l = 0; l < r1::kLevels; ++l) {
    ASSERT_EQ(h.cluster_of[l].size(), n);
    std::vector<int> seen(n, 0);
    std::int64_t level_phi = 0;
    for (const auto& node : h.levels[l]) {
      EXPECT_GE(node.children.size(), 1u);
      EXPECT_LE(node.children.size(), 16u);
      level_phi += node.phi_raw;
      if (l == 0)
        for (const auto p : node.children) ++seen[p];
    }
    EXPECT_EQ(level_phi, kUnit) << "level " << l;
    if (l == 0) { EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](int s) { return s == 1; })); }
    for (std::size_t p = 0; p < n; ++p) {
      const auto c = h.cluster_of[l][p];
      ASSERT_LT(c, h.levels[l].size());
      for (std::size_t d = 0; d < 3; ++d) {
        EXPECT_LE(h.levels[l][c].lo[d], L.pos[p][d]);
        EXPECT_GE(h.levels[l][c].hi[d], L.pos[p][d]);
      }
      if (l + 1 < r1::kLevels) { EXPECT_EQ(h.cluster_of[l + 1][p], h.levels[l][c].parent) << "nesting, level " << l; }
    }
  }
  for (const auto& top : h.levels[r1::kLevels - 1]) EXPECT_EQ(top.parent, 0xFFFFFFFFu);
  const auto st = r1::check_hierarchy(h, L.pos, L.phi, L.color, L.ids);
  EXPECT_TRUE(st.is_ok()) << st.message();
}

// ---- an independent brute-force implementation of R1-HIER-010..015 ------------------------------

struct RefItem {
  std::array<std::int64_t, 3> pos;
  std::int64_t phi;
  ParticleId min_id;
  std::array<i128, 3> moment;
};

// Round-to-nearest-even of a / b for b > 0, by floor division and the remainder.
std::int64_t rne_quotient(i128 a, i128 b) {
  i128 q = a / b, r = a % b;
  if (r < 0) {
    q -= 1;
    r += b;
  }
  if (2 * r > b || (2 * r == b && (q % 2 != 0))) q += 1;
  return static_cast<std::int64_t>(q);
}

// |coordinate| <= 2^60, so a difference squared is below 2^122 and the sum fits.
u128 ref_d2(const std::array<std::int64_t, 3>& a, const std::array<std::int64_t, 3>& b) {
  u128 s = 0;
  for (std::size_t d = 0; d < 3; ++d) {
    const i128 diff = static_cast<i128>(a[d]) - b[d];
    s += static_cast<u128>(diff * diff);
  }
  return s;
}

// cluster_of[level][particle] by the literal rule: O(n^2) per level, no tree.
std::array<std::vector<std::uint32_t>, r1::kLevels> reference_clusters(const Layout& L, std::int64_t r0) {
  const std::size_t n = L.pos.size();
  std::vector<RefItem> items(n);
  for (std::size_t p = 0; p < n; ++p) {
    items[p].phi = L.phi[p].raw;
    items[p].min_id = L.ids[p];
    for (std::size_t d = 0; d < 3; ++d) {
      items[p].pos[d] = L.pos[p][d].raw;
      items[p].moment[d] = static_cast<i128>(L.phi[p].raw) * L.pos[p][d].raw;
    }
  }
  std::vector<std::uint32_t> of_item(n);  // particle -> current item
  std::iota(of_item.begin(), of_item.end(), 0u);
  std::array<std::vector<std::uint32_t>, r1::kLevels> out;
  boost::multiprecision::cpp_int r2 = boost::multiprecision::cpp_int(r0) * r0;
  const boost::multiprecision::cpp_int cap = (boost::multiprecision::cpp_int(1) << 128) - 1;
  for (std::size_t level = 0; level < r1::kLevels; ++level, r2 *= 10) {
    const u128 R2 = static_cast<u128>(r2 > cap ? cap : r2);
    const std::size_t m = items.size();
    auto before = [&](std::size_t a, std::size_t b) {
      return items[a].phi != items[b].phi ? items[a].phi > items[b].phi : items[a].min_id < items[b].min_id;
    };
    std::vector<std::size_t> canon(m);
    std::iota(canon.begin(), canon.end(), std::size_t{0});
    std::sort(canon.begin(), canon.end(), before);
    std::vector<std::size_t> rank(m);
    for (std::size_t r = 0; r < m; ++r) rank[canon[r]] = r;
    std::vector<long> cluster(m, -1);
    std::vector<std::vector<std::size_t>> members;
    for (const std::size_t lead : canon) {
      if (cluster[lead] >= 0) continue;
      const long c = static_cast<long>(members.size());
      members.push_back({lead});
      cluster[lead] = c;
      std::vector<std::pair<u128, std::size_t>> cand;
      for (std::size_t j = 0; j < m; ++j) {
        if (cluster[j] >= 0) continue;
        const u128 d2 = ref_d2(items[lead].pos, items[j].pos);
        if (d2 <= R2) cand.emplace_back(d2, rank[j]);
      }
      std::sort(cand.begin(), cand.end());
      for (std::size_t k = 0; k < cand.size() && k < 15; ++k) {
        members.back().push_back(canon[cand[k].second]);
        cluster[canon[cand[k].second]] = c;
      }
    }
    std::vector<RefItem> next(members.size());
    for (std::size_t c = 0; c < members.size(); ++c) {
      next[c] = items[members[c][0]];
      for (std::size_t k = 1; k < members[c].size(); ++k) {
        const RefItem& it = items[members[c][k]];
        next[c].phi += it.phi;
        next[c].min_id = std::min(next[c].min_id, it.min_id);
        for (std::size_t d = 0; d < 3; ++d) next[c].moment[d] += it.moment[d];
      }
      for (std::size_t d = 0; d < 3; ++d) next[c].pos[d] = rne_quotient(next[c].moment[d], next[c].phi);
    }
    std::vector<std::size_t> ids(next.size());
    std::iota(ids.begin(), ids.end(), std::size_t{0});
    std::sort(ids.begin(), ids.end(), [&](std::size_t a, std::size_t b) {
      return next[a].phi != next[b].phi ? next[a].phi > next[b].phi : next[a].min_id < next[b].min_id;
    });
    std::vector<std::uint32_t> id_of(next.size());
    std::vector<RefItem> sorted(next.size());
    for (std::size_t k = 0; k < ids.size(); ++k) {
      id_of[ids[k]] = static_cast<std::uint32_t>(k);
      sorted[k] = next[ids[k]];
    }
    out[level].resize(n);
    for (std::size_t p = 0; p < n; ++p) {
      of_item[p] = id_of[static_cast<std::size_t>(cluster[of_item[p]])];
      out[level][p] = of_item[p];
    }
    items = std::move(sorted);
  }
  return out;
}

// A small layout with many ties: coordinates on a coarse grid, several equal phi values.
Layout tie_layout(std::size_t n, std::uint64_t seed, std::int64_t grid) {
  Layout L;
  for (std::size_t i = 0; i < n; ++i) {
    std::array<Q32, 3> p{};
    for (std::uint64_t d = 0; d < 3; ++d)
      p[d] = Q32::from_raw(static_cast<std::int64_t>(r1::rng::uniform_below(seed, i, d, 2 * static_cast<std::uint64_t>(grid) + 1)) * kUnit - grid * kUnit);
    L.pos.push_back(p);
    L.color.push_back(Color{static_cast<std::uint8_t>(r1::rng::uniform_below(seed, i, 4, 3)), 0, 0});
    L.ids.push_back(r1::hier_test::make_id(seed, i));
  }
  // phi in {1, 2, 3} * 2^10, so equal values and equal sums abound; the last particle takes the
  // remainder of 2^32.
  std::int64_t sum = 0;
  for (std::size_t i = 0; i + 1 < n; ++i) {
    L.phi.push_back(Q32::from_raw((1 + static_cast<std::int64_t>(r1::rng::uniform_below(seed, i, 3, 3))) << 10));
    sum += L.phi.back().raw;
  }
  L.phi.push_back(Q32::from_raw(kUnit - sum));
  return L;
}

// ---- k-d tree ------------------------------------------------------------------------------------

// n points with integer coordinates in [-grid, grid]^3 (coincident points likely on small grids).
std::vector<r1::hier::Point> grid_points(std::uint32_t n, std::int64_t grid, std::uint64_t seed) {
  std::vector<r1::hier::Point> pts(n);
  for (std::uint32_t i = 0; i < n; ++i)
    for (std::uint64_t d = 0; d < 3; ++d)
      pts[i][d] = static_cast<std::int64_t>(r1::rng::uniform_below(seed, i, d, 2 * static_cast<std::uint64_t>(grid) + 1)) - grid;
  return pts;
}

// The k nearest alive points within squared distance r2 of point q by brute force, ties by index:
// what a tree search must have returned in `got` (inside a RapidCheck property).
void expect_brute_force_nearest(const std::vector<r1::hier::Point>& pts, const std::vector<bool>& alive, std::uint32_t q,
                                u128 r2, std::uint32_t k, const std::vector<r1::hier::Hit>& got) {
  std::vector<std::pair<u128, std::uint32_t>> want;
  for (std::uint32_t j = 0; j < pts.size(); ++j)
    if (alive[j] && ref_d2(pts[q], pts[j]) <= r2) want.emplace_back(ref_d2(pts[q], pts[j]), j);
  std::sort(want.begin(), want.end());
  if (want.size() > k) want.resize(k);
  RC_ASSERT(got.size() == want.size());
  for (std::size_t i = 0; i < got.size(); ++i) RC_ASSERT(got[i].d2 == want[i].first && got[i].item == want[i].second);
}

RC_GTEST_PROP(HierKdTree, NearestMatchesBruteForceUnderDeletion, ()) {
  const auto n = *rc::gen::inRange<std::uint32_t>(1, 200);
  const auto grid = *rc::gen::inRange<std::int64_t>(1, 6);
  const auto seed = *rc::gen::arbitrary<std::uint64_t>();
  const std::vector<r1::hier::Point> pts = grid_points(n, grid, seed);
  r1::hier::KdTree tree(pts);
  std::vector<bool> alive(n, true);
  std::vector<r1::hier::Hit> got;
  for (std::uint32_t step = 0; step < n; ++step) {
    const std::uint32_t q = static_cast<std::uint32_t>(r1::rng::uniform_below(seed, step, 20, n));
    const u128 r2 = r1::rng::uniform_below(seed, step, 21, static_cast<std::uint64_t>(3 * grid * grid * 4 + 2));
    const std::uint32_t k = static_cast<std::uint32_t>(r1::rng::uniform_below(seed, step, 22, 20));
    tree.nearest(pts[q], r2, k, got);
    expect_brute_force_nearest(pts, alive, q, r2, k, got);
    if (alive[q]) {
      tree.remove(q);
      alive[q] = false;
    }
    RC_ASSERT(tree.alive_count() == static_cast<std::uint32_t>(std::count(alive.begin(), alive.end(), true)));
  }
}

TEST(HierKdTree, CoincidentPointsComeInRankOrder) {
  std::vector<r1::hier::Point> pts(1000, r1::hier::Point{5, 5, 5});
  r1::hier::KdTree tree(pts);
  tree.remove(0);
  tree.remove(3);
  std::vector<r1::hier::Hit> got;
  tree.nearest(pts[0], 0, 15, got);
  ASSERT_EQ(got.size(), 15u);
  EXPECT_EQ(got[0].item, 1u);
  EXPECT_EQ(got[1].item, 2u);
  EXPECT_EQ(got[2].item, 4u);
  EXPECT_EQ(got[14].item, 16u);
}

// R1-HIER-071: the bottom-up search is the same search; the leaf-local bounds never exceed the true
// nearest-neighbour distance.
RC_GTEST_PROP(HierKdTree, BottomUpSearchAndNeighbourBoundsMatchBruteForce, ()) {
  const auto n = *rc::gen::inRange<std::uint32_t>(1, 300);
  const auto grid = *rc::gen::inRange<std::int64_t>(1, 8);
  const auto seed = *rc::gen::arbitrary<std::uint64_t>();
  const std::vector<r1::hier::Point> pts = grid_points(n, grid, seed);
  r1::hier::KdTree tree(pts);
  const auto lower = tree.nearest_other_lower_bounds(false);
  RC_ASSERT(lower == tree.nearest_other_lower_bounds(true));
  for (std::uint32_t i = 0; i < n; ++i)
    for (std::uint32_t j = 0; j < n; ++j)
      if (j != i) RC_ASSERT(lower[i] <= ref_d2(pts[i], pts[j]));
  std::vector<bool> alive(n, true);
  std::vector<r1::hier::Hit> got;
  for (std::uint32_t step = 0; step < n; ++step) {
    const std::uint32_t q = static_cast<std::uint32_t>(r1::rng::uniform_below(seed, step, 30, n));
    const u128 r2 = r1::rng::uniform_below(seed, step, 31, static_cast<std::uint64_t>(3 * grid * grid * 4 + 2));
    const std::uint32_t k = static_cast<std::uint32_t>(r1::rng::uniform_below(seed, step, 32, 20));
    tree.nearest_from(q, r2, k, got);
    expect_brute_force_nearest(pts, alive, q, r2, k, got);
    // Deletions in rank order, as the leaders go, and some out of order.
    const std::uint32_t del = step % 3 == 0 ? q : step;
    if (del < n && alive[del]) {
      tree.remove(del);
      alive[del] = false;
    }
    RC_ASSERT(tree.alive_count() == static_cast<std::uint32_t>(std::count(alive.begin(), alive.end(), true)));
  }
}

// R1-HIER-070: a tree built in parallel answers exactly as one built on one thread.
TEST(HierKdTree, ParallelBuildAnswersTheSame) {
  const Layout L = make_layout(Shape::kBlobs, 40000, 8);
  std::vector<r1::hier::Point> pts(L.pos.size());
  for (std::size_t i = 0; i < pts.size(); ++i)
    for (std::size_t d = 0; d < 3; ++d) pts[i][d] = L.pos[i][d].raw;
  r1::hier::KdTree serial(pts);
  std::optional<r1::hier::KdTree> par;
  tbb::task_arena(4).execute([&] { par.emplace(pts, true); });
  EXPECT_EQ(serial.nearest_other_lower_bounds(false), par->nearest_other_lower_bounds(true));
  std::vector<r1::hier::Hit> a, b;
  for (std::uint32_t i = 0; i < 3000; ++i) {
    const auto q = static_cast<std::uint32_t>(r1::rng::uniform_below(4, i, 0, pts.size()));
    const u128 r2 = static_cast<u128>(r1::rng::uniform_below(4, i, 1, 1u << 20)) * kUnit * kUnit / (1u << 10);
    serial.nearest_from(q, r2, 15, a);
    par->nearest_from(q, r2, 15, b);
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t k = 0; k < a.size(); ++k) ASSERT_TRUE(a[k].d2 == b[k].d2 && a[k].item == b[k].item);
    serial.remove(q);
    par->remove(q);
  }
}

// ---- the rule against brute force ------------------------------------------------------------------

RC_GTEST_PROP(Hierarchy, LeaderRuleMatchesBruteForce, ()) {
  const auto n = *rc::gen::inRange<std::size_t>(1, 120);
  const auto grid = *rc::gen::inRange<std::int64_t>(1, 8);
  const auto seed = *rc::gen::arbitrary<std::uint64_t>();
  // r0 from 0 (coincident only) to beyond the diagonal, in quarter units.
  const auto r0 = *rc::gen::inRange<std::int64_t>(0, 4 * grid * 4) * (kUnit / 4);
  const Layout L = tie_layout(n, seed, grid);
  auto h = build(L, {.radius0_raw = r0});
  RC_ASSERT(h.is_ok());
  const auto want = reference_clusters(L, r0);
  for (std::size_t l = 0; l < r1::kLevels; ++l) RC_ASSERT(h->cluster_of[l] == want[l]);
  RC_ASSERT(r1::check_hierarchy(*h, L.pos, L.phi, L.color, L.ids).is_ok());
}

TEST(Hierarchy, BlobsMatchBruteForceAtTheChosenRadius) {
  const Layout L = make_layout(Shape::kBlobs, 1500, 3);
  const Hierarchy h = build_ok(L);
  const auto want = reference_clusters(L, h.radius_raw[0]);
  for (std::size_t l = 0; l < r1::kLevels; ++l) EXPECT_EQ(h.cluster_of[l], want[l]) << "level " << l;
  expect_structure(h, L);
}

// ---- structure on many shapes ----------------------------------------------------------------------

class HierarchyShapes : public ::testing::TestWithParam<Shape> {};

TEST_P(HierarchyShapes, InvariantsHold) {
  for (const std::size_t n : {1u, 2u, 17u, 300u, 3000u}) {
    const Layout L = make_layout(GetParam(), n, 11);
    const Hierarchy h = build_ok(L);
    expect_structure(h, L);
  }
}

INSTANTIATE_TEST_SUITE_P(All, HierarchyShapes,
                         ::testing::Values(Shape::kUniform, Shape::kBlobs, Shape::kLine, Shape::kPlane, Shape::kStar,
                                           Shape::kCoincident, Shape::kSpikes));

TEST(Hierarchy, CanonicalIdOrder) {
  const Layout L = tie_layout(400, 5, 3);  // many equal phi sums
  const Hierarchy h = build_ok(L, {.radius0_raw = kUnit});
  for (std::size_t l = 0; l < r1::kLevels; ++l) {
    std::vector<ParticleId> lowest(h.levels[l].size());
    std::vector<bool> set(lowest.size(), false);
    for (std::size_t p = 0; p < L.pos.size(); ++p) {
      const auto c = h.cluster_of[l][p];
      if (!set[c] || L.ids[p] < lowest[c]) lowest[c] = L.ids[p];
      set[c] = true;
    }
    std::size_t ties = 0;
    for (std::size_t id = 1; id < lowest.size(); ++id) {
      const auto& a = h.levels[l][id - 1];
      const auto& b = h.levels[l][id];
      EXPECT_GE(a.phi_raw, b.phi_raw);
      if (a.phi_raw == b.phi_raw) {
        ++ties;
        EXPECT_LT(lowest[id - 1], lowest[id]);
      }
    }
    if (l == 0) { EXPECT_GT(ties, 0u) << "the layout should exercise the tie rule"; }
  }
}

TEST(Hierarchy, CoincidentPointsFillClustersOfSixteen) {
  const Layout L = make_layout(Shape::kCoincident, 1000, 2);
  const Hierarchy h = build_ok(L);
  EXPECT_EQ(h.radius_raw[0], 0);  // merging coincident points alone meets the target (R1-HIER-032)
  EXPECT_EQ(r1::hierarchy_counts(h), (std::array<std::size_t, 4>{63, 4, 1, 1}));
  for (std::size_t id = 0; id + 1 < h.levels[0].size(); ++id) EXPECT_EQ(h.levels[0][id].particles, 16u);
  expect_structure(h, L);
}

TEST(Hierarchy, StarLeavesAtOneSpot) {
  const Layout L = make_layout(Shape::kStar, 5001, 4);
  const Hierarchy h = build_ok(L);
  expect_structure(h, L);
  // The hub is alone: nothing lies near it, and its cluster never mixes with leaves at level 0.
  const auto hub = h.cluster_of[0][0];
  EXPECT_EQ(h.levels[0][hub].particles, 1u);
  // 5000 coincident leaves: 313 clusters at level 0, then about 16-fold merges.
  const auto c = r1::hierarchy_counts(h);
  EXPECT_EQ(c[0], 313u + 1u);
  EXPECT_EQ(c[3], 1u);  // T = 1
}

TEST(Hierarchy, SinglesAndPairs) {
  const Layout one = make_layout(Shape::kUniform, 1, 1);
  const Hierarchy h1 = build_ok(one);
  EXPECT_EQ(r1::hierarchy_counts(h1), (std::array<std::size_t, 4>{1, 1, 1, 1}));
  EXPECT_EQ(h1.levels[3][0].phi_raw, kUnit);
  EXPECT_EQ(h1.radius_raw[0], 0);
  const Layout two = make_layout(Shape::kUniform, 2, 1);
  const Hierarchy h2 = build_ok(two);
  EXPECT_EQ(r1::hierarchy_counts(h2)[3], 1u);  // T = 1
  expect_structure(h2, two);
}

TEST(Hierarchy, ZeroRadiusMergesOnlyCoincidentPoints) {
  Layout L = make_layout(Shape::kUniform, 100, 8);
  L.pos[7] = L.pos[3];
  L.pos[9] = L.pos[3];
  const Hierarchy h = build_ok(L, {.radius0_raw = 0});
  EXPECT_EQ(h.levels[0].size(), 98u);
  EXPECT_EQ(h.cluster_of[0][7], h.cluster_of[0][3]);
  EXPECT_EQ(h.cluster_of[0][9], h.cluster_of[0][3]);
  expect_structure(h, L);
}

// ---- colour ---------------------------------------------------------------------------------------

TEST(Hierarchy, DominantColourCarriesMostFocus) {
  const Color red{255, 0, 0}, blue{0, 0, 255}, green{0, 255, 0};
  constexpr std::int64_t u = kUnit / 16;
  struct P {
    std::int64_t x;
    Color c;
    std::int64_t phi;
  };
  // At 0: red 1 + 1, blue 3, green 2 -> blue. At 100: red 2 against green 1 + 1, a tie; red's
  // particle has the larger phi, so it comes first canonically and wins. At -100: green 5.
  const std::vector<P> ps = {{0, red, 1 * u},   {0, red, 1 * u},     {0, blue, 3 * u},   {0, green, 2 * u},
                             {100, red, 2 * u}, {100, green, 1 * u}, {100, green, 1 * u}, {-100, green, 5 * u}};
  Layout L;
  for (std::size_t i = 0; i < ps.size(); ++i) {
    L.pos.push_back({Q32::from_int(ps[i].x), Q32::from_int(0), Q32::from_int(0)});
    L.color.push_back(ps[i].c);
    L.phi.push_back(Q32::from_raw(ps[i].phi));
    L.ids.push_back(r1::hier_test::make_id(9, i));
  }
  const Hierarchy h = build_ok(L, {.radius0_raw = 0});
  ASSERT_EQ(h.levels[0].size(), 3u);
  EXPECT_EQ(h.levels[0][h.cluster_of[0][0]].color, blue);
  EXPECT_EQ(h.levels[0][h.cluster_of[0][4]].color, red);
  EXPECT_EQ(h.levels[0][h.cluster_of[0][7]].color, green);
  // r_3 = 4 sqrt(1000) > 100 units: one top cluster; green 2 + 1 + 1 + 5 beats red 4 and blue 3.
  const Hierarchy top = build_ok(L, {.radius0_raw = 4 * kUnit});
  ASSERT_EQ(top.levels[3].size(), 1u);
  EXPECT_EQ(top.levels[3][0].color, green);
  expect_structure(top, L);
}

// ---- radii, tau_0 and the search ------------------------------------------------------------------

TEST(HierarchyRadius, LadderFractionsAreRounded) {
  using Big = boost::multiprecision::cpp_bin_float_100;
  for (std::uint32_t b = 0; b < 8; ++b) {
    const Big f = boost::multiprecision::pow(Big(2), Big(32) - Big(b) / 8);
    const auto want = static_cast<std::int64_t>(boost::multiprecision::round(f));
    // rho_b of D = 2^32 is exactly F[b].
    EXPECT_EQ(r1::hier::ladder_radius(kUnit, b), want) << b;
  }
  EXPECT_EQ(r1::hier::ladder_radius(std::int64_t{1} << 62, 8), std::int64_t{1} << 61);
  EXPECT_EQ(r1::hier::ladder_radius(std::int64_t{1} << 62, 512), 0);
  EXPECT_EQ(r1::hier::top_target(1), 1u);
  EXPECT_EQ(r1::hier::top_target(10000), 1u);
  EXPECT_EQ(r1::hier::top_target(10001), 2u);
}

TEST(HierarchyRadius, DiameterBoundsEveryPair) {
  std::vector<r1::hier::Point> pts = {{0, 0, 0}, {3, 4, 0}, {3, 0, 0}};
  EXPECT_EQ(r1::hier::diameter_bound(pts), 5);  // exact square root
  pts.push_back({3, 4, 1});
  EXPECT_EQ(r1::hier::diameter_bound(pts), 6);  // sqrt(26) rounded up
}

TEST(HierarchyRadius, ReportedRadiiAndTau) {
  const Layout L = make_layout(Shape::kUniform, 50, 2);
  const Hierarchy h = build_ok(L, {.radius0_raw = 2 * kUnit});
  EXPECT_EQ(h.radius_raw[0], 2 * kUnit);
  EXPECT_EQ(h.radius_raw[2], 20 * kUnit);
  using Big = boost::multiprecision::cpp_bin_float_100;
  for (std::size_t l : {1u, 3u}) {
    const Big r = boost::multiprecision::sqrt(Big(4) * boost::multiprecision::pow(Big(10), static_cast<int>(l))) * Big(kUnit);
    EXPECT_EQ(h.radius_raw[l], static_cast<std::int64_t>(boost::multiprecision::round(r))) << l;
  }
  EXPECT_EQ(h.tau0, 1.0);  // r = 2 sqrt(tau): r_0 = 2 units
}

// The bisection of R1-HIER-032, re-run literally through the forced-radius API.
TEST(HierarchyRadius, SearchIsTheDocumentedBisection) {
  for (const Shape s : {Shape::kBlobs, Shape::kLine, Shape::kSpikes}) {
    const Layout L = make_layout(s, 2500, 6);
    std::vector<r1::hier::Point> pts(L.pos.size());
    for (std::size_t i = 0; i < pts.size(); ++i)
      for (std::size_t d = 0; d < 3; ++d) pts[i][d] = L.pos[i][d].raw;
    const std::int64_t D = r1::hier::diameter_bound(pts);
    const std::uint64_t T = r1::hier::top_target(pts.size());
    auto passes = [&](std::uint32_t j) {
      return r1::hierarchy_counts(build_ok(L, {.radius0_raw = r1::hier::ladder_radius(D, j)}))[3] <= T;
    };
    std::int64_t want = 0;
    if (!passes(512)) {
      std::uint32_t lo = 0, hi = 512;
      while (hi - lo > 1) {
        const std::uint32_t mid = (lo + hi) / 2;
        (passes(mid) ? lo : hi) = mid;
      }
      want = r1::hier::ladder_radius(D, lo);
    }
    const Hierarchy h = build_ok(L);
    EXPECT_EQ(h.radius_raw[0], want);
    EXPECT_LE(r1::hierarchy_counts(h)[3], T);
  }
}

// Items of a layout in particle order (rank = index), as a level-0 input for cluster_level.
r1::hier::Items items_of(const Layout& L) {
  r1::hier::Items items;
  for (std::size_t p = 0; p < L.pos.size(); ++p) {
    r1::hier::Point pt{};
    std::array<i128, 3> m{};
    for (std::size_t d = 0; d < 3; ++d) {
      pt[d] = L.pos[p][d].raw;
      m[d] = static_cast<i128>(L.phi[p].raw) * L.pos[p][d].raw;
    }
    items.pos.push_back(pt);
    items.phi.push_back(L.phi[p].raw);
    items.min_id.push_back(static_cast<std::uint32_t>(p));
    items.moment.push_back(m);
  }
  return items;
}

// R1-HIER-071: stopping a level early, the bound from the items alone and the search-free clusters
// of one change no level: cluster_levels with them passes exactly when the full build's level 3
// meets the target, and then gives the same levels.
TEST(HierarchyRadius, EarlyStopAndShortcutsChangeNoLevel) {
  for (const Shape s : {Shape::kBlobs, Shape::kSpikes, Shape::kUniform, Shape::kStar}) {
    const r1::hier::Items items = items_of(make_layout(s, 6000, 14));
    r1::hier::KdTree tree(items.pos);
    const auto nb = r1::hier::Neighbours::of(tree, false);
    const std::int64_t D = r1::hier::diameter_bound(items.pos);
    const std::uint64_t T = r1::hier::top_target(items.size());
    for (const std::uint32_t j : {512u, 300u, 120u, 90u, 80u, 72u, 66u, 60u, 50u, 30u, 0u}) {
      SCOPED_TRACE(j);
      const std::int64_t r0 = r1::hier::ladder_radius(D, j);
      const auto full = r1::hier::cluster_levels(items, tree, r0, std::numeric_limits<std::uint64_t>::max());
      ASSERT_TRUE(full.has_value());
      const auto fast = r1::hier::cluster_levels(items, tree, r0, T, &nb);
      ASSERT_EQ(fast.has_value(), (*full)[3].clusters.size() <= T);
      if (!fast) continue;
      for (std::size_t l = 0; l < r1::kLevels; ++l) {
        EXPECT_EQ((*fast)[l].cluster_of_item, (*full)[l].cluster_of_item);
        EXPECT_EQ((*fast)[l].clusters.pos, (*full)[l].clusters.pos);
        EXPECT_EQ((*fast)[l].clusters.phi, (*full)[l].clusters.phi);
      }
    }
  }
}

// R1-HIER-070: the windowed parallel leader loop (queries asked at once, checked in order, asked
// again when an earlier leader took a member) gives the serial loop's level, with and without
// the clusters of one, on a spread layout and on one full of coincident points.
TEST(HierarchyParallel, LeaderLoopIsTheSerialOne) {
  for (const Shape s : {Shape::kBlobs, Shape::kStar, Shape::kSpikes}) {
    SCOPED_TRACE(static_cast<int>(s));
    const r1::hier::Items items = items_of(make_layout(s, 50000, 23));
    r1::hier::KdTree tree(items.pos);
    const auto nb = r1::hier::Neighbours::of(tree, false);
    const std::int64_t D = r1::hier::diameter_bound(items.pos);
    for (const std::uint32_t j : {100u, 80u, 72u, 64u, 48u}) {
      SCOPED_TRACE(j);
      const u128 r2 = r1::hier::radius2_at_level(r1::hier::ladder_radius(D, j), 0);
      const auto serial = r1::hier::cluster_level(items, tree, r2);
      ASSERT_TRUE(serial.has_value());
      std::optional<r1::hier::Level> par, par_alone;
      tbb::task_arena(4).execute([&] {
        par = r1::hier::cluster_level(items, tree, r2, std::numeric_limits<std::uint64_t>::max(), {}, true);
        par_alone = r1::hier::cluster_level(items, tree, r2, std::numeric_limits<std::uint64_t>::max(), nb.lower2, true);
      });
      ASSERT_TRUE(par.has_value() && par_alone.has_value());
      EXPECT_EQ(par->cluster_of_item, serial->cluster_of_item);
      EXPECT_EQ(par_alone->cluster_of_item, serial->cluster_of_item);
      EXPECT_EQ(par->clusters.pos, serial->clusters.pos);
    }
  }
}

// R1-HIER-070: the parallel switch changes how the stage runs, not a byte of its result, on layouts
// large enough to split (the tree build, the sorts, the leader loop, the speculative search).
TEST(HierarchyParallel, SameBytesAsSerial) {
  for (const Shape s : {Shape::kUniform, Shape::kBlobs, Shape::kLine, Shape::kSpikes, Shape::kStar}) {
    SCOPED_TRACE(static_cast<int>(s));
    const Layout L = make_layout(s, 40000, 17);
    const auto serial = r1::hierarchy_bytes(build_ok(L));
    std::string par, par2, par_forced;
    // Four threads: three radii a round; two threads: two.
    tbb::task_arena(4).execute([&] {
      par = r1::hierarchy_bytes(build_ok(L, {.radius0_raw = std::nullopt, .parallel = true}));
      par_forced = r1::hierarchy_bytes(build_ok(L, {.radius0_raw = 3 * kUnit, .parallel = true}));
    });
    tbb::task_arena(2).execute([&] { par2 = r1::hierarchy_bytes(build_ok(L, {.radius0_raw = std::nullopt, .parallel = true})); });
    EXPECT_EQ(serial, par);
    EXPECT_EQ(serial, par2);
    EXPECT_EQ(r1::hierarchy_bytes(build_ok(L, {.radius0_raw = 3 * kUnit})), par_forced);
  }
}

// ---- determinism ------------------------------------------------------------------------------------

TEST(HierarchyDeterminism, SameInputsSameBytes) {
  const Layout L = make_layout(Shape::kSpikes, 4000, 12);
  const auto a = r1::hierarchy_bytes(build_ok(L));
  const auto b = r1::hierarchy_bytes(build_ok(L));
  EXPECT_EQ(a, b);
}

// Maps a hierarchy of permuted particles back to the original numbering.
Hierarchy unpermute(Hierarchy h, const std::vector<std::size_t>& perm) {
  // perm[new] = old
  for (auto& of : h.cluster_of) {
    std::vector<std::uint32_t> back(of.size());
    for (std::size_t i = 0; i < of.size(); ++i) back[perm[i]] = of[i];
    of = std::move(back);
  }
  for (auto& node : h.levels[0]) {
    for (auto& c : node.children) c = static_cast<std::uint32_t>(perm[c]);
    std::sort(node.children.begin(), node.children.end());
  }
  return h;
}

RC_GTEST_PROP(HierarchyDeterminism, PermutingParticlesPermutesTheResult, ()) {
  const auto n = *rc::gen::inRange<std::size_t>(1, 600);
  const auto shape = *rc::gen::element(Shape::kUniform, Shape::kBlobs, Shape::kStar, Shape::kSpikes, Shape::kLine);
  const auto seed = *rc::gen::arbitrary<std::uint64_t>();
  const Layout L = make_layout(shape, n, seed);
  std::vector<std::size_t> perm(n);
  std::iota(perm.begin(), perm.end(), std::size_t{0});
  for (std::size_t i = n; i > 1; --i) std::swap(perm[i - 1], perm[r1::rng::uniform_below(seed, i, 50, i)]);
  Layout P;
  for (const std::size_t old : perm) {
    P.pos.push_back(L.pos[old]);
    P.phi.push_back(L.phi[old]);
    P.color.push_back(L.color[old]);
    P.ids.push_back(L.ids[old]);
  }
  auto a = build(L);
  auto b = build(P);
  RC_ASSERT(a.is_ok() && b.is_ok());
  RC_ASSERT(r1::hierarchy_bytes(*a) == r1::hierarchy_bytes(unpermute(*b, perm)));
}

// ---- counts per level ------------------------------------------------------------------------------

// Each level shrinks the count between 3-fold and 16-fold (the cap), and the top meets T.
void expect_useful_counts(const Hierarchy& h, std::size_t n, const char* what) {
  const auto c = r1::hierarchy_counts(h);
  std::size_t prev = n;
  for (std::size_t l = 0; l < c.size(); ++l) {
    EXPECT_GE(c[l] * 16, prev) << what << " level " << l;
    if (c[l] > 1) { EXPECT_LE(c[l] * 3, prev) << what << " level " << l << ": " << c[l] << " of " << prev; }
    prev = c[l];
  }
  EXPECT_LE(c[3], r1::hier::top_target(n)) << what;
}

TEST(HierarchyCounts, TenThousandPoints) {
  for (const Shape s : {Shape::kUniform, Shape::kBlobs, Shape::kLine, Shape::kPlane, Shape::kSpikes}) {
    const Layout L = make_layout(s, 10'000, 21);
    const Hierarchy h = build_ok(L);
    expect_useful_counts(h, L.pos.size(), "shape");
  }
}

// ---- the bytes and the checker ---------------------------------------------------------------------

TEST(HierarchyBytes, LayoutOfOneParticle) {
  const Layout L = make_layout(Shape::kCoincident, 1, 1);
  const Hierarchy h = build_ok(L);
  const std::string b = r1::hierarchy_bytes(h);
  // magic 8 + n 4 + levels 4 + per level (radius 8 + count 4 + node 4+4+8+48+3+1 + child 4) + 4 * 4
  EXPECT_EQ(b.size(), 16u + 4u * (12u + 68u + 4u) + 16u);
  EXPECT_EQ(b.substr(0, 8), "R1HIER01");
  EXPECT_EQ(static_cast<unsigned char>(b[8]), 1u);
  // Level 0 node: parent 0 (little-endian at offset 28), particles 1, phi 2^32.
  EXPECT_EQ(b.substr(28, 4), std::string("\0\0\0\0", 4));
  EXPECT_EQ(b.substr(32, 4), std::string("\1\0\0\0", 4));
  EXPECT_EQ(b.substr(36, 8), std::string("\0\0\0\0\1\0\0\0", 8));
  // Level 3's node has no parent.
  const std::size_t level3 = 16 + 3 * 84;
  EXPECT_EQ(b.substr(level3 + 12, 4), std::string("\xFF\xFF\xFF\xFF", 4));
  EXPECT_EQ(r1::hierarchy_digest(h), r1::hemera::hash(b));
}

// R1-HIER-052: the bytes read back to the same hierarchy, and every damaged prefix is a clean error.
TEST(HierarchyBytes, ParseRoundTripsAndRefusesTruncation) {
  const Layout L = make_layout(Shape::kBlobs, 300, 5);
  const Hierarchy h = build_ok(L);
  const std::string b = r1::hierarchy_bytes(h);
  auto back = r1::parse_hierarchy_bytes(b, "h.bin");
  ASSERT_TRUE(back.is_ok()) << back.status().message();
  EXPECT_EQ(r1::hierarchy_bytes(*back), b);
  EXPECT_EQ(back->tau0, h.tau0);
  for (std::size_t l = 0; l < r1::kLevels; ++l)
    for (std::size_t id = 0; id < h.levels[l].size(); ++id) {
      EXPECT_EQ(back->levels[l][id].level, l);
      EXPECT_EQ(back->levels[l][id].id, id);
    }
  for (std::size_t cut = 0; cut < b.size(); cut += 1 + cut / 7) {
    auto r = r1::parse_hierarchy_bytes(b.substr(0, cut), "h.bin");
    ASSERT_FALSE(r.is_ok()) << cut;
    EXPECT_EQ(r.status().kind(), r1::ErrorKind::kInput);
    EXPECT_EQ(r.status().message().rfind("h.bin: ", 0), 0u) << r.status().message();
  }
  EXPECT_FALSE(r1::parse_hierarchy_bytes(b + "x", "h.bin").is_ok());
}

TEST(HierarchyCheck, DetectsEachKindOfDamage) {
  const Layout L = make_layout(Shape::kBlobs, 800, 2);
  const Hierarchy good = build_ok(L);
  ASSERT_TRUE(r1::check_hierarchy(good, L.pos, L.phi, L.color, L.ids).is_ok());
  auto damaged = [&](auto&& edit) {
    Hierarchy h = good;
    edit(h);
    return !r1::check_hierarchy(h, L.pos, L.phi, L.color, L.ids).is_ok();
  };
  EXPECT_TRUE(damaged([](Hierarchy& h) { h.levels[0][0].phi_raw += 1; }));
  EXPECT_TRUE(damaged([](Hierarchy& h) { h.levels[1][0].lo[1].raw -= 1; }));
  EXPECT_TRUE(damaged([](Hierarchy& h) { h.levels[2][0].color[0] ^= 1; }));
  EXPECT_TRUE(damaged([](Hierarchy& h) { h.levels[0][0].parent ^= 1; }));
  EXPECT_TRUE(damaged([](Hierarchy& h) { std::swap(h.levels[0][0], h.levels[0][1]); }));
  EXPECT_TRUE(damaged([](Hierarchy& h) { h.cluster_of[1][5] = h.cluster_of[1][5] == 0 ? 1 : 0; }));
  EXPECT_TRUE(damaged([](Hierarchy& h) { h.radius_raw[2] += 1; }));
  EXPECT_TRUE(damaged([](Hierarchy& h) { h.levels[0][0].children.push_back(h.levels[0][1].children[0]); }));
}

// The colour tie rule (R1-HIER-015): with every phi equal and two colours taking turns, many nodes
// hold both colours with the same phi; the tie goes to the colour whose first member in canonical
// order (here: the lowest id) comes first. The checker agrees with the builder on each, and
// catches the other tied colour.
TEST(HierarchyCheck, ColourTiesGoToTheCanonicallyFirstMember) {
  Layout L = make_layout(Shape::kBlobs, 256, 5);
  for (std::size_t p = 0; p < L.phi.size(); ++p) {
    L.phi[p] = Q32::from_raw(std::int64_t{1} << 24);  // 256 x 2^-8 = 1 exactly
    L.color[p] = p % 2 == 0 ? Color{10, 20, 30} : Color{200, 100, 50};
  }
  const Hierarchy good = build_ok(L);
  ASSERT_TRUE(r1::check_hierarchy(good, L.pos, L.phi, L.color, L.ids).is_ok());
  std::size_t ties = 0;
  for (std::size_t l = 0; l < good.levels.size(); ++l)
    for (std::size_t id = 0; id < good.levels[l].size(); ++id) {
      std::size_t even = 0, odd = 0;
      std::optional<std::size_t> first;  // the member with the lowest id
      for (std::size_t p = 0; p < L.ids.size(); ++p) {
        if (good.cluster_of[l][p] != id) continue;
        (p % 2 == 0 ? even : odd) += 1;
        if (!first || L.ids[p] < L.ids[*first]) first = p;
      }
      if (even != odd) continue;
      ++ties;
      EXPECT_EQ(good.levels[l][id].color, L.color[*first]) << "level " << l << " node " << id;
      Hierarchy h = good;
      h.levels[l][id].color = L.color[*first + 1 - 2 * (*first % 2)];  // the other colour
      EXPECT_FALSE(r1::check_hierarchy(h, L.pos, L.phi, L.color, L.ids).is_ok()) << "level " << l << " node " << id;
    }
  EXPECT_GT(ties, 3u);
}

// ---- input errors -----------------------------------------------------------------------------------

TEST(HierarchyErrors, BadInputsAreInputErrors) {
  const Layout good = make_layout(Shape::kUniform, 20, 3);
  auto expect_input = [](const Layout& L, const std::string& part, r1::HierarchyOptions opt = {}) {
    const auto r = build(L, opt);
    ASSERT_FALSE(r.is_ok());
    EXPECT_EQ(r.status().kind(), r1::ErrorKind::kInput);
    EXPECT_NE(r.status().message().find(part), std::string::npos) << r.status().message();
  };
  expect_input(Layout{}, "no particles");
  Layout L = good;
  L.ids.pop_back();
  expect_input(L, "20 positions");
  L = good;
  L.phi[3].raw = 0;
  expect_input(L, "particle 3");
  L = good;
  L.phi[4].raw += 1;
  expect_input(L, "sum to more than 2^32");
  L = good;
  L.phi[4].raw -= 1;
  expect_input(L, "not 2^32");
  L = good;
  L.ids[7] = L.ids[2];
  expect_input(L, "particles 2 and 7 have the same id");
  L = good;
  L.pos[6][2] = Q32::from_int(1 << 29);
  expect_input(L, "particle 6: coordinate 2");
  expect_input(good, "negative", {.radius0_raw = -1});
}

}  // namespace
