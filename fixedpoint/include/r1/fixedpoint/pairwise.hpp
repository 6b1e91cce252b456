// fp64 sums and dot products in one fixed pairwise tree, serial and TBB-parallel (R1-NUM-050..054).
#pragma once

#include <cstddef>
#include <span>

namespace r1::fx {

// The tree (R1-NUM-051): S(x[0..n)) is +0.0 for n = 0, x[0] for n = 1, and for n >= 2
//     S(x[0..n)) = S(x[0..m)) + S(x[m..n)),   m = the largest power of two below n,
// every + a correctly rounded IEEE double addition. The result is a pure function of the input
// (order, grain and thread count play no part) with error at most ceil(log2 n) u sum|x_i| to
// first order (u = 2^-53). Finite inputs whose result is finite give the same bits everywhere;
// a NaN result is a NaN with an unspecified payload.

// S(x).
double pairwise_sum(std::span<const double> x) noexcept;
// S(p) with p_i = a_i * b_i, each product rounded once (no fused multiply-add).
// std::invalid_argument when the lengths differ.
double pairwise_dot(std::span<const double> a, std::span<const double> b);
// sqrt(pairwise_dot(x, x)), the IEEE correctly rounded square root; no rescaling, so it
// overflows to inf when the squares do.
double pairwise_norm2(std::span<const double> x) noexcept;

// The same trees evaluated by TBB tasks: subtrees of more than `grain` leaves run in parallel,
// the rest serially. Bit-identical to the serial functions for every grain (0 counts as 1) and
// every thread count, because every subtree is the same function of its own slice.
inline constexpr std::size_t kPairwiseDefaultGrain = std::size_t{1} << 14;
double parallel_pairwise_sum(std::span<const double> x, std::size_t grain = kPairwiseDefaultGrain);
double parallel_pairwise_dot(std::span<const double> a, std::span<const double> b,
                             std::size_t grain = kPairwiseDefaultGrain);
double parallel_pairwise_norm2(std::span<const double> x, std::size_t grain = kPairwiseDefaultGrain);

// The tree built incrementally, for callers that produce the leaves in pieces (many dot products
// in one sweep over a row-major matrix, say): push() each full block of kPairwiseLeafBlock
// consecutive leaves in order, then finish() with the remaining tail (fewer than
// kPairwiseLeafBlock leaves). The result is S of all leaves pushed, bit for bit (the blocked
// evaluation of proofs/pairwise_tree.md, step 3); pairwise_sum and pairwise_dot use it.
inline constexpr std::size_t kPairwiseLeafBlock = 64;
class PairwiseAccumulator {
 public:
  // Adds the next full block of kPairwiseLeafBlock leaves; the buffer is overwritten.
  void push(double* block) noexcept;
  // S of every leaf pushed followed by the tail; resets the accumulator.
  double finish(const double* tail, std::size_t count) noexcept;

 private:
  double sums_[64] = {};
  unsigned heights_[64] = {};
  int top_ = 0;
  bool any_ = false;
};

// The definition above as literal recursion, without the blocked fast path: the oracle the tests
// compare the fast path with (the switch that turns the fast path off).
double pairwise_sum_recursive(std::span<const double> x) noexcept;

}  // namespace r1::fx
