// A static k-d tree over integer points with deletion: the k nearest alive points within a squared
// radius, nearest first, ties by rank; exact integer distances; searched bottom-up from a point's leaf
// (R1-HIER-010, R1-HIER-011, R1-HIER-070..071).
#include "kd_tree.hpp"

#include <algorithm>
#include <bit>
#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

namespace r1::hier {

namespace {

// Leaves hold at most this many points: small enough that a leaf scan is cheap, large enough
// that the tree has few nodes (about 2n / 16). It shapes only the search, never its answer. A
// leaf's alive points are a 16-bit mask in its node.
constexpr std::uint32_t kLeafSize = 16;
constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
// Cell faces that no split made. Valid coordinates have |c| <= 2^60 (R1-HIER-003), so these never
// equal a real split value.
constexpr std::int64_t kOpenLo = std::numeric_limits<std::int64_t>::min();
constexpr std::int64_t kOpenHi = std::numeric_limits<std::int64_t>::max();

std::uint64_t abs_diff(std::int64_t a, std::int64_t b) {
  // |a - b| < 2^63 for |a|, |b| < 2^62; formed in unsigned arithmetic so no signed overflow.
  return a >= b ? static_cast<std::uint64_t>(a) - static_cast<std::uint64_t>(b)
                : static_cast<std::uint64_t>(b) - static_cast<std::uint64_t>(a);
}

u128 square(std::uint64_t d) { return static_cast<u128>(d) * d; }

// The heap's order as a function object, so that the heap operations inline it.
constexpr auto kHitBefore = [](const Hit& a, const Hit& b) { return hit_before(a, b); };

u128 d2_of(const Point& a, const Point& b) {
  return square(abs_diff(a[0], b[0])) + square(abs_diff(a[1], b[1])) + square(abs_diff(a[2], b[2]));
}

}  // namespace

u128 distance2(const Point& a, const Point& b) { return d2_of(a, b); }

namespace {

// Nodes of a subtree over m points: a leaf, or a node and its halves floor(m / 2), ceil(m / 2).
// Sizes at one depth take at most two values, so the recursion is short.
std::uint32_t subtree_nodes(std::uint32_t m) {
  if (m <= kLeafSize) return 1;
  return 1 + subtree_nodes(m / 2) + subtree_nodes(m - m / 2);
}

// Below this many points a subtree is built on the calling thread (task overhead, not results).
constexpr std::uint32_t kParallelBuildMin = 1u << 14;

}  // namespace

KdTree::KdTree(std::span<const Point> points, bool parallel) : points_(points.begin(), points.end()) {
  const auto n = static_cast<std::uint32_t>(points_.size());
  leaf_of_.assign(n, 0);
  slot_of_.assign(n, 0);
  alive_.assign(n, 1);
  if (n == 0) return;
  const std::uint32_t count = subtree_nodes(n);
  nodes_.resize(count);
  cells_.resize(count);
  parent_.resize(count);
  std::vector<Ranked> work(n);
  for (std::uint32_t i = 0; i < n; ++i) work[i] = {points_[i], i};
  Cell everything;
  everything.lo.fill(kOpenLo);
  everything.hi.fill(kOpenHi);
  build(work.data(), 0, 0, everything, 0, n, parallel);  // the root is node 0
  perm_.resize(n);
  perm_points_.resize(n);
  for (std::uint32_t i = 0; i < n; ++i) {
    perm_[i] = work[i].rank;
    perm_points_[i] = work[i].p;
  }
  reset();
}

// Builds the subtree over work[begin, end) as node `self` and the nodes after it in preorder:
// the left child is self + 1, the right one follows the left subtree (children come after their
// parent, which reset() relies on). Node numbers depend only on subtree sizes, so the halves can
// be built at once.
std::uint32_t KdTree::build(Ranked* work, std::uint32_t self, std::uint32_t parent, const Cell& cell,
                            std::uint32_t begin, std::uint32_t end, bool parallel) {
  Node node;
  node.begin = begin;
  cells_[self] = cell;
  parent_[self] = parent;
  // The bounding box of the points.
  node.lo = node.hi = work[begin].p;
  for (std::uint32_t i = begin + 1; i < end; ++i) {
    const Point& p = work[i].p;
    for (std::size_t d = 0; d < 3; ++d) {
      node.lo[d] = std::min(node.lo[d], p[d]);
      node.hi[d] = std::max(node.hi[d], p[d]);
    }
  }
  if (end - begin <= kLeafSize) {
    node.count = static_cast<std::uint16_t>(end - begin);
    for (std::uint32_t i = begin; i < end; ++i) {
      leaf_of_[work[i].rank] = self;
      slot_of_[work[i].rank] = static_cast<std::uint8_t>(i - begin);
    }
    nodes_[self] = node;
    return self;
  }
  // Split the widest dimension of the points (ties: the lowest) at the median of (coordinate,
  // rank): a strict total order, so the halves are the same sets on every machine even when
  // coordinates repeat.
  std::size_t dim = 0;
  for (std::size_t d = 1; d < 3; ++d)
    if (abs_diff(node.hi[d], node.lo[d]) > abs_diff(node.hi[dim], node.lo[dim])) dim = d;
  const std::uint32_t mid = begin + (end - begin) / 2;
  std::nth_element(work + begin, work + mid, work + end, [dim](const Ranked& a, const Ranked& b) {
    return a.p[dim] != b.p[dim] ? a.p[dim] < b.p[dim] : a.rank < b.rank;
  });
  const std::uint32_t left = self + 1;
  node.right = left + subtree_nodes(mid - begin);
  // The points before mid have coordinate <= the median's, those from mid on >= it.
  const std::int64_t split = work[mid].p[dim];
  Cell left_cell = cell, right_cell = cell;
  left_cell.hi[dim] = split;
  right_cell.lo[dim] = split;
  if (parallel && end - begin >= kParallelBuildMin) {
    tbb::parallel_invoke([&] { build(work, left, self, left_cell, begin, mid, true); },
                         [&] { build(work, node.right, self, right_cell, mid, end, true); });
  } else {
    build(work, left, self, left_cell, begin, mid, parallel);
    build(work, node.right, self, right_cell, mid, end, parallel);
  }
  nodes_[self] = node;
  return self;
}

void KdTree::reset() {
  std::fill(alive_.begin(), alive_.end(), std::uint8_t{1});
  alive_count_ = static_cast<std::uint32_t>(alive_.size());
  // Children have larger indices than their parent, so one backward sweep sees them first.
  for (std::size_t i = nodes_.size(); i-- > 0;) {
    Node& nd = nodes_[i];
    if (nd.right == 0) {
      nd.alive_mask = static_cast<std::uint16_t>((1u << nd.count) - 1);
      refresh_leaf(nd);
    } else {
      nd.min_alive = std::min(nodes_[i + 1].min_alive, nodes_[nd.right].min_alive);
    }
  }
}

void KdTree::refresh_leaf(Node& leaf) {
  leaf.min_alive = kNone;
  for (unsigned mask = leaf.alive_mask; mask != 0; mask &= mask - 1)
    leaf.min_alive = std::min(leaf.min_alive, perm_[leaf.begin + static_cast<unsigned>(std::countr_zero(mask))]);
}

void KdTree::remove(std::uint32_t item) {
  alive_[item] = 0;
  --alive_count_;
  // A leaf's bound stays exact; the nodes above keep theirs (the removed rank is still a lower
  // bound of what is left) unless the leaf empties: "none alive" is passed up at once, so that
  // no search enters an empty subtree.
  std::uint32_t node = leaf_of_[item];
  Node& leaf = nodes_[node];
  leaf.alive_mask = static_cast<std::uint16_t>(leaf.alive_mask & ~(1u << slot_of_[item]));
  if (leaf.min_alive != item) return;
  refresh_leaf(leaf);
  while (node != 0 && nodes_[node].min_alive == kNone) {
    node = parent_[node];
    Node& p = nodes_[node];
    const std::uint32_t m = std::min(nodes_[node + 1].min_alive, nodes_[p.right].min_alive);
    if (m == p.min_alive) break;
    p.min_alive = m;
  }
}

u128 KdTree::box_distance2(const Point& q, const Node& n) {
  u128 s = 0;
  for (std::size_t d = 0; d < 3; ++d) {
    if (q[d] < n.lo[d]) s += square(abs_diff(n.lo[d], q[d]));
    else if (q[d] > n.hi[d]) s += square(abs_diff(q[d], n.hi[d]));
  }
  return s;
}

// The least squared distance from q (inside the cell) to a face of the cell: every point outside
// the node's subtree is at least this far from q. u128 max for a cell without faces (the root).
u128 KdTree::face_distance2(const Point& q, const Cell& c) {
  u128 m = u128_max;
  for (std::size_t d = 0; d < 3; ++d) {
    if (c.lo[d] != kOpenLo) m = std::min(m, square(abs_diff(q[d], c.lo[d])));
    if (c.hi[d] != kOpenHi) m = std::min(m, square(abs_diff(c.hi[d], q[d])));
  }
  return m;
}

// Every alive point below a node has d2 >= mind2 and rank >= min_rank, so (mind2, min_rank) is a
// lower bound in (d2, rank) order: a subtree whose bound is not before the current k-th best (or
// beyond the radius while fewer than k are held) cannot change the answer.
bool KdTree::may_hold(const Query& query, u128 mind2, std::uint32_t min_rank) {
  if (query.heap.size() < query.k) return mind2 <= query.r2;
  const Hit& worst = query.heap.front();
  return mind2 != worst.d2 ? mind2 < worst.d2 : min_rank < worst.item;
}

void KdTree::offer(Query& query, u128 d2, std::uint32_t item) {
  const Hit h{d2, item};
  std::vector<Hit>& heap = query.heap;
  if (heap.size() < query.k) {
    if (d2 > query.r2) return;
    heap.push_back(h);
    std::push_heap(heap.begin(), heap.end(), kHitBefore);
  } else if (hit_before(h, heap.front())) {
    std::pop_heap(heap.begin(), heap.end(), kHitBefore);
    heap.back() = h;
    std::push_heap(heap.begin(), heap.end(), kHitBefore);
  }
}

template <bool kTighten>
void KdTree::search(std::uint32_t node, Query& query) {
  Node& nd = nodes_[node];
  if (nd.right == 0) {
    std::uint32_t lowest = kNone;
    for (unsigned mask = nd.alive_mask; mask != 0; mask &= mask - 1) {
      const std::uint32_t j = nd.begin + static_cast<unsigned>(std::countr_zero(mask));
      const std::uint32_t item = perm_[j];
      lowest = std::min(lowest, item);
      if (item == query.skip) continue;
      const u128 d2 = d2_of(query.q, perm_points_[j]);
      // Beyond the radius, or behind the k-th best: not an answer (offer would refuse it).
      if (d2 > query.bound()) continue;
      offer(query, d2, item);
    }
    if constexpr (kTighten) nd.min_alive = lowest;  // the scan makes the leaf's bound exact
    return;
  }
  std::uint32_t a = node + 1, b = nd.right;
  const bool a_alive = nodes_[a].min_alive != kNone, b_alive = nodes_[b].min_alive != kNone;
  if (a_alive && b_alive) {
    u128 ma = box_distance2(query.q, nodes_[a]), mb = box_distance2(query.q, nodes_[b]);
    // Nearer child first (ties: the one with the lower rank bound), so the bound tightens early.
    if (mb < ma || (mb == ma && nodes_[b].min_alive < nodes_[a].min_alive)) {
      std::swap(a, b);
      std::swap(ma, mb);
    }
    if (may_hold(query, ma, nodes_[a].min_alive)) search<kTighten>(a, query);
    if (may_hold(query, mb, nodes_[b].min_alive)) search<kTighten>(b, query);
  } else if (a_alive || b_alive) {
    // One child holds nothing alive: no distance to it is needed.
    const std::uint32_t c = a_alive ? a : b;
    if (may_hold(query, box_distance2(query.q, nodes_[c]), nodes_[c].min_alive)) search<kTighten>(c, query);
  }
  // The children's bounds are lower bounds (tightened if just visited): so is their minimum.
  if constexpr (kTighten) nd.min_alive = std::min(nodes_[a].min_alive, nodes_[b].min_alive);
}

std::vector<u128> KdTree::nearest_other_lower_bounds(bool parallel) const {
  std::vector<u128> out(points_.size());
  auto leaf = [&](std::size_t node) {
    const Node& nd = nodes_[node];
    if (nd.right != 0) return;
    const std::uint32_t end = nd.begin + nd.count;
    for (std::uint32_t j = nd.begin; j < end; ++j) {
      u128 best = face_distance2(perm_points_[j], cells_[node]);
      for (std::uint32_t i = nd.begin; i < end; ++i)
        if (i != j) best = std::min(best, d2_of(perm_points_[j], perm_points_[i]));
      out[perm_[j]] = best;
    }
  };
  if (parallel) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nodes_.size(), 1024), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t node = r.begin(); node < r.end(); ++node) leaf(node);
    });
  } else {
    for (std::size_t node = 0; node < nodes_.size(); ++node) leaf(node);
  }
  return out;
}

// Every point outside a node's subtree lies on or beyond a face of its cell, so its d2 to q
// (inside the cell) is at least the squared distance to the nearest face. When that exceeds the
// query's bound, no outside point can join the answer, and the search from the item's leaf
// stops going up.
template <bool kTighten>
void KdTree::from_leaf(std::uint32_t item, Query& query) {
  std::uint32_t node = leaf_of_[item];
  search<kTighten>(node, query);
  while (node != 0 && face_distance2(query.q, cells_[node]) <= query.bound()) {
    const std::uint32_t parent = parent_[node];
    Node& p = nodes_[parent];
    const std::uint32_t sibling = node == parent + 1 ? p.right : parent + 1;
    const Node& sib = nodes_[sibling];
    if (sib.min_alive != kNone && may_hold(query, box_distance2(query.q, sib), sib.min_alive))
      search<kTighten>(sibling, query);
    if constexpr (kTighten) p.min_alive = std::min(nodes_[parent + 1].min_alive, nodes_[p.right].min_alive);
    node = parent;
  }
  std::sort_heap(query.heap.begin(), query.heap.end(), kHitBefore);
}

void KdTree::nearest_from(std::uint32_t item, u128 r2, std::uint32_t k, std::vector<Hit>& out) {
  out.clear();
  if (k == 0 || alive_count_ == 0) return;
  Query query{points_[item], r2, k, kNone, out};
  from_leaf<true>(item, query);
}

void KdTree::nearest_from_readonly(std::uint32_t item, u128 r2, std::uint32_t k, std::vector<Hit>& out) const {
  out.clear();
  if (k == 0 || alive_count_ == 0) return;
  Query query{points_[item], r2, k, item, out};
  // Without tightening, the search only reads the tree.
  const_cast<KdTree*>(this)->from_leaf<false>(item, query);
}

void KdTree::nearest(const Point& q, u128 r2, std::uint32_t k, std::vector<Hit>& out) {
  out.clear();
  if (k == 0 || alive_count_ == 0) return;
  Query query{q, r2, k, kNone, out};
  if (may_hold(query, box_distance2(q, nodes_[0]), nodes_[0].min_alive)) search<true>(0, query);
  std::sort_heap(out.begin(), out.end(), kHitBefore);
}

}  // namespace r1::hier
