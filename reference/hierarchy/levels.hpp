// Leader clustering of one level and the four nested levels with canonical ids, in exact integer
// arithmetic; the early stop and the clusters of one found without a search (R1-HIER-010..015,
// R1-HIER-020..022, R1-HIER-071).
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <vector>

#include "kd_tree.hpp"
#include "r1/fixedpoint/int128.hpp"
#include "r1/spec/epoch.hpp"

namespace r1::hier {

// The items one level clusters, in canonical order (R1-HIER-012): particles at level 0, the
// clusters of the level below (in canonical id order) above it.
struct Items {
  std::vector<Point> pos;                      // Q32 raws: the particle, or the cluster's centroid
  std::vector<std::int64_t> phi;               // exact phi sum (Q32 raw)
  std::vector<std::uint32_t> min_id;           // lowest member id, as its rank in id byte order
  std::vector<std::array<i128, 3>> moment;     // exact sum of phi_raw * x_raw over the members
  std::size_t size() const { return pos.size(); }
};

struct Level {
  std::vector<std::uint32_t> cluster_of_item;  // item -> canonical cluster id
  Items clusters;                              // by canonical id; the next level's items
};

// For each level-0 item a lower bound on the squared distance to its nearest other item,
// whatever the radius (KdTree::nearest_other_lower_bounds). An item whose bound exceeds the
// radius has no other item within it, so it is a cluster alone (R1-HIER-010), found without a
// search, and the count of such items bounds level 0's cluster count from below before it is
// built (R1-HIER-071).
struct Neighbours {
  std::vector<u128> lower2;  // by item (rank)
  std::vector<u128> sorted;  // the same values ascending
  static Neighbours of(const KdTree& tree, bool parallel);
  // Items surely without another item within squared distance r2.
  std::size_t alone(u128 r2) const;
};

// True when level 0 built with r_0 = radius0_raw surely has more than top_limit * 16^3 clusters
// (the items alone, plus one per 16 of the others), so that the radius fails without a build.
bool surely_fails(std::size_t items, std::int64_t radius0_raw, std::uint64_t top_limit, const Neighbours& neighbours);

// r_L^2 = r0^2 * 10^L in Q32 raw units squared (R1-HIER-021), saturating at 2^128 - 1, which
// exceeds every squared distance of valid positions and so means "unbounded".
u128 radius2_at_level(std::int64_t radius0_raw, int level);

// One level: leader clustering of `items` (R1-HIER-010..011) with squared threshold r2, then
// canonical ids (R1-HIER-013) and the aggregates of each cluster (R1-HIER-014). `tree` must be
// built over items.pos; it is reset first. Stops and returns std::nullopt as soon as the level is
// sure to have more than max_clusters clusters (those made so far plus one per 16 items still
// unassigned); with the default it always finishes. `lower2`, when given, holds each item's
// Neighbours::lower2 (only a shortcut: the clusters are the same). `parallel`: the leaders'
// queries are asked a window at a time on TBB workers, then checked in order (R1-HIER-070).
std::optional<Level> cluster_level(const Items& items, KdTree& tree, u128 r2,
                                   std::uint64_t max_clusters = std::numeric_limits<std::uint64_t>::max(),
                                   std::span<const u128> lower2 = {}, bool parallel = false);

// All kLevels levels from the particles (level 0 items) with r_0 = radius0_raw; tree0 is built
// over particles.pos. Stops early and returns std::nullopt as soon as some level L is sure to have
// more than top_limit * 16^(3 - L) clusters: level 3 then has more than top_limit (R1-HIER-032).
// `neighbours` (of the particles, optional) only saves work; `parallel` as for cluster_level.
std::optional<std::array<Level, kLevels>> cluster_levels(const Items& particles, KdTree& tree0,
                                                         std::int64_t radius0_raw, std::uint64_t top_limit,
                                                         const Neighbours* neighbours = nullptr, bool parallel = false);

// Clusters per level.
std::array<std::size_t, kLevels> level_counts(const std::array<Level, kLevels>& levels);

}  // namespace r1::hier
