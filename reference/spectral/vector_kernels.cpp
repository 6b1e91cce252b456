// Vector kernels of the spectral solver, Q32 (exact sums, one rounding) and fp64 (fixed orders)
// (R1-SPEC-011..015, R1-SPEC-030).
#include "vector_kernels.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "exact_round.hpp"
#include "r1/fixedpoint/counter_rng.hpp"
#include "r1/fixedpoint/pairwise.hpp"

namespace r1::spectral {

std::int64_t FastExact::round_shift(int s) const {
  if (!spilled_) {
    const i128 r = fx::detail::rne_shift(acc_, s);
    if (!fx::detail::fits_i64(r)) fx::detail::throw_overflow("spectral round");
    return static_cast<std::int64_t>(r);
  }
  const auto r = spectral::round_shift(total(), s);
  if (!r) fx::detail::throw_overflow("spectral round");
  return *r;
}

namespace {

// Runs body(lo, hi) over [0, n) in kBlock pieces: serially, or as TBB tasks when asked and the
// range is long enough. Callers only write disjoint ranges, so the split never shows.
template <class Body>
void for_blocks(std::size_t n, bool parallel, const Body& body) {
  if (!parallel || n < kParallelMin) {
    for (std::size_t lo = 0; lo < n; lo += kBlock) body(lo, std::min(n, lo + kBlock));
    return;
  }
  const std::size_t blocks = (n + kBlock - 1) / kBlock;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t b = r.begin(); b != r.end(); ++b) body(b * kBlock, std::min(n, (b + 1) * kBlock));
  });
}

constexpr int kCoefBits = 60;  // coefficients of combinations are multiples of 2^-60 (R1-SPEC-013)

i128 product(std::int64_t a, std::int64_t b) { return static_cast<i128>(a) * b; }

// The fast paths below add products in a plain i128 without overflow checks. They are taken only
// when every factor's magnitude is below 2^kSafeBits, so that the sum provably fits:
// dots: a block of kBlock = 2^12 products of two such raws is below 2^(12 + 2 * 57) = 2^126;
// combine and rotate: at most kMaxFastTerms products of a coefficient (< 2^63) and a raw (< 2^57), plus the
// base term (< 2^(57 + 60)), stay below 2^126. Otherwise the checked FastExact path runs. Both
// paths compute the same exact sum, so the choice never changes a result (R1-SPEC-011).
constexpr int kSafeBits = 57;
constexpr std::size_t kMaxFastTerms = 48;
static_assert(kBlock <= (std::size_t{1} << 12), "dots fast path bound assumes blocks of at most 2^12");

}  // namespace

// ---- Q32 ----------------------------------------------------------------------------------------

template <>
double VectorOps<fx::Q32>::dot(std::span<const fx::Q32> x, std::span<const fx::Q32> y) const {
  if (x.size() != n_ || y.size() != n_) throw std::invalid_argument("spectral dot: length");
  auto block_sum = [&](std::size_t lo, std::size_t hi, FastExact& acc) {
    for (std::size_t i = lo; i < hi; ++i) acc.add(product(x[i].raw, y[i].raw));
  };
  FastExact total;
  if (!parallel_ || n_ < kParallelMin) {
    block_sum(0, n_, total);
  } else {
    tbb::enumerable_thread_specific<FastExact> parts;
    for_blocks(n_, true, [&](std::size_t lo, std::size_t hi) { block_sum(lo, hi, parts.local()); });
    for (const FastExact& p : parts) total.merge(p);  // exact: the merge order plays no part
  }
  // Products count units of 2^-64; the scaled inner product divides by 2^e.
  return to_double_scaled(total.total(), 64 + e_);
}

template <>
void VectorOps<fx::Q32>::dots(std::span<const fx::Q32* const> qs, std::span<const fx::Q32> w,
                               std::span<double> out) const {
  const std::size_t k = qs.size();
  auto block_sum = [&](std::size_t lo, std::size_t hi, std::vector<FastExact>& acc) {
    std::uint64_t wbits = 0;
    for (std::size_t i = lo; i < hi; ++i) wbits |= magnitude_bits(w[i].raw);
    for (std::size_t q = 0; q < k; ++q) {
      const fx::Q32* v = qs[q];
      FastExact& a = acc[q];
      u128 sum = 0;  // unsigned: a speculative sum may wrap (defined); it is used only when it cannot
      std::uint64_t vbits = 0;
      for (std::size_t i = lo; i < hi; ++i) {
        sum += static_cast<u128>(product(v[i].raw, w[i].raw));
        vbits |= magnitude_bits(v[i].raw);
      }
      if (((wbits | vbits) >> kSafeBits) == 0) {
        a.add(static_cast<i128>(sum));  // every factor below 2^57: the sum was exact (see kSafeBits)
      } else {
        for (std::size_t i = lo; i < hi; ++i) a.add(product(v[i].raw, w[i].raw));
      }
    }
  };
  std::vector<FastExact> total(k);
  if (!parallel_ || n_ < kParallelMin) {
    for_blocks(n_, false, [&](std::size_t lo, std::size_t hi) { block_sum(lo, hi, total); });
  } else {
    tbb::enumerable_thread_specific<std::vector<FastExact>> parts([k] { return std::vector<FastExact>(k); });
    for_blocks(n_, true, [&](std::size_t lo, std::size_t hi) { block_sum(lo, hi, parts.local()); });
    for (const auto& p : parts)
      for (std::size_t q = 0; q < k; ++q) total[q].merge(p[q]);
  }
  for (std::size_t q = 0; q < k; ++q) out[q] = to_double_scaled(total[q].total(), 64 + e_);
}

template <>
void VectorOps<fx::Q32>::combine(std::span<fx::Q32> out, const fx::Q32* base, std::span<const double> c,
                                  std::span<const fx::Q32* const> xs) const {
  const std::size_t k = c.size();
  std::vector<std::int64_t> coef(k);
  for (std::size_t q = 0; q < k; ++q) coef[q] = coef60(c[q]);
  const i128 one = i128{1} << kCoefBits;
  for_blocks(n_, parallel_, [&](std::size_t lo, std::size_t hi) {
    // The block's sums are formed vector by vector (each x read sequentially), then rounded.
    std::vector<u128> sum(hi - lo, 0);  // unsigned: may wrap (defined); used only when it cannot
    std::vector<std::uint64_t> bits(hi - lo, 0);
    if (base != nullptr)
      for (std::size_t i = lo; i < hi; ++i) {
        sum[i - lo] = static_cast<u128>(static_cast<i128>(base[i].raw) * one);
        bits[i - lo] = magnitude_bits(base[i].raw);
      }
    if (k <= kMaxFastTerms)
      for (std::size_t q = 0; q < k; ++q) {
        const fx::Q32* x = xs[q];
        const std::int64_t cq = coef[q];
        for (std::size_t i = lo; i < hi; ++i) {
          sum[i - lo] += static_cast<u128>(product(cq, x[i].raw));
          bits[i - lo] |= magnitude_bits(x[i].raw);
        }
      }
    for (std::size_t i = lo; i < hi; ++i) {
      if (k <= kMaxFastTerms && (bits[i - lo] >> kSafeBits) == 0) {  // the plain sum was exact (kSafeBits)
        const i128 r = fx::detail::rne_shift(static_cast<i128>(sum[i - lo]), kCoefBits);
        if (!fx::detail::fits_i64(r)) fx::detail::throw_overflow("spectral round");
        out[i] = fx::Q32::from_raw(static_cast<std::int64_t>(r));
        continue;
      }
      FastExact acc;
      if (base != nullptr) acc.add(static_cast<i128>(base[i].raw) * one);
      for (std::size_t q = 0; q < k; ++q) acc.add(product(coef[q], xs[q][i].raw));
      out[i] = fx::Q32::from_raw(acc.round_shift(kCoefBits));
    }
  });
}

template <>
void VectorOps<fx::Q32>::scale(std::span<fx::Q32> out, std::span<const fx::Q32> x, double f) const {
  for_blocks(n_, parallel_, [&](std::size_t lo, std::size_t hi) {
    for (std::size_t i = lo; i < hi; ++i) out[i] = mul_exact(x[i], f);
  });
}

template <>
void VectorOps<fx::Q32>::rotate(std::span<fx::Q32* const> v, std::size_t rows, std::size_t cols,
                                 std::span<const double> y) const {
  std::vector<std::int64_t> coef(rows * cols);
  for (std::size_t t = 0; t < rows * cols; ++t) coef[t] = coef60(y[t]);
  for_blocks(n_, parallel_, [&](std::size_t lo, std::size_t hi) {
    const std::size_t len = hi - lo;
    std::vector<std::int64_t> tmp(cols * len);
    // Whether every input entry of the block is below 2^57 (the fast path's condition).
    std::uint64_t bits = 0;
    for (std::size_t j = 0; j < rows; ++j)
      for (std::size_t i = lo; i < hi; ++i) bits |= magnitude_bits(v[j][i].raw);
    const bool fast = rows <= kMaxFastTerms && (bits >> kSafeBits) == 0;
    std::vector<i128> sum(fast ? len : 0);
    for (std::size_t c = 0; c < cols; ++c) {
      if (fast) {  // the plain sums are exact (see kSafeBits); each row vector read sequentially
        std::fill(sum.begin(), sum.end(), i128{0});
        for (std::size_t j = 0; j < rows; ++j) {
          const std::int64_t cj = coef[j * cols + c];
          const fx::Q32* x = v[j];
          for (std::size_t i = lo; i < hi; ++i) sum[i - lo] += product(cj, x[i].raw);
        }
        for (std::size_t i = 0; i < len; ++i) {
          const i128 r = fx::detail::rne_shift(sum[i], kCoefBits);
          if (!fx::detail::fits_i64(r)) fx::detail::throw_overflow("spectral round");
          tmp[c * len + i] = static_cast<std::int64_t>(r);
        }
        continue;
      }
      for (std::size_t i = lo; i < hi; ++i) {
        FastExact acc;
        for (std::size_t j = 0; j < rows; ++j) acc.add(product(coef[j * cols + c], v[j][i].raw));
        tmp[c * len + (i - lo)] = acc.round_shift(kCoefBits);
      }
    }
    for (std::size_t c = 0; c < cols; ++c)
      for (std::size_t i = lo; i < hi; ++i) v[c][i] = fx::Q32::from_raw(tmp[c * (hi - lo) + (i - lo)]);
  });
}

template <>
void VectorOps<fx::Q32>::random(std::span<fx::Q32> out, std::uint64_t seed, std::uint64_t dim) const {
  for_blocks(n_, parallel_, [&](std::size_t lo, std::size_t hi) {
    for (std::size_t i = lo; i < hi; ++i)
      out[i] = fx::Q32::from_raw(static_cast<std::int64_t>(rng::bits(seed, i, dim) >> 31) - fx::Q32::kOneRaw);
  });
}

// ---- fp64 ---------------------------------------------------------------------------------------

template <>
double VectorOps<double>::dot(std::span<const double> x, std::span<const double> y) const {
  const double d = parallel_ ? fx::parallel_pairwise_dot(x, y) : fx::pairwise_dot(x, y);
  return std::ldexp(d, -e_);  // a power-of-two scaling: exact
}

template <>
void VectorOps<double>::dots(std::span<const double* const> qs, std::span<const double> w, std::span<double> out) const {
  for (std::size_t q = 0; q < qs.size(); ++q) out[q] = dot(std::span<const double>(qs[q], n_), w);
}

template <>
void VectorOps<double>::combine(std::span<double> out, const double* base, std::span<const double> c,
                                 std::span<const double* const> xs) const {
  const std::size_t k = c.size();
  for_blocks(n_, parallel_, [&](std::size_t lo, std::size_t hi) {
    for (std::size_t i = lo; i < hi; ++i) {
      double s = base != nullptr ? base[i] : 0.0;
      for (std::size_t q = 0; q < k; ++q) s = s + c[q] * xs[q][i];  // left to right, no FMA
      out[i] = s;
    }
  });
}

template <>
void VectorOps<double>::scale(std::span<double> out, std::span<const double> x, double f) const {
  for_blocks(n_, parallel_, [&](std::size_t lo, std::size_t hi) {
    for (std::size_t i = lo; i < hi; ++i) out[i] = x[i] * f;
  });
}

template <>
void VectorOps<double>::rotate(std::span<double* const> v, std::size_t rows, std::size_t cols,
                                std::span<const double> y) const {
  for_blocks(n_, parallel_, [&](std::size_t lo, std::size_t hi) {
    std::vector<double> tmp(cols * (hi - lo));
    for (std::size_t c = 0; c < cols; ++c)
      for (std::size_t i = lo; i < hi; ++i) {
        double s = 0.0;
        for (std::size_t j = 0; j < rows; ++j) s = s + y[j * cols + c] * v[j][i];
        tmp[c * (hi - lo) + (i - lo)] = s;
      }
    for (std::size_t c = 0; c < cols; ++c)
      for (std::size_t i = lo; i < hi; ++i) v[c][i] = tmp[c * (hi - lo) + (i - lo)];
  });
}

template <>
void VectorOps<double>::random(std::span<double> out, std::uint64_t seed, std::uint64_t dim) const {
  for_blocks(n_, parallel_, [&](std::size_t lo, std::size_t hi) {
    for (std::size_t i = lo; i < hi; ++i)
      out[i] = static_cast<double>(static_cast<std::int64_t>(rng::bits(seed, i, dim) >> 31) - fx::Q32::kOneRaw) * 0x1p-32;
  });
}

}  // namespace r1::spectral
