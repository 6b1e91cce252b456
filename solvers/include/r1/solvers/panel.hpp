// The spectral solver's vectors as columns of a row-major panel, and the block kernels on them in
// both numeric domains: scaled inner products, combinations with one rounding per entry, exact
// scaling, random columns (R1-SPEC-011..015, R1-SPEC-030).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "r1/fixedpoint/exact_sum.hpp"
#include "r1/fixedpoint/q32.hpp"

namespace r1::spectral {

// An exact sum of 128-bit terms: a plain i128 while it cannot overflow, spilling into an
// ExactSum when an addition would (R1-SPEC-011). Either way the total is exact, so the fast
// path never changes a result; it only avoids the three-limb add on the common path.
class FastExact {
 public:
  void add(i128 t) {
    i128 r;
    if (__builtin_add_overflow(acc_, t, &r)) {
      spill_.add_term(acc_);
      spilled_ = true;
      acc_ = t;
    } else {
      acc_ = r;
    }
  }
  void merge(const FastExact& o) {
    add(o.acc_);
    if (o.spilled_) {
      spill_.merge(o.spill_);
      spilled_ = true;
    }
  }
  // The exact total.
  fx::ExactSum total() const {
    fx::ExactSum s = spill_;
    s.add_term(acc_);
    return s;
  }
  // RNE(total / 2^s), 1 <= s <= 126; throws fx::OverflowError when it does not fit int64.
  std::int64_t round_shift(int s) const;

 private:
  i128 acc_ = 0;
  fx::ExactSum spill_;
  bool spilled_ = false;
};

// A bit pattern whose highest set bit bounds |x| (x ^ (x >> 63) is |x| - 1 for negatives, |x|
// otherwise); OR-ing these over a block bounds every magnitude in it without a branch. The
// unchecked i128 fast paths test it against their proven bounds.
inline std::uint64_t magnitude_bits(std::int64_t x) { return static_cast<std::uint64_t>(x ^ (x >> 63)); }

// n rows by `cols` columns, row-major: entry (i, c) is entry i of vector c. A block of vectors
// then sits side by side in every row, so the operator gathers one short run per stored entry
// for a whole block and the kernels read each row once for many columns. The layout is a
// matter of speed only: every result is defined entry by entry (spec/spectral.md).
template <class Scalar>
class Panel {
 public:
  Panel() = default;
  Panel(std::size_t n, std::size_t cols) : n_(n), cols_(cols), a_(n * cols) {}
  std::size_t rows() const { return n_; }
  std::size_t cols() const { return cols_; }
  Scalar* row(std::size_t i) { return a_.data() + i * cols_; }
  const Scalar* row(std::size_t i) const { return a_.data() + i * cols_; }
  Scalar& at(std::size_t i, std::size_t c) { return a_[i * cols_ + c]; }
  const Scalar& at(std::size_t i, std::size_t c) const { return a_[i * cols_ + c]; }
  // The first entry of column c; consecutive entries are cols() apart.
  Scalar* column(std::size_t c) { return a_.data() + c; }
  const Scalar* column(std::size_t c) const { return a_.data() + c; }
  std::vector<Scalar> copy_column(std::size_t c) const;
  void set_column(std::size_t c, std::span<const Scalar> v);

 private:
  std::size_t n_ = 0, cols_ = 0;
  std::vector<Scalar> a_;
};

// A list of panel columns.
using Cols = std::span<const std::uint32_t>;

// The operations the block Lanczos driver needs, for Scalar = fx::Q32 (canonical) or double: the
// solver's vector-space concept (R1-SOL-002). The kernels are virtual so that an accelerated
// backend can run the one driver on its own kernels (accel/cpu's TBB and SIMD ones); every
// implementation must give these functions' bits, which the kernel tests hold it to.
// `e` fixes the scaled inner product <x, y> = 2^-e sum_i x_i y_i, under which basis vectors have
// unit length while their entries stay O(1) (R1-SPEC-011). With `parallel`, work is split over
// TBB tasks at fixed boundaries; every result is bit-identical to the serial one (exact sums
// merge in any order; fp64 evaluates the fixed pairwise tree of each product).
//
// Q32 panels hold raws in units of 2^-frac (frac >= 32; the solver's basis uses 48, R1-SPEC-011):
// the kernels below are the same integer operations at any frac, only the inner product's scale
// and the random vectors' units follow it. fp64 ignores frac.
template <class Scalar>
class PanelOps {
 public:
  PanelOps(std::size_t n, int e, bool parallel, int frac = 32) : n_(n), e_(e), frac_(frac), parallel_(parallel) {}
  virtual ~PanelOps() = default;
  std::size_t size() const { return n_; }
  int scale_exponent() const { return e_; }
  int frac_bits() const { return frac_; }
  bool parallel() const { return parallel_; }

  // out[q * ws.size() + c] = <column qs[q], column ws[c]> as a double: Q32, the exact sum of raw
  // products times 2^-(2 frac + e), correctly rounded; fp64, the pairwise dot (R1-NUM-051) times 2^-e.
  virtual void dots(const Panel<Scalar>& p, Cols qs, Cols ws, std::span<double> out) const;
  double dot(const Panel<Scalar>& p, std::uint32_t a, std::uint32_t b) const;
  // For every o: column outs[o] <- (column bases[o], or 0 when bases is empty)
  //                                  + sum_t coef[t * outs.size() + o] * column terms[t],
  // one rounding per entry (Q32: coefficients enter as RNE(c 2^60), |c| < 8; fp64: left to
  // right over t, no FMA). An output column may also be a base or a term: each row's results are
  // formed from the row's old values before any is written.
  virtual void combine(Panel<Scalar>& p, Cols outs, Cols bases, Cols terms, std::span<const double> coef) const;
  // Column c <- column c * f (Q32: the exact product rounded once).
  virtual void scale(Panel<Scalar>& p, std::uint32_t c, double f) const;
  // Column c <- the random vector of R1-SPEC-030: entry i is bits(seed, i, dim) >> 31 minus
  // 2^32, times 2^-32 (uniform multiples of 2^-32 in [-1, 1)); the same values in both domains
  // and at every frac.
  virtual void random(Panel<Scalar>& p, std::uint32_t c, std::uint64_t seed, std::uint64_t dim) const;
  // Column dst <- column src.
  virtual void copy(Panel<Scalar>& p, std::uint32_t dst, std::uint32_t src) const;
  // Columns dst[k] <- columns src[k] for every k at once, in one sweep over the rows (a column may
  // be both a source and a destination: each row is read before it is written).
  virtual void move(Panel<Scalar>& p, Cols dst, Cols src) const;
  // The Chebyshev filter's recurrence on compact blocks: spectral::three_term (below) with this
  // object's parallel(), the values it defines.
  virtual void three_term(std::size_t len, const Scalar* s, const Scalar* y, Scalar* p, double alpha, double beta,
                          double gamma) const;

 private:
  std::size_t n_;
  int e_, frac_;
  bool parallel_;
};

template <>
void PanelOps<fx::Q32>::dots(const Panel<fx::Q32>&, Cols, Cols, std::span<double>) const;
template <>
void PanelOps<fx::Q32>::combine(Panel<fx::Q32>&, Cols, Cols, Cols, std::span<const double>) const;
template <>
void PanelOps<fx::Q32>::scale(Panel<fx::Q32>&, std::uint32_t, double) const;
template <>
void PanelOps<fx::Q32>::random(Panel<fx::Q32>&, std::uint32_t, std::uint64_t, std::uint64_t) const;
template <>
void PanelOps<double>::dots(const Panel<double>&, Cols, Cols, std::span<double>) const;
template <>
void PanelOps<double>::combine(Panel<double>&, Cols, Cols, Cols, std::span<const double>) const;
template <>
void PanelOps<double>::scale(Panel<double>&, std::uint32_t, double) const;
template <>
void PanelOps<double>::random(Panel<double>&, std::uint32_t, std::uint64_t, std::uint64_t) const;

// The row block length the kernels split at, and the length below which they stay serial;
// neither changes a result.
inline constexpr std::size_t kBlock = 4096;
inline constexpr std::size_t kParallelMin = std::size_t{1} << 15;

// The argument checks of PanelOps::dots and PanelOps::combine (sizes, every column inside a panel
// of `cols` columns), for kernels that override them: std::invalid_argument on a mismatch.
void check_dots(std::size_t rows, std::size_t n, std::size_t cols, Cols qs, Cols ws, std::size_t outs);
void check_combine(std::size_t rows, std::size_t n, std::size_t cols, Cols outs, Cols bases, Cols terms,
                   std::size_t coefs);

// The exact inner products' reduction (R1-SPEC-011): block_sum(lo, hi, acc) adds the exact
// products of rows [lo, hi) of every pair into acc[pair]; the row blocks run serially or as TBB
// tasks (exact sums merge in any order), and out[pair] = the total times 2^-shift, correctly
// rounded. Q32 kernels differ only in how they sum a block.
using BlockDots = std::function<void(std::size_t lo, std::size_t hi, std::vector<FastExact>& acc)>;
void exact_dots(std::size_t n, bool parallel, int shift, std::span<double> out, const BlockDots& block_sum);

// The Chebyshev filter's recurrence on compact blocks (R1-SPEC-080): for k < len,
// p[k] <- alpha s[k] + beta y[k] + gamma p[k] (gamma = 0: p is not read), one rounding per entry
// as PanelOps::combine's with the terms (s, y, p) (Q32: coefficients RNE(c 2^60), |c| < 8, the
// exact sum rounded once, ties to even; fp64: left to right, no FMA). Bit-identical in parallel.
template <class Scalar>
void three_term(std::size_t len, const Scalar* s, const Scalar* y, Scalar* p, double alpha, double beta, double gamma,
                bool parallel);

// Runs body(lo, hi) over [0, n) in kBlock pieces: serially, or as TBB tasks when asked and the
// range is long enough. Callers only write disjoint ranges, so the split never shows.
void for_row_blocks(std::size_t n, bool parallel, const std::function<void(std::size_t, std::size_t)>& body);

}  // namespace r1::spectral
