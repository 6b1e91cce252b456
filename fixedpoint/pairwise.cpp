// fp64 pairwise tree reduction: blocked serial evaluation and TBB tasks (R1-NUM-050..054).
#include "r1/fixedpoint/pairwise.hpp"

#include <tbb/parallel_invoke.h>

#include <bit>
#include <cmath>
#include <stdexcept>

namespace r1::fx {
namespace {

// The split of R1-NUM-051: the largest power of two strictly below n (n >= 2).
std::size_t split_point(std::size_t n) { return std::bit_floor(n - 1); }

double recursive_sum(const double* x, std::size_t n) {
  if (n == 0) return 0.0;
  if (n == 1) return x[0];
  const std::size_t m = split_point(n);
  return recursive_sum(x, m) + recursive_sum(x + m, n - m);
}

// Blocks of 64 leaves: every split point above a block is a power of two >= 64, hence a block
// boundary, so the tree is a perfect tree inside each full block plus the tree over the block
// sums (and the final partial block, the tail, as one more item). 64 keeps the buffer in L1 and
// the level-by-level loops long enough to vectorise.
constexpr std::size_t kBlock = 64;

// The perfect tree over exactly kBlock values, one level at a time, in place.
double block_tree(double* t) {
  for (std::size_t width = kBlock / 2; width >= 1; width /= 2) {
    for (std::size_t i = 0; i < width; ++i) t[i] = t[2 * i] + t[2 * i + 1];
  }
  return t[0];
}

}  // namespace

// Full blocks enter a binary counter (a stack of perfect subtrees, a merge whenever two have the
// same height); the stack then folds from the right, which is the split rule applied to the
// items (proofs/pairwise_tree.md, step 3).
void PairwiseAccumulator::push(double* block) noexcept {
  double s = block_tree(block);
  unsigned h = 0;
  while (top_ > 0 && heights_[top_ - 1] == h) {
    s = sums_[--top_] + s;
    ++h;
  }
  sums_[top_] = s;
  heights_[top_++] = h;
  any_ = true;
}

double PairwiseAccumulator::finish(const double* tail, std::size_t count) noexcept {
  // The tail is the last item (or the whole tree when no block came); without a tail the last
  // perfect subtree is.
  double s = (count > 0 || !any_) ? recursive_sum(tail, count) : sums_[--top_];
  while (top_ > 0) s = sums_[--top_] + s;
  any_ = false;
  return s;
}

namespace {

static_assert(kBlock == kPairwiseLeafBlock, "the accumulator's blocks are the tree's blocks");

// The tree over n leaves, where fill(begin, count, out) writes leaves begin.. into out.
template <class Fill>
double blocked_tree(std::size_t n, Fill fill) {
  alignas(64) double buf[kBlock];
  PairwiseAccumulator acc;
  std::size_t i = 0;
  for (; i + kBlock <= n; i += kBlock) {
    fill(i, kBlock, buf);
    acc.push(buf);
  }
  fill(i, n - i, buf);
  return acc.finish(buf, n - i);
}

double serial_sum(const double* x, std::size_t n) {
  return blocked_tree(n, [x](std::size_t begin, std::size_t count, double* out) {
    for (std::size_t j = 0; j < count; ++j) out[j] = x[begin + j];
  });
}

double serial_dot(const double* a, const double* b, std::size_t n) {
  return blocked_tree(n, [a, b](std::size_t begin, std::size_t count, double* out) {
    for (std::size_t j = 0; j < count; ++j) out[j] = a[begin + j] * b[begin + j];
  });
}

// Splits exactly as the tree does, so each task computes one subtree of the serial result.
double parallel_sum(const double* x, std::size_t n, std::size_t grain) {
  if (n <= grain || n < 2) return serial_sum(x, n);
  const std::size_t m = split_point(n);
  double left = 0.0, right = 0.0;
  tbb::parallel_invoke([&] { left = parallel_sum(x, m, grain); }, [&] { right = parallel_sum(x + m, n - m, grain); });
  return left + right;
}

double parallel_dot(const double* a, const double* b, std::size_t n, std::size_t grain) {
  if (n <= grain || n < 2) return serial_dot(a, b, n);
  const std::size_t m = split_point(n);
  double left = 0.0, right = 0.0;
  tbb::parallel_invoke([&] { left = parallel_dot(a, b, m, grain); },
                       [&] { right = parallel_dot(a + m, b + m, n - m, grain); });
  return left + right;
}

void require_same_length(std::span<const double> a, std::span<const double> b) {
  if (a.size() != b.size()) throw std::invalid_argument("pairwise_dot: spans of different lengths");
}

}  // namespace

double pairwise_sum(std::span<const double> x) noexcept { return serial_sum(x.data(), x.size()); }

double pairwise_dot(std::span<const double> a, std::span<const double> b) {
  require_same_length(a, b);
  return serial_dot(a.data(), b.data(), a.size());
}

double pairwise_norm2(std::span<const double> x) noexcept { return std::sqrt(serial_dot(x.data(), x.data(), x.size())); }

double parallel_pairwise_sum(std::span<const double> x, std::size_t grain) {
  return parallel_sum(x.data(), x.size(), grain == 0 ? 1 : grain);
}

double parallel_pairwise_dot(std::span<const double> a, std::span<const double> b, std::size_t grain) {
  require_same_length(a, b);
  return parallel_dot(a.data(), b.data(), a.size(), grain == 0 ? 1 : grain);
}

double parallel_pairwise_norm2(std::span<const double> x, std::size_t grain) {
  return std::sqrt(parallel_dot(x.data(), x.data(), x.size(), grain == 0 ? 1 : grain));
}

double pairwise_sum_recursive(std::span<const double> x) noexcept { return recursive_sum(x.data(), x.size()); }

}  // namespace r1::fx
