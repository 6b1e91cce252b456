// A static k-d tree over integer points with deletion: the k nearest alive points within a squared
// radius, nearest first, ties by rank; exact integer distances (R1-HIER-010, R1-HIER-011).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "r1/fixedpoint/int128.hpp"

namespace r1::hier {

// Coordinates are Q32 raws with |c| < 2^62 (R1-HIER-003), so a coordinate difference fits int64
// and a squared distance (three squares below 2^126 each) fits u128 exactly.
using Point = std::array<std::int64_t, 3>;

struct Hit {
  u128 d2 = 0;          // exact squared distance to the query
  std::uint32_t item = 0;  // rank of the point (its index in the span the tree was built from)
};

// (d2, item) lexicographic: the order in which a leader takes its members (R1-HIER-011).
inline bool hit_before(const Hit& a, const Hit& b) { return a.d2 != b.d2 ? a.d2 < b.d2 : a.item < b.item; }

// Exact squared Euclidean distance.
u128 distance2(const Point& a, const Point& b);

class KdTree {
 public:
  // Point i has rank i. Every point starts alive.
  explicit KdTree(std::span<const Point> points);

  // Makes every point alive again (the tree shape does not depend on which are alive).
  void reset();
  bool alive(std::uint32_t item) const { return alive_[item] != 0; }
  std::uint32_t alive_count() const { return nodes_.empty() ? 0 : nodes_[0].alive; }
  // Marks an alive point dead.
  void remove(std::uint32_t item);

  // The (at most k) alive points j with |p_j - q|^2 <= r2 that come first in (d2, j) order,
  // written to `out` in that order. The result is a function of the alive set alone: the tree
  // only prunes subtrees that cannot hold a point of the answer.
  void nearest(const Point& q, u128 r2, std::uint32_t k, std::vector<Hit>& out);

 private:
  struct Node {
    Point lo{}, hi{};              // bounding box of the node's points (all, alive or not)
    std::uint32_t begin = 0, end = 0;  // range in perm_
    std::uint32_t left = 0, right = 0;  // children; left == 0 for a leaf (node 0 is the root)
    std::uint32_t parent = 0;
    std::uint32_t alive = 0;       // alive points below
    std::uint32_t min_alive = 0;   // lowest alive rank below (meaningless when alive == 0)
  };

  std::uint32_t build(std::uint32_t begin, std::uint32_t end, std::uint32_t parent);
  void search(std::uint32_t node);
  bool may_hold(u128 mind2, std::uint32_t min_rank) const;
  void offer(u128 d2, std::uint32_t item);
  u128 min_distance2(const Node& n) const;
  void recompute_min(std::uint32_t node);

  std::vector<Point> points_;         // by rank
  std::vector<std::uint32_t> perm_;   // ranks in tree order
  std::vector<Point> perm_points_;    // points_ in tree order, for locality in leaves
  std::vector<Node> nodes_;
  std::vector<std::uint32_t> leaf_of_;  // rank -> leaf node
  std::vector<std::uint8_t> alive_;

  // Query state of nearest().
  Point q_{};
  u128 r2_ = 0;
  std::uint32_t k_ = 0;
  std::vector<Hit> heap_;  // max-heap under hit_before
};

}  // namespace r1::hier
