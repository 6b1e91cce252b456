// Leader clustering of one level and the four nested levels with canonical ids, in exact integer
// arithmetic; the nearest-neighbour shortcut and the early stop (R1-HIER-010..015,
// R1-HIER-020..022, R1-HIER-032, R1-HIER-071).
#include "levels.hpp"

#include <algorithm>
#include <limits>
#include <numeric>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "r1/fixedpoint/q32.hpp"

namespace r1::hier {

namespace {
constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
// Parallel leader loop: items per window (more: fewer rounds, more answers asked again or
// wasted on items an earlier leader takes), and the smallest level worth it. Speed only.
constexpr std::size_t kWindow = 1024;
constexpr std::uint32_t kParallelLevelMin = 1u << 15;
}  // namespace

Neighbours Neighbours::of(const KdTree& tree, bool parallel) {
  Neighbours nb;
  nb.lower2 = tree.nearest_other_lower_bounds(parallel);
  nb.sorted = nb.lower2;
  if (parallel) {
    tbb::parallel_sort(nb.sorted.begin(), nb.sorted.end());
  } else {
    std::sort(nb.sorted.begin(), nb.sorted.end());
  }
  return nb;
}

std::size_t Neighbours::alone(u128 r2) const {
  return static_cast<std::size_t>(sorted.end() - std::upper_bound(sorted.begin(), sorted.end(), r2));
}

namespace {

// limit * 16^(3 - level), saturating at 2^64 - 1: more clusters than this at `level` means more
// than `limit` at the top, since each level above shrinks the count at most kMaxChildren-fold.
std::uint64_t level_limit(std::uint64_t top_limit, int level) {
  u128 limit = top_limit;
  for (int k = level; k < kLevels - 1; ++k) limit *= kMaxChildren;  // < 2^64 * 2^12: no wrap
  return limit > std::numeric_limits<std::uint64_t>::max() ? std::numeric_limits<std::uint64_t>::max()
                                                             : static_cast<std::uint64_t>(limit);
}

}  // namespace

bool surely_fails(std::size_t items, std::int64_t radius0_raw, std::uint64_t top_limit, const Neighbours& neighbours) {
  // The items alone are clusters of one; the others fill clusters of at most kMaxChildren.
  const std::uint64_t alone = neighbours.alone(radius2_at_level(radius0_raw, 0));
  const std::uint64_t rest = items - alone;
  return alone + (rest + kMaxChildren - 1) / kMaxChildren > level_limit(top_limit, 0);
}

u128 radius2_at_level(std::int64_t radius0_raw, int level) {
  const auto r = static_cast<u128>(radius0_raw);
  u128 r2 = r * r;  // < 2^126 for r0 < 2^63
  for (int l = 0; l < level; ++l) {
    if (r2 > u128_max / 10) return u128_max;  // saturate: wider than any pair of valid positions
    r2 *= 10;
  }
  return r2;
}

std::optional<Level> cluster_level(const Items& items, KdTree& tree, u128 r2, std::uint64_t max_clusters,
                                   std::span<const u128> lower2, bool parallel) {
  const auto m = static_cast<std::uint32_t>(items.size());
  tree.reset();
  // Leader clustering (R1-HIER-010, R1-HIER-011): items in canonical order; each one still
  // unassigned leads a new cluster and takes the kMaxChildren - 1 first unassigned items in
  // (squared distance, rank) order within the radius.
  std::vector<std::uint32_t> leader_cluster(m, kNone);
  std::vector<std::uint32_t> start;
  std::vector<std::uint32_t> members;
  members.reserve(m);
  std::vector<Hit> hits;
  auto alone = [&](std::uint32_t i) { return !lower2.empty() && lower2[i] > r2; };
  // Leader i with its members `found` (the answer of R1-HIER-011 for the items unassigned now);
  // false when the level must exceed max_clusters.
  auto lead = [&](std::uint32_t i, const std::vector<Hit>& found) {
    const auto c = static_cast<std::uint32_t>(start.size());
    start.push_back(static_cast<std::uint32_t>(members.size()));
    members.push_back(i);
    leader_cluster[i] = c;
    for (const Hit& h : found) {
      members.push_back(h.item);
      leader_cluster[h.item] = c;
      tree.remove(h.item);
    }
    // Every cluster still to come takes at most kMaxChildren of the items left.
    const std::uint64_t at_least = std::uint64_t{c} + 1 + (std::uint64_t{tree.alive_count()} + kMaxChildren - 1) / kMaxChildren;
    return at_least <= max_clusters;
  };
  if (!parallel || m < kParallelLevelMin) {
    for (std::uint32_t i = 0; i < m; ++i) {
      if (!tree.alive(i)) continue;
      tree.remove(i);
      if (alone(i)) {
        hits.clear();  // nothing within the radius, alive or not: a cluster of one
      } else {
        tree.nearest_from(i, r2, kMaxChildren - 1, hits);
      }
      if (!lead(i, hits)) return std::nullopt;
    }
  } else {
    // The next kWindow unassigned items are asked their queries at once on TBB workers, against
    // the unassigned set as it stands (leaving the item itself out), then taken in canonical
    // order as the rule says. An item already taken by an earlier leader of the window is
    // skipped. A leader's answer A is still its answer if every item of A is still unassigned:
    // the set only shrank since, so no item can have come before A's in (d2, rank) order, and
    // when A is short of kMaxChildren - 1 nothing else was within the radius. Otherwise the
    // leader asks again. Same clusters as the loop above.
    std::vector<std::uint32_t> window;
    std::vector<std::vector<Hit>> answers(kWindow);
    std::vector<std::uint64_t> in_tree_order;
    for (std::uint32_t i = 0; i < m;) {
      window.clear();
      for (; i < m && window.size() < kWindow; ++i)
        if (tree.alive(i)) window.push_back(i);
      // Asked in tree order, so that queries near one another in space run one after another.
      in_tree_order.resize(window.size());
      for (std::size_t w = 0; w < window.size(); ++w)
        in_tree_order[w] = (std::uint64_t{tree.leaf_of(window[w])} << 32) | w;
      std::sort(in_tree_order.begin(), in_tree_order.end());
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, window.size(), 8), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t k = r.begin(); k < r.end(); ++k) {
          const auto w = static_cast<std::uint32_t>(in_tree_order[k]);
          if (alone(window[w])) {
            answers[w].clear();
          } else {
            tree.nearest_from_readonly(window[w], r2, kMaxChildren - 1, answers[w]);
          }
        }
      });
      for (std::size_t w = 0; w < window.size(); ++w) {
        const std::uint32_t leader = window[w];
        if (!tree.alive(leader)) continue;
        tree.remove(leader);
        const bool still = std::all_of(answers[w].begin(), answers[w].end(), [&](const Hit& h) { return tree.alive(h.item); });
        if (!still) tree.nearest_from(leader, r2, kMaxChildren - 1, answers[w]);
        if (!lead(leader, answers[w])) return std::nullopt;
      }
    }
  }
  const auto clusters = static_cast<std::uint32_t>(start.size());
  start.push_back(static_cast<std::uint32_t>(members.size()));

  // Per cluster (or item) work below writes only its own entries: on TBB workers when
  // `parallel`, the same values either way.
  auto for_each = [&](std::uint32_t count, const auto& fn) {
    if (!parallel || count < kParallelLevelMin) {
      for (std::uint32_t c = 0; c < count; ++c) fn(c);
      return;
    }
    tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, count, 4096), [&](const tbb::blocked_range<std::uint32_t>& r) {
      for (std::uint32_t c = r.begin(); c < r.end(); ++c) fn(c);
    });
  };

  // Aggregates in leader order: exact sums, the lowest member id.
  std::vector<std::int64_t> phi(clusters, 0);
  std::vector<std::uint32_t> min_id(clusters, kNone);
  std::vector<std::array<i128, 3>> moment(clusters, std::array<i128, 3>{});
  for_each(clusters, [&](std::uint32_t c) {
    for (std::uint32_t k = start[c]; k < start[c + 1]; ++k) {
      const std::uint32_t i = members[k];
      phi[c] += items.phi[i];  // every phi sum is at most the total, 2^32
      min_id[c] = std::min(min_id[c], items.min_id[i]);
      for (std::size_t d = 0; d < 3; ++d) moment[c][d] += items.moment[i][d];  // |sum| <= 2^32 * 2^62
    }
  });

  // Canonical ids (R1-HIER-013, R-1.0 10.2): phi sum descending, ties by the lowest member id.
  // Member sets are disjoint and ids distinct, so the order is total (one sorted result for
  // either sort).
  std::vector<std::uint32_t> order(clusters);
  std::iota(order.begin(), order.end(), 0u);
  auto canonical = [&](std::uint32_t a, std::uint32_t b) { return phi[a] != phi[b] ? phi[a] > phi[b] : min_id[a] < min_id[b]; };
  if (parallel && clusters >= kParallelLevelMin) {
    tbb::parallel_sort(order.begin(), order.end(), canonical);
  } else {
    std::sort(order.begin(), order.end(), canonical);
  }
  std::vector<std::uint32_t> canon(clusters);
  for (std::uint32_t id = 0; id < clusters; ++id) canon[order[id]] = id;

  Level out;
  out.cluster_of_item.resize(m);
  for_each(m, [&](std::uint32_t i) { out.cluster_of_item[i] = canon[leader_cluster[i]]; });
  Items& next = out.clusters;
  next.pos.resize(clusters);
  next.phi.resize(clusters);
  next.min_id.resize(clusters);
  next.moment.resize(clusters);
  for_each(clusters, [&](std::uint32_t id) {
    const std::uint32_t c = order[id];
    next.phi[id] = phi[c];
    next.min_id[id] = min_id[c];
    next.moment[id] = moment[c];
    // The phi-weighted centroid, the exact rational rounded once to Q32, ties to even
    // (R1-HIER-014); it lies in the members' bounding box, so it is a valid position.
    for (std::size_t d = 0; d < 3; ++d)
      next.pos[id][d] = static_cast<std::int64_t>(fx::detail::rne_div(moment[c][d], phi[c]));
  });
  return out;
}

std::optional<std::array<Level, kLevels>> cluster_levels(const Items& particles, KdTree& tree0,
                                                         std::int64_t radius0_raw, std::uint64_t top_limit,
                                                         const Neighbours* neighbours, bool parallel) {
  std::array<Level, kLevels> levels;
  for (std::size_t l = 0; l < levels.size(); ++l) {
    const int level = static_cast<int>(l);
    const std::uint64_t max_clusters = level_limit(top_limit, level);
    std::optional<Level> built;
    if (l == 0) {
      if (neighbours && surely_fails(particles.size(), radius0_raw, top_limit, *neighbours)) return std::nullopt;
      built = cluster_level(particles, tree0, radius2_at_level(radius0_raw, 0), max_clusters,
                            neighbours ? std::span<const u128>(neighbours->lower2) : std::span<const u128>(), parallel);
    } else {
      const Items& items = levels[l - 1].clusters;
      KdTree tree(items.pos, parallel);
      built = cluster_level(items, tree, radius2_at_level(radius0_raw, level), max_clusters, {}, parallel);
    }
    if (!built) return std::nullopt;
    levels[l] = std::move(*built);
  }
  return levels;
}

std::array<std::size_t, kLevels> level_counts(const std::array<Level, kLevels>& levels) {
  std::array<std::size_t, kLevels> c{};
  for (std::size_t l = 0; l < levels.size(); ++l) c[l] = levels[l].clusters.size();
  return c;
}

}  // namespace r1::hier
