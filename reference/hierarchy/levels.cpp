// Leader clustering of one level and the four nested levels with canonical ids, in exact integer
// arithmetic (R1-HIER-010..015, R1-HIER-020..022).
#include "levels.hpp"

#include <algorithm>
#include <limits>
#include <numeric>

#include "r1/fixedpoint/q32.hpp"

namespace r1::hier {

namespace {
constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
}  // namespace

u128 radius2_at_level(std::int64_t radius0_raw, int level) {
  const auto r = static_cast<u128>(radius0_raw);
  u128 r2 = r * r;  // < 2^126 for r0 < 2^63
  for (int l = 0; l < level; ++l) {
    if (r2 > u128_max / 10) return u128_max;  // saturate: wider than any pair of valid positions
    r2 *= 10;
  }
  return r2;
}

Level cluster_level(const Items& items, KdTree& tree, u128 r2) {
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
  for (std::uint32_t i = 0; i < m; ++i) {
    if (!tree.alive(i)) continue;
    const auto c = static_cast<std::uint32_t>(start.size());
    start.push_back(static_cast<std::uint32_t>(members.size()));
    members.push_back(i);
    leader_cluster[i] = c;
    tree.remove(i);
    tree.nearest(items.pos[i], r2, kMaxChildren - 1, hits);
    for (const Hit& h : hits) {
      members.push_back(h.item);
      leader_cluster[h.item] = c;
      tree.remove(h.item);
    }
  }
  const auto clusters = static_cast<std::uint32_t>(start.size());
  start.push_back(static_cast<std::uint32_t>(members.size()));

  // Aggregates in leader order: exact sums, the lowest member id.
  std::vector<std::int64_t> phi(clusters, 0);
  std::vector<std::uint32_t> min_id(clusters, kNone);
  std::vector<std::array<i128, 3>> moment(clusters, std::array<i128, 3>{});
  for (std::uint32_t c = 0; c < clusters; ++c) {
    for (std::uint32_t k = start[c]; k < start[c + 1]; ++k) {
      const std::uint32_t i = members[k];
      phi[c] += items.phi[i];  // every phi sum is at most the total, 2^32
      min_id[c] = std::min(min_id[c], items.min_id[i]);
      for (std::size_t d = 0; d < 3; ++d) moment[c][d] += items.moment[i][d];  // |sum| <= 2^32 * 2^62
    }
  }

  // Canonical ids (R1-HIER-013, R-1.0 10.2): phi sum descending, ties by the lowest member id.
  // Member sets are disjoint and ids distinct, so the order is total.
  std::vector<std::uint32_t> order(clusters);
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return phi[a] != phi[b] ? phi[a] > phi[b] : min_id[a] < min_id[b];
  });
  std::vector<std::uint32_t> canon(clusters);
  for (std::uint32_t id = 0; id < clusters; ++id) canon[order[id]] = id;

  Level out;
  out.cluster_of_item.resize(m);
  for (std::uint32_t i = 0; i < m; ++i) out.cluster_of_item[i] = canon[leader_cluster[i]];
  Items& next = out.clusters;
  next.pos.resize(clusters);
  next.phi.resize(clusters);
  next.min_id.resize(clusters);
  next.moment.resize(clusters);
  for (std::uint32_t id = 0; id < clusters; ++id) {
    const std::uint32_t c = order[id];
    next.phi[id] = phi[c];
    next.min_id[id] = min_id[c];
    next.moment[id] = moment[c];
    // The phi-weighted centroid, the exact rational rounded once to Q32, ties to even
    // (R1-HIER-014); it lies in the members' bounding box, so it is a valid position.
    for (std::size_t d = 0; d < 3; ++d)
      next.pos[id][d] = static_cast<std::int64_t>(fx::detail::rne_div(moment[c][d], phi[c]));
  }
  return out;
}

std::optional<std::array<Level, kLevels>> cluster_levels(const Items& particles, KdTree& tree0,
                                                         std::int64_t radius0_raw, std::uint64_t top_limit) {
  std::array<Level, kLevels> levels;
  for (std::size_t l = 0; l < levels.size(); ++l) {
    const int level = static_cast<int>(l);
    if (l == 0) {
      levels[0] = cluster_level(particles, tree0, radius2_at_level(radius0_raw, 0));
    } else {
      const Items& items = levels[l - 1].clusters;
      KdTree tree(items.pos);
      levels[l] = cluster_level(items, tree, radius2_at_level(radius0_raw, level));
    }
    // Each level above can shrink the count at most kMaxChildren-fold, so more than
    // top_limit * 16^(3 - l) clusters here means more than top_limit at the top.
    u128 limit = top_limit;
    for (int k = level; k < kLevels - 1; ++k) limit *= kMaxChildren;  // < 2^64 * 2^12: no wrap
    if (levels[l].clusters.size() > limit) return std::nullopt;
  }
  return levels;
}

std::array<std::size_t, kLevels> level_counts(const std::array<Level, kLevels>& levels) {
  std::array<std::size_t, kLevels> c{};
  for (std::size_t l = 0; l < levels.size(); ++l) c[l] = levels[l].clusters.size();
  return c;
}

}  // namespace r1::hier
