// A static k-d tree over integer points with deletion: the k nearest alive points within a squared
// radius, nearest first, ties by rank; exact integer distances (R1-HIER-010, R1-HIER-011).
#include "kd_tree.hpp"

#include <algorithm>
#include <limits>

namespace r1::hier {

namespace {

// Leaves hold at most this many points: small enough that a leaf scan is cheap, large enough
// that the tree has few nodes (about 2n / 8). It shapes only the search, never its answer.
constexpr std::uint32_t kLeafSize = 8;
constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

std::uint64_t abs_diff(std::int64_t a, std::int64_t b) {
  // |a - b| < 2^63 for |a|, |b| < 2^62; formed in unsigned arithmetic so no signed overflow.
  return a >= b ? static_cast<std::uint64_t>(a) - static_cast<std::uint64_t>(b)
                : static_cast<std::uint64_t>(b) - static_cast<std::uint64_t>(a);
}

u128 square(std::uint64_t d) { return static_cast<u128>(d) * d; }

}  // namespace

u128 distance2(const Point& a, const Point& b) {
  return square(abs_diff(a[0], b[0])) + square(abs_diff(a[1], b[1])) + square(abs_diff(a[2], b[2]));
}

KdTree::KdTree(std::span<const Point> points) : points_(points.begin(), points.end()) {
  const auto n = static_cast<std::uint32_t>(points_.size());
  perm_.resize(n);
  for (std::uint32_t i = 0; i < n; ++i) perm_[i] = i;
  leaf_of_.assign(n, 0);
  alive_.assign(n, 1);
  if (n == 0) return;
  nodes_.reserve(2 * (n / kLeafSize + 1));
  build(0, n, 0);  // the root is node 0
  perm_points_.resize(n);
  for (std::uint32_t i = 0; i < n; ++i) perm_points_[i] = points_[perm_[i]];
  reset();
}

// Builds the subtree over perm_[begin, end) and returns its node index (children come after
// their parent, which reset() relies on).
std::uint32_t KdTree::build(std::uint32_t begin, std::uint32_t end, std::uint32_t parent) {
  const auto self = static_cast<std::uint32_t>(nodes_.size());
  nodes_.emplace_back();
  Node node;
  node.begin = begin;
  node.end = end;
  node.parent = parent;
  node.lo = node.hi = points_[perm_[begin]];
  for (std::uint32_t i = begin + 1; i < end; ++i) {
    const Point& p = points_[perm_[i]];
    for (std::size_t d = 0; d < 3; ++d) {
      node.lo[d] = std::min(node.lo[d], p[d]);
      node.hi[d] = std::max(node.hi[d], p[d]);
    }
  }
  if (end - begin <= kLeafSize) {
    for (std::uint32_t i = begin; i < end; ++i) leaf_of_[perm_[i]] = self;
    nodes_[self] = node;
    return self;
  }
  // Split the widest dimension (ties: the lowest) at the median of (coordinate, rank): a strict
  // total order, so the halves are the same sets on every machine even when coordinates repeat.
  std::size_t dim = 0;
  for (std::size_t d = 1; d < 3; ++d)
    if (abs_diff(node.hi[d], node.lo[d]) > abs_diff(node.hi[dim], node.lo[dim])) dim = d;
  const std::uint32_t mid = begin + (end - begin) / 2;
  std::nth_element(perm_.begin() + begin, perm_.begin() + mid, perm_.begin() + end,
                   [&](std::uint32_t a, std::uint32_t b) {
                     const std::int64_t ca = points_[a][dim], cb = points_[b][dim];
                     return ca != cb ? ca < cb : a < b;
                   });
  node.left = build(begin, mid, self);
  node.right = build(mid, end, self);
  nodes_[self] = node;
  return self;
}

void KdTree::reset() {
  std::fill(alive_.begin(), alive_.end(), std::uint8_t{1});
  // Children have larger indices than their parent, so one backward sweep sees them first.
  for (std::size_t i = nodes_.size(); i-- > 0;) {
    Node& nd = nodes_[i];
    if (nd.left == 0) {
      nd.alive = nd.end - nd.begin;
      nd.min_alive = kNone;
      for (std::uint32_t j = nd.begin; j < nd.end; ++j) nd.min_alive = std::min(nd.min_alive, perm_[j]);
    } else {
      nd.alive = nodes_[nd.left].alive + nodes_[nd.right].alive;
      nd.min_alive = std::min(nodes_[nd.left].min_alive, nodes_[nd.right].min_alive);
    }
  }
}

void KdTree::recompute_min(std::uint32_t node) {
  Node& nd = nodes_[node];
  nd.min_alive = kNone;
  for (std::uint32_t j = nd.begin; j < nd.end; ++j)
    if (alive_[perm_[j]] != 0) nd.min_alive = std::min(nd.min_alive, perm_[j]);
}

void KdTree::remove(std::uint32_t item) {
  alive_[item] = 0;
  std::uint32_t node = leaf_of_[item];
  for (std::uint32_t n = node;; n = nodes_[n].parent) {
    --nodes_[n].alive;
    if (n == 0) break;
  }
  if (nodes_[node].min_alive != item) return;  // the lowest alive rank is unchanged everywhere
  recompute_min(node);
  while (node != 0) {
    const std::uint32_t parent = nodes_[node].parent;
    Node& p = nodes_[parent];
    const std::uint32_t m = std::min(nodes_[p.left].min_alive, nodes_[p.right].min_alive);
    if (m == p.min_alive) break;
    p.min_alive = m;
    node = parent;
  }
}

u128 KdTree::min_distance2(const Node& n) const {
  u128 s = 0;
  for (std::size_t d = 0; d < 3; ++d) {
    if (q_[d] < n.lo[d]) s += square(abs_diff(n.lo[d], q_[d]));
    else if (q_[d] > n.hi[d]) s += square(abs_diff(q_[d], n.hi[d]));
  }
  return s;
}

// Every alive point below a node has d2 >= mind2 and rank >= min_rank, so (mind2, min_rank) is a
// lower bound in (d2, rank) order: a subtree whose bound is not before the current k-th best (or
// beyond the radius while fewer than k are held) cannot change the answer.
bool KdTree::may_hold(u128 mind2, std::uint32_t min_rank) const {
  if (heap_.size() < k_) return mind2 <= r2_;
  const Hit& worst = heap_.front();
  return mind2 != worst.d2 ? mind2 < worst.d2 : min_rank < worst.item;
}

void KdTree::offer(u128 d2, std::uint32_t item) {
  const Hit h{d2, item};
  if (heap_.size() < k_) {
    if (d2 > r2_) return;
    heap_.push_back(h);
    std::push_heap(heap_.begin(), heap_.end(), hit_before);
  } else if (hit_before(h, heap_.front())) {
    std::pop_heap(heap_.begin(), heap_.end(), hit_before);
    heap_.back() = h;
    std::push_heap(heap_.begin(), heap_.end(), hit_before);
  }
}

void KdTree::search(std::uint32_t node) {
  const Node& nd = nodes_[node];
  if (nd.left == 0) {
    for (std::uint32_t j = nd.begin; j < nd.end; ++j) {
      const std::uint32_t item = perm_[j];
      if (alive_[item] != 0) offer(distance2(q_, perm_points_[j]), item);
    }
    return;
  }
  std::uint32_t a = nd.left, b = nd.right;
  u128 ma = min_distance2(nodes_[a]), mb = min_distance2(nodes_[b]);
  // Nearer child first (ties: the one holding the lower rank), so the bound tightens early.
  if (mb < ma || (mb == ma && nodes_[b].min_alive < nodes_[a].min_alive)) {
    std::swap(a, b);
    std::swap(ma, mb);
  }
  if (nodes_[a].alive != 0 && may_hold(ma, nodes_[a].min_alive)) search(a);
  if (nodes_[b].alive != 0 && may_hold(mb, nodes_[b].min_alive)) search(b);
}

void KdTree::nearest(const Point& q, u128 r2, std::uint32_t k, std::vector<Hit>& out) {
  out.clear();
  if (k == 0 || nodes_.empty() || nodes_[0].alive == 0) return;
  q_ = q;
  r2_ = r2;
  k_ = k;
  heap_.clear();
  if (may_hold(min_distance2(nodes_[0]), nodes_[0].min_alive)) search(0);
  std::sort_heap(heap_.begin(), heap_.end(), hit_before);
  out.assign(heap_.begin(), heap_.end());
}

}  // namespace r1::hier
