// A static k-d tree over integer points with deletion: the k nearest alive points within a squared
// radius, nearest first, ties by rank; exact integer distances; searched bottom-up from a point's leaf
// (R1-HIER-010, R1-HIER-011, R1-HIER-070..071).
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
  // Point i has rank i. Every point starts alive. With `parallel` the two halves of a node are
  // built on TBB workers; the tree is the same (R1-HIER-070).
  explicit KdTree(std::span<const Point> points, bool parallel = false);

  // Makes every point alive again (the tree shape does not depend on which are alive).
  void reset();
  bool alive(std::uint32_t item) const { return alive_[item] != 0; }
  std::uint32_t alive_count() const { return alive_count_; }
  // The leaf that holds point `item`: leaves are numbered in tree order, so items sorted by it are
  // near one another in space.
  std::uint32_t leaf_of(std::uint32_t item) const { return leaf_of_[item]; }
  // Marks an alive point dead: O(1), the nodes above learn it lazily (see Node::min_alive).
  void remove(std::uint32_t item);

  // The (at most k) alive points j with |p_j - q|^2 <= r2 that come first in (d2, j) order,
  // written to `out` in that order. The result is a function of the alive set alone: the tree
  // only prunes subtrees that cannot hold a point of the answer.
  void nearest(const Point& q, u128 r2, std::uint32_t k, std::vector<Hit>& out);
  // The same answer for q = the position of point `item` (alive or not), found bottom-up: from
  // the item's leaf through ever larger subtrees, stopping once no point outside the current
  // subtree's cell can come near enough. A small radius then costs a leaf, not a descent.
  void nearest_from(std::uint32_t item, u128 r2, std::uint32_t k, std::vector<Hit>& out);
  // nearest_from's answer with `item` itself left out, computed without touching the tree: any
  // number of these may run at once (not beside remove, reset or the other queries). Used to
  // answer a window of leaders' queries in parallel before they are checked in order.
  void nearest_from_readonly(std::uint32_t item, u128 r2, std::uint32_t k, std::vector<Hit>& out) const;
  // For every point (by rank), a lower bound on the squared distance to its nearest other point,
  // alive or not: the least of the distances to the other points of its leaf and to its leaf's
  // cell faces (every point outside the leaf lies beyond one). One pass over the leaves, on TBB
  // workers when `parallel` (the values are per point).
  std::vector<u128> nearest_other_lower_bounds(bool parallel) const;

 private:
  // One cache line.
  struct alignas(64) Node {
    Point lo{}, hi{};          // bounding box of the node's points (all, alive or not)
    std::uint32_t begin = 0;   // first position in perm_ of the node's points
    std::uint32_t right = 0;   // right child; the left child is the next node; 0: a leaf
    // A lower bound on the lowest alive rank below, kNone (all ones) exactly when none is alive.
    // Removing a point leaves the bounds above its leaf as they were (still lower bounds, now
    // possibly loose) unless the leaf empties, which is passed up; a search that visits a node
    // tightens it from its children on the way back.
    std::uint32_t min_alive = 0;
    // Leaves only: the point count (at most kLeafSize) and which of them are alive (bit i: the
    // point at perm_[begin + i]), so that a leaf scan reads no per-point flag elsewhere in memory.
    std::uint16_t count = 0;
    std::uint16_t alive_mask = 0;
  };
  static_assert(sizeof(Node) == 64);

  // A node's cell: the box its ancestors' split planes cut out (closed; a point of the subtree
  // lies in it, a point outside lies on or beyond one of its faces). kOpen stands for no face.
  struct Cell {
    Point lo{}, hi{};
  };

  // A point with its rank, the unit the build partitions (no lookup per comparison).
  struct Ranked {
    Point p;
    std::uint32_t rank;
  };

  // One query: the point, the radius, k, a rank to leave out (kNone: none) and the heap of the
  // best so far (a max-heap under hit_before), which ends as the answer.
  struct Query {
    Point q;
    u128 r2;
    std::uint32_t k;
    std::uint32_t skip;
    std::vector<Hit>& heap;
    // The least d2 a point must have to be refused: the radius while fewer than k are held,
    // else the k-th best (a point at exactly that d2 may still win on rank).
    u128 bound() const { return heap.size() < k ? r2 : heap.front().d2; }
  };

  std::uint32_t build(Ranked* work, std::uint32_t self, std::uint32_t parent, const Cell& cell, std::uint32_t begin,
                      std::uint32_t end, bool parallel);
  // kTighten: a search may tighten the bounds of the nodes it visits (not in read-only queries).
  template <bool kTighten>
  void search(std::uint32_t node, Query& query);
  template <bool kTighten>
  void from_leaf(std::uint32_t item, Query& query);
  static bool may_hold(const Query& query, u128 mind2, std::uint32_t min_rank);
  static void offer(Query& query, u128 d2, std::uint32_t item);
  static u128 box_distance2(const Point& q, const Node& n);
  static u128 face_distance2(const Point& q, const Cell& c);
  void refresh_leaf(Node& leaf);

  std::vector<Point> points_;         // by rank
  std::vector<std::uint32_t> perm_;   // ranks in tree order
  std::vector<Point> perm_points_;    // points_ in tree order, for locality in leaves
  std::vector<Node> nodes_;
  std::vector<Cell> cells_;              // by node
  std::vector<std::uint32_t> parent_;    // by node (the root's is 0)
  std::vector<std::uint32_t> leaf_of_;  // rank -> leaf node
  std::vector<std::uint8_t> slot_of_;   // rank -> its bit in the leaf's alive_mask
  std::vector<std::uint8_t> alive_;
  std::uint32_t alive_count_ = 0;
};

}  // namespace r1::hier
