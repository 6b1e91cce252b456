// Vector kernels of the spectral solver in both numeric domains (R1-SPEC-011..015): scaled
// inner products, linear combinations with one rounding per entry, exact scaling, basis rotation.
#pragma once

#include <cstddef>
#include <cstdint>
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

// The operations the Lanczos driver needs, for Scalar = fx::Q32 (canonical) or double.
// Vectors have n entries; `e` fixes the scaled inner product <x, y> = 2^-e sum_i x_i y_i, under
// which basis vectors have unit length while their entries stay O(1) (R1-SPEC-011).
// With `parallel`, work is split over TBB tasks at fixed index boundaries; every result is
// bit-identical to the serial one (exact sums merge in any order; fp64 uses the fixed pairwise
// tree, whose parallel evaluation is the same function).
template <class Scalar>
class VectorOps {
 public:
  VectorOps(std::size_t n, int e, bool parallel) : n_(n), e_(e), parallel_(parallel) {}
  std::size_t size() const { return n_; }
  int scale_exponent() const { return e_; }
  bool parallel() const { return parallel_; }

  // <x, y> as a double: Q32, the exact sum correctly rounded; fp64, the pairwise dot times 2^-e.
  double dot(std::span<const Scalar> x, std::span<const Scalar> y) const;
  // out[k] = <qs[k], w> for every k, reading w once per block.
  void dots(std::span<const Scalar* const> qs, std::span<const Scalar> w, std::span<double> out) const;
  // out_i = base_i + sum_k c[k] * xs[k]_i, one rounding per entry (Q32: coefficients enter as
  // RNE(c * 2^60), |c| < 8; fp64: evaluated left to right). `base` may be out itself or null (0).
  void combine(std::span<Scalar> out, const Scalar* base, std::span<const double> c,
               std::span<const Scalar* const> xs) const;
  // out_i = x_i * f (Q32: the exact product rounded once).
  void scale(std::span<Scalar> out, std::span<const Scalar> x, double f) const;
  // In place: for c < cols, V[c]_i <- sum_j y[j * cols + c] * V[j]_i over j < rows (the Ritz
  // vectors of a basis); y is rows x cols, row-major, |y| < 8.
  void rotate(std::span<Scalar* const> v, std::size_t rows, std::size_t cols, std::span<const double> y) const;
  // Entries of a random vector: the value of bits(seed, i, dim) >> 31 minus 2^32, times 2^-32,
  // i.e. uniform multiples of 2^-32 in [-1, 1) (R1-SPEC-030); the same values in both domains.
  void random(std::span<Scalar> out, std::uint64_t seed, std::uint64_t dim) const;

 private:
  std::size_t n_;
  int e_;
  bool parallel_;
};

// The two domains' kernels (vector_kernels.cpp).
template <>
double VectorOps<fx::Q32>::dot(std::span<const fx::Q32> x, std::span<const fx::Q32> y) const;
template <>
void VectorOps<fx::Q32>::dots(std::span<const fx::Q32* const> qs, std::span<const fx::Q32> w, std::span<double> out) const;
template <>
void VectorOps<fx::Q32>::combine(std::span<fx::Q32> out, const fx::Q32* base, std::span<const double> c,
                             std::span<const fx::Q32* const> xs) const;
template <>
void VectorOps<fx::Q32>::scale(std::span<fx::Q32> out, std::span<const fx::Q32> x, double f) const;
template <>
void VectorOps<fx::Q32>::rotate(std::span<fx::Q32* const> v, std::size_t rows, std::size_t cols, std::span<const double> y) const;
template <>
void VectorOps<fx::Q32>::random(std::span<fx::Q32> out, std::uint64_t seed, std::uint64_t dim) const;
template <>
double VectorOps<double>::dot(std::span<const double> x, std::span<const double> y) const;
template <>
void VectorOps<double>::dots(std::span<const double* const> qs, std::span<const double> w, std::span<double> out) const;
template <>
void VectorOps<double>::combine(std::span<double> out, const double* base, std::span<const double> c,
                             std::span<const double* const> xs) const;
template <>
void VectorOps<double>::scale(std::span<double> out, std::span<const double> x, double f) const;
template <>
void VectorOps<double>::rotate(std::span<double* const> v, std::size_t rows, std::size_t cols, std::span<const double> y) const;
template <>
void VectorOps<double>::random(std::span<double> out, std::uint64_t seed, std::uint64_t dim) const;

// The block length the kernels split index ranges at, and the length below which they stay
// serial; neither changes a result.
inline constexpr std::size_t kBlock = 4096;
inline constexpr std::size_t kParallelMin = std::size_t{1} << 15;

}  // namespace r1::spectral
