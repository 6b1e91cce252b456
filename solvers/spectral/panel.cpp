// Block kernels of the spectral solver on row-major panels, Q32 (exact sums, one rounding) and
// fp64 (fixed orders) (R1-SPEC-011..015, R1-SPEC-030).
#include "r1/solvers/panel.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <stdexcept>

#include "r1/solvers/exact_round.hpp"
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

void for_row_blocks(std::size_t n, bool parallel, const std::function<void(std::size_t, std::size_t)>& body) {
  if (!parallel || n < kParallelMin) {
    for (std::size_t lo = 0; lo < n; lo += kBlock) body(lo, std::min(n, lo + kBlock));
    return;
  }
  const std::size_t blocks = (n + kBlock - 1) / kBlock;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t b = r.begin(); b != r.end(); ++b) body(b * kBlock, std::min(n, (b + 1) * kBlock));
  });
}

template <class Scalar>
std::vector<Scalar> Panel<Scalar>::copy_column(std::size_t c) const {
  std::vector<Scalar> v(n_);
  for (std::size_t i = 0; i < n_; ++i) v[i] = at(i, c);
  return v;
}

template <class Scalar>
void Panel<Scalar>::set_column(std::size_t c, std::span<const Scalar> v) {
  if (v.size() != n_) throw std::invalid_argument("panel: column length");
  for (std::size_t i = 0; i < n_; ++i) at(i, c) = v[i];
}

template class Panel<fx::Q32>;
template class Panel<double>;

namespace {
void check_cols(Cols cols, std::size_t limit) {
  for (const std::uint32_t c : cols)
    if (c >= limit) throw std::invalid_argument("panel: column out of range");
}
}  // namespace

void check_dots(std::size_t rows, std::size_t n, std::size_t cols, Cols qs, Cols ws, std::size_t outs) {
  if (outs != qs.size() * ws.size() || rows != n) throw std::invalid_argument("spectral dots: sizes");
  check_cols(qs, cols);
  check_cols(ws, cols);
}

void check_combine(std::size_t rows, std::size_t n, std::size_t cols, Cols outs, Cols bases, Cols terms,
                   std::size_t coefs) {
  if (coefs != terms.size() * outs.size() || (!bases.empty() && bases.size() != outs.size()) || rows != n)
    throw std::invalid_argument("spectral combine: sizes");
  check_cols(outs, cols);
  check_cols(bases, cols);
  check_cols(terms, cols);
}

void exact_dots(std::size_t n, bool parallel, int shift, std::span<double> out, const BlockDots& block_sum) {
  const std::size_t pairs = out.size();
  std::vector<FastExact> total(pairs);
  if (!parallel || n < kParallelMin) {
    for_row_blocks(n, false, [&](std::size_t lo, std::size_t hi) { block_sum(lo, hi, total); });
  } else {
    tbb::enumerable_thread_specific<std::vector<FastExact>> parts([pairs] { return std::vector<FastExact>(pairs); });
    for_row_blocks(n, true, [&](std::size_t lo, std::size_t hi) { block_sum(lo, hi, parts.local()); });
    for (const auto& part : parts)  // exact: the merge order plays no part
      for (std::size_t k = 0; k < pairs; ++k) total[k].merge(part[k]);
  }
  for (std::size_t k = 0; k < pairs; ++k) out[k] = to_double_scaled(total[k].total(), shift);
}

template <class Scalar>
double PanelOps<Scalar>::dot(const Panel<Scalar>& p, std::uint32_t a, std::uint32_t b) const {
  double d = 0;
  const std::uint32_t qa[1] = {a}, qb[1] = {b};
  dots(p, qa, qb, std::span<double>(&d, 1));
  return d;
}

template <class Scalar>
void PanelOps<Scalar>::copy(Panel<Scalar>& p, std::uint32_t dst, std::uint32_t src) const {
  if (dst == src) return;
  for_row_blocks(n_, parallel_, [&](std::size_t lo, std::size_t hi) {
    for (std::size_t i = lo; i < hi; ++i) p.at(i, dst) = p.at(i, src);
  });
}

template <class Scalar>
void PanelOps<Scalar>::move(Panel<Scalar>& p, Cols dst, Cols src) const {
  if (dst.size() != src.size()) throw std::invalid_argument("panel move: sizes");
  check_cols(dst, p.cols());
  check_cols(src, p.cols());
  for_row_blocks(n_, parallel_, [&](std::size_t lo, std::size_t hi) {
    std::vector<Scalar> tmp(src.size());
    for (std::size_t i = lo; i < hi; ++i) {
      Scalar* row = p.row(i);
      for (std::size_t k = 0; k < src.size(); ++k) tmp[k] = row[src[k]];
      for (std::size_t k = 0; k < dst.size(); ++k) row[dst[k]] = tmp[k];
    }
  });
}

namespace {

constexpr int kCoefBits = 60;  // coefficients of combinations are multiples of 2^-60 (R1-SPEC-013)

i128 product(std::int64_t a, std::int64_t b) { return static_cast<i128>(a) * b; }

// The dot products' fast path adds the products of a row block in a plain (unsigned, wrapping)
// i128 without overflow checks, and uses the sum only when every factor of the pair's two
// columns in the block is below 2^kSafeBits: then kBlock = 2^12 products stay below
// 2^(12 + 2 * 57) = 2^126 and the sum was exact. Otherwise the checked FastExact path recomputes
// the pair over the block. Both compute the same exact sum, so the choice never changes a result.
constexpr int kSafeBits = 57;
static_assert(kBlock <= (std::size_t{1} << 12), "dots fast path bound assumes blocks of at most 2^12 rows");


}  // namespace

// ---- Q32 ----------------------------------------------------------------------------------------

namespace {

// Rows per tile of the dot kernel: 64 rows of the widest panels (~1.5 KB each) stay in L2 while
// every column of the list passes over them.
constexpr std::size_t kTile = 64;

// The dot products of one tile of rows: for every q, sum[q * nw + c] += sum over the tile's rows
// of x_q * w_c (speculative: unsigned and wrapping). The tile's list columns are in xt (column q
// at xt + q * kTile), its w values in wt (rows x stride, zero-padded to a multiple of W). W
// independent accumulators keep the add/carry chains apart.
template <std::size_t W>
void tile_dots(const std::int64_t* xt, std::size_t nq, std::size_t rows, const std::int64_t* wt, std::size_t stride,
               std::size_t nw, u128* sum) {
  for (std::size_t q = 0; q < nq; ++q) {
    const std::int64_t* x = xt + q * kTile;
    for (std::size_t c0 = 0; c0 < nw; c0 += W) {
      // Named accumulators (not an array) so that they live in registers.
      u128 a0 = 0, a1 = 0, a2 = 0, a3 = 0;
      const std::int64_t* wr = wt + c0;
      for (std::size_t i = 0; i < rows; ++i, wr += stride) {
        const std::int64_t xi = x[i];
        a0 += static_cast<u128>(product(xi, wr[0]));
        if constexpr (W >= 2) a1 += static_cast<u128>(product(xi, wr[1]));
        if constexpr (W >= 4) {
          a2 += static_cast<u128>(product(xi, wr[2]));
          a3 += static_cast<u128>(product(xi, wr[3]));
        }
      }
      const u128 a[4] = {a0, a1, a2, a3};
      for (std::size_t j = 0; j < W && c0 + j < nw; ++j) sum[q * nw + c0 + j] += a[j];
    }
  }
}

}  // namespace

template <>
void PanelOps<fx::Q32>::dots(const Panel<fx::Q32>& p, Cols qs, Cols ws, std::span<double> out) const {
  const std::size_t nq = qs.size(), nw = ws.size(), pairs = nq * nw;
  check_dots(p.rows(), n_, p.cols(), qs, ws, out.size());
  // Accumulator width: 4 chains for blocks of columns, fewer for one or two.
  const std::size_t width = nw >= 3 ? 4 : nw, stride = (nw + width - 1) / width * width;
  auto block_sum = [&](std::size_t lo, std::size_t hi, std::vector<FastExact>& acc) {
    std::vector<u128> sum(pairs, 0);  // unsigned: a speculative sum may wrap (defined); used only when it cannot
    std::vector<std::uint64_t> qbits(nq, 0), wbits(nw, 0);
    std::vector<std::int64_t> wt(kTile * stride, 0), xt(kTile * nq);
    for (std::size_t t0 = lo; t0 < hi; t0 += kTile) {
      const std::size_t rows = std::min(kTile, hi - t0);
      // The tile transposed: each row read once, contiguously.
      for (std::size_t i = 0; i < rows; ++i) {
        const fx::Q32* row = p.row(t0 + i);
        for (std::size_t c = 0; c < nw; ++c) {
          const std::int64_t v = row[ws[c]].raw;
          wt[i * stride + c] = v;
          wbits[c] |= magnitude_bits(v);
        }
        for (std::size_t q = 0; q < nq; ++q) {
          const std::int64_t v = row[qs[q]].raw;
          xt[q * kTile + i] = v;
          qbits[q] |= magnitude_bits(v);
        }
      }
      switch (width) {
        case 1: tile_dots<1>(xt.data(), nq, rows, wt.data(), stride, nw, sum.data()); break;
        case 2: tile_dots<2>(xt.data(), nq, rows, wt.data(), stride, nw, sum.data()); break;
        default: tile_dots<4>(xt.data(), nq, rows, wt.data(), stride, nw, sum.data()); break;
      }
    }
    for (std::size_t q = 0; q < nq; ++q)
      for (std::size_t c = 0; c < nw; ++c) {
        if (((qbits[q] | wbits[c]) >> kSafeBits) == 0) {
          acc[q * nw + c].add(static_cast<i128>(sum[q * nw + c]));  // exact (see kSafeBits)
        } else {
          for (std::size_t i = lo; i < hi; ++i) acc[q * nw + c].add(product(p.at(i, qs[q]).raw, p.at(i, ws[c]).raw));
        }
      }
  };
  // Products count units of 2^-(2 frac); the scaled inner product divides by 2^e.
  exact_dots(n_, parallel_, 2 * frac_ + e_, out, block_sum);
}

namespace {

// Outputs o0 .. o0 + W - 1 of one row of a combination, in W register accumulators: result[o] =
// RNE((base_o 2^60 + sum_t coef[t * ld + o] x[t]) / 2^60), the sums plain i128 (the caller has
// checked the bound that makes them exact).
template <std::size_t W>
void combine_row(const fx::Q32* row, Cols bases, std::size_t o0, const std::vector<std::int64_t>& x,
                 const std::int64_t* coef, std::size_t ld, i128 one, std::int64_t* result) {
  auto start = [&](std::size_t o) -> i128 { return bases.empty() ? 0 : static_cast<i128>(row[bases[o]].raw) * one; };
  // Named accumulators (not an array) so that they live in registers.
  i128 s0 = start(o0), s1 = 0, s2 = 0, s3 = 0;
  if constexpr (W >= 2) s1 = start(o0 + 1);
  if constexpr (W >= 4) {
    s2 = start(o0 + 2);
    s3 = start(o0 + 3);
  }
  const std::int64_t* ct = coef + o0;
  for (std::size_t t = 0; t < x.size(); ++t, ct += ld) {
    const std::int64_t xt = x[t];
    s0 += product(ct[0], xt);
    if constexpr (W >= 2) s1 += product(ct[1], xt);
    if constexpr (W >= 4) {
      s2 += product(ct[2], xt);
      s3 += product(ct[3], xt);
    }
  }
  const i128 s[4] = {s0, s1, s2, s3};
  for (std::size_t j = 0; j < W; ++j) {
    const i128 r = fx::detail::rne_shift(s[j], kCoefBits);
    if (!fx::detail::fits_i64(r)) fx::detail::throw_overflow("spectral round");
    result[o0 + j] = static_cast<std::int64_t>(r);
  }
}

}  // namespace

template <>
void PanelOps<fx::Q32>::combine(Panel<fx::Q32>& p, Cols outs, Cols bases, Cols terms, std::span<const double> c) const {
  const std::size_t no = outs.size(), nt = terms.size();
  check_combine(p.rows(), n_, p.cols(), outs, bases, terms, c.size());
  // Coefficients as multiples of 2^-60, row t holding the outputs' coefficients side by side:
  // up to four sums share each loaded term.
  std::vector<std::int64_t> coef(nt * no, 0);
  std::uint64_t cbits = 0;
  for (std::size_t t = 0; t < nt; ++t)
    for (std::size_t o = 0; o < no; ++o) {
      coef[t * no + o] = coef60(c[t * no + o]);
      cbits |= magnitude_bits(coef[t * no + o]);
    }
  // The fast path's bound: every term is below 2^(cw + xw) with cw, xw the bit widths of the
  // largest coefficient and the row's largest term entry, so nt terms stay below
  // 2^(cw + xw + bit_width(nt)); the base term is below 2^(63 + 60). When
  // cw + xw + bit_width(nt) <= 125 the whole sum is below 2^126 and the plain i128 sum is exact.
  const int cw = static_cast<int>(std::bit_width(cbits)), tw = static_cast<int>(std::bit_width(nt));
  const i128 one = i128{1} << kCoefBits;
  for_row_blocks(n_, parallel_, [&](std::size_t lo, std::size_t hi) {
    std::vector<std::int64_t> x(nt), result(no);
    for (std::size_t i = lo; i < hi; ++i) {
      fx::Q32* row = p.row(i);
      std::uint64_t xbits = 0;
      for (std::size_t t = 0; t < nt; ++t) {
        x[t] = row[terms[t]].raw;
        xbits |= magnitude_bits(x[t]);
      }
      if (cw + static_cast<int>(std::bit_width(xbits)) + tw <= 125) {
        std::size_t o0 = 0;
        for (; o0 + 4 <= no; o0 += 4) combine_row<4>(row, bases, o0, x, coef.data(), no, one, result.data());
        for (; o0 + 2 <= no; o0 += 2) combine_row<2>(row, bases, o0, x, coef.data(), no, one, result.data());
        for (; o0 < no; ++o0) combine_row<1>(row, bases, o0, x, coef.data(), no, one, result.data());
      } else {
        for (std::size_t o = 0; o < no; ++o) {
          FastExact acc;
          if (!bases.empty()) acc.add(static_cast<i128>(row[bases[o]].raw) * one);
          for (std::size_t t = 0; t < nt; ++t) acc.add(product(coef[t * no + o], x[t]));
          result[o] = acc.round_shift(kCoefBits);
        }
      }
      for (std::size_t o = 0; o < no; ++o) row[outs[o]] = fx::Q32::from_raw(result[o]);
    }
  });
}

template <>
void PanelOps<fx::Q32>::scale(Panel<fx::Q32>& p, std::uint32_t c, double f) const {
  for_row_blocks(n_, parallel_, [&](std::size_t lo, std::size_t hi) {
    for (std::size_t i = lo; i < hi; ++i) p.at(i, c) = mul_exact(p.at(i, c), f);
  });
}

template <>
void PanelOps<fx::Q32>::random(Panel<fx::Q32>& p, std::uint32_t c, std::uint64_t seed, std::uint64_t dim) const {
  const std::int64_t unit = std::int64_t{1} << (frac_ - 32);  // 2^-32 in units of 2^-frac
  for_row_blocks(n_, parallel_, [&](std::size_t lo, std::size_t hi) {
    for (std::size_t i = lo; i < hi; ++i)
      p.at(i, c) = fx::Q32::from_raw((static_cast<std::int64_t>(rng::bits(seed, i, dim) >> 31) - fx::Q32::kOneRaw) * unit);
  });
}

// ---- fp64 ---------------------------------------------------------------------------------------

template <>
void PanelOps<double>::dots(const Panel<double>& p, Cols qs, Cols ws, std::span<double> out) const {
  const std::size_t nq = qs.size(), nw = ws.size(), pairs = nq * nw;
  if (out.size() != pairs || p.rows() != n_) throw std::invalid_argument("spectral dots: sizes");
  check_cols(qs, p.cols());
  check_cols(ws, p.cols());
  // Each pair's products go through the pairwise tree (R1-NUM-051) in index order, 64 leaves at a
  // time, so one sweep over the rows serves every pair. Tasks take disjoint pairs, each pair's
  // tree stays serial: the bits are those of pairwise_dot on the two columns.
  constexpr std::size_t L = fx::kPairwiseLeafBlock;
  auto run = [&](std::size_t k0, std::size_t k1) {
    std::vector<fx::PairwiseAccumulator> acc(k1 - k0);
    alignas(64) double buf[L];
    std::size_t i = 0;
    for (; i + L <= n_; i += L)
      for (std::size_t k = k0; k < k1; ++k) {
        const std::uint32_t a = qs[k / nw], b = ws[k % nw];
        for (std::size_t j = 0; j < L; ++j) buf[j] = p.at(i + j, a) * p.at(i + j, b);
        acc[k - k0].push(buf);
      }
    for (std::size_t k = k0; k < k1; ++k) {
      const std::uint32_t a = qs[k / nw], b = ws[k % nw];
      for (std::size_t j = 0; i + j < n_; ++j) buf[j] = p.at(i + j, a) * p.at(i + j, b);
      out[k] = std::ldexp(acc[k - k0].finish(buf, n_ - i), -e_);  // a power-of-two scaling: exact
    }
  };
  if (parallel_ && n_ >= kParallelMin && pairs > 1) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pairs, 1),
                      [&](const tbb::blocked_range<std::size_t>& r) { run(r.begin(), r.end()); });
  } else {
    run(0, pairs);
  }
}

template <>
void PanelOps<double>::combine(Panel<double>& p, Cols outs, Cols bases, Cols terms, std::span<const double> c) const {
  const std::size_t no = outs.size(), nt = terms.size();
  check_combine(p.rows(), n_, p.cols(), outs, bases, terms, c.size());
  for_row_blocks(n_, parallel_, [&](std::size_t lo, std::size_t hi) {
    std::vector<double> result(no);
    for (std::size_t i = lo; i < hi; ++i) {
      double* row = p.row(i);
      for (std::size_t o = 0; o < no; ++o) {
        double s = bases.empty() ? 0.0 : row[bases[o]];
        for (std::size_t t = 0; t < nt; ++t) s = s + c[t * no + o] * row[terms[t]];  // left to right, no FMA
        result[o] = s;
      }
      for (std::size_t o = 0; o < no; ++o) row[outs[o]] = result[o];
    }
  });
}

template <>
void PanelOps<double>::scale(Panel<double>& p, std::uint32_t c, double f) const {
  for_row_blocks(n_, parallel_, [&](std::size_t lo, std::size_t hi) {
    for (std::size_t i = lo; i < hi; ++i) p.at(i, c) = p.at(i, c) * f;
  });
}

template <>
void PanelOps<double>::random(Panel<double>& p, std::uint32_t c, std::uint64_t seed, std::uint64_t dim) const {
  for_row_blocks(n_, parallel_, [&](std::size_t lo, std::size_t hi) {
    for (std::size_t i = lo; i < hi; ++i)
      p.at(i, c) = static_cast<double>(static_cast<std::int64_t>(rng::bits(seed, i, dim) >> 31) - fx::Q32::kOneRaw) * 0x1p-32;
  });
}

template <>
void three_term(std::size_t len, const fx::Q32* s, const fx::Q32* y, fx::Q32* p, double alpha, double beta, double gamma,
                bool parallel) {
  const std::int64_t ca = coef60(alpha), cb = coef60(beta), cg = coef60(gamma);
  const int cw = static_cast<int>(std::bit_width(magnitude_bits(ca) | magnitude_bits(cb) | magnitude_bits(cg)));
  for_row_blocks(len, parallel, [&](std::size_t lo, std::size_t hi) {
    for (std::size_t k = lo; k < hi; ++k) {
      const std::int64_t xs = s[k].raw, xy = y[k].raw, xp = gamma == 0 ? 0 : p[k].raw;
      // Three terms below 2^(cw + xw) each stay below 2^126 when cw + xw <= 124: the plain sum is exact.
      const std::uint64_t xbits = magnitude_bits(xs) | magnitude_bits(xy) | magnitude_bits(xp);
      std::int64_t r;
      if (cw + static_cast<int>(std::bit_width(xbits)) <= 124) {
        const i128 t = product(ca, xs) + product(cb, xy) + product(cg, xp);
        const i128 q = fx::detail::rne_shift(t, kCoefBits);
        if (!fx::detail::fits_i64(q)) fx::detail::throw_overflow("spectral round");
        r = static_cast<std::int64_t>(q);
      } else {
        FastExact acc;
        acc.add(product(ca, xs));
        acc.add(product(cb, xy));
        acc.add(product(cg, xp));
        r = acc.round_shift(kCoefBits);
      }
      p[k] = fx::Q32::from_raw(r);
    }
  });
}

template <>
void three_term(std::size_t len, const double* s, const double* y, double* p, double alpha, double beta, double gamma,
                bool parallel) {
  for_row_blocks(len, parallel, [&](std::size_t lo, std::size_t hi) {
    for (std::size_t k = lo; k < hi; ++k) {
      double t = alpha * s[k];
      t = t + beta * y[k];
      if (gamma != 0) t = t + gamma * p[k];
      p[k] = t;
    }
  });
}

template <class Scalar>
void PanelOps<Scalar>::three_term(std::size_t len, const Scalar* s, const Scalar* y, Scalar* p, double alpha, double beta,
                                  double gamma) const {
  spectral::three_term(len, s, y, p, alpha, beta, gamma, parallel_);
}

template class PanelOps<fx::Q32>;
template class PanelOps<double>;

}  // namespace r1::spectral
