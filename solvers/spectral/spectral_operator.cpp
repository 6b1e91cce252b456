// The regularised normalised Laplacian the solver iterates on: rho rule, exact Q32 and fp64
// entries, the deflated vector, the operator application (R1-SPEC-001..006,
// R1-SPEC-010).
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <limits>

#include "r1/solvers/exact_round.hpp"
#include "r1/fixedpoint/pairwise.hpp"
#include "r1/fixedpoint/prefetch.hpp"
#include "r1/solvers/spectral.hpp"
#include "r1/solvers/panel.hpp"
#include "trivial_vector.hpp"

namespace r1 {

using spectral::FastExact;
using spectral::U256;

Result<fx::Q32> spectral_rho(const Graph& g, const SpectralParams& params) {
  fx::Q32 rho;
  if (params.rho) {
    const double r = *params.rho;
    if (!std::isfinite(r) || r < 0)
      return Status::input("spectral: rho must be a finite number >= 0 (got " + std::to_string(r) + ")");
    const auto q = fx::Q32::checked_from_double(r);
    if (!q) return Status::input("spectral: rho " + std::to_string(r) + " is outside the Q32 range");
    rho = *q;
  } else if (g.component_size.size() > 1) {
    // Mean weighted degree, the exact sum of Q32 degrees divided by n and rounded once (RNE).
    u128 sum = 0;
    for (const std::uint64_t d : g.degree) sum += d;
    rho = fx::Q32::from_raw(static_cast<std::int64_t>(fx::detail::rne_div(static_cast<i128>(sum), g.n)));
  }
  if (rho.raw == 0) {
    for (std::uint32_t i = 0; i < g.n; ++i)
      if (g.degree[i] == 0)
        return Status::input("spectral: particle " + std::to_string(i) +
                             " has no links, so D^(-1/2) is undefined with rho = 0; give --rho > 0 or leave rho automatic");
  }
  return rho;
}

namespace {

// D_i = degree_i + rho as an exact integer of Q32 units (< 2^62 + 2^63 by check_graph and the
// Q32 range of rho).
u128 regularised_degree(const Graph& g, std::uint32_t i, fx::Q32 rho) {
  return static_cast<u128>(g.degree[i]) + static_cast<u128>(rho.raw);
}

Status check_graph(const Graph& g) {
  if (g.n == 0) return Status::input("spectral: the graph has no particles");
  if (g.row_ptr.size() != g.n + std::size_t{1} || g.degree.size() != g.n || g.w.size() != g.col.size())
    return Status::internal("spectral: malformed layout graph");
  // D_i < 2^63 keeps D_i D_j below 2^126 in the exact entry rounding (R1-SPEC-003); a weighted
  // degree of 2^31 is far beyond any graph that fits in memory.
  for (const std::uint64_t d : g.degree)
    if (d >= (std::uint64_t{1} << 62)) return Status::input("spectral: a weighted degree reaches 2^30");
  return Status::ok();
}

}  // namespace

namespace spectral {

fx::Q32 m_entry(std::int64_t w, u128 di, u128 dj) {
  const u128 w2 = static_cast<u128>(w) * static_cast<u128>(w);
  const U256 num{w2 << 64, w2 >> 64};
  return fx::Q32::from_raw(static_cast<std::int64_t>(rne_sqrt_ratio(num, di * dj)));
}

int scale_exponent(std::uint32_t n) { return n <= 1 ? 0 : static_cast<int>(std::bit_width(n - 1)); }

std::vector<fx::Q32> scaled_trivial(const Graph& g, fx::Q32 rho, int e, int frac) {
  if (2 * frac + e > 120) throw std::invalid_argument("scaled_trivial: 2 frac + e above 120");
  u128 sum_d = 0;
  for (std::uint32_t i = 0; i < g.n; ++i) sum_d += regularised_degree(g, i, rho);
  std::vector<fx::Q32> t(g.n);
  for (std::uint32_t i = 0; i < g.n; ++i) {
    // D_i < 2^64, so the numerator is below 2^(64 + 120) and the root below 2^(frac + e / 2) < 2^63.
    const U256 num = spectral::shl(U256{regularised_degree(g, i, rho), 0}, 2 * frac + e);
    t[i] = fx::Q32::from_raw(static_cast<std::int64_t>(spectral::rne_sqrt_ratio(num, sum_d)));
  }
  return t;
}

}  // namespace spectral

Result<SpectralOperator<fx::Q32>> spectral_operator_q32(const Graph& g, const SpectralParams& params) {
  R1_TRY(check_graph(g));
  R1_ASSIGN(const fx::Q32 rho, spectral_rho(g, params));
  SpectralOperator<fx::Q32> op;
  op.graph = &g;
  op.n = g.n;
  op.e = spectral::scale_exponent(g.n);
  op.rho = rho;
  const std::size_t n = g.n;
  std::vector<u128> d(n);
  for (std::uint32_t i = 0; i < g.n; ++i) d[i] = regularised_degree(g, i, rho);
  // M_ij = RNE(2^32 w / sqrt(D_i D_j)) = RNE(sqrt(2^64 w^2 / (D_i D_j))) (R1-SPEC-003): w <= 2^32,
  // so 2^64 w^2 <= 2^128; D_i D_j < 2^128 because each D < 2^64 for any graph r1 can hold.
  op.m.resize(g.col.size());
  for (std::uint32_t i = 0; i < g.n; ++i)
    for (std::uint64_t k = g.row_ptr[i]; k < g.row_ptr[i + 1]; ++k) op.m[k] = spectral::m_entry(g.w[k], d[i], d[g.col[k]]);
  if (rho.raw > 0) {
    // g_i = RNE(2^32 sqrt(rho / (n D_i))) = RNE(sqrt(2^64 rho_raw / (n D_i))) (R1-SPEC-004).
    op.g.resize(n);
    for (std::uint32_t i = 0; i < g.n; ++i) {
      const U256 num{static_cast<u128>(rho.raw) << 64, 0};
      op.g[i] = fx::Q32::from_raw(static_cast<std::int64_t>(spectral::rne_sqrt_ratio(num, static_cast<u128>(g.n) * d[i])));
    }
  }
  // trivial_i = RNE(2^32 sqrt(2^e D_i / sum D)) (R1-SPEC-006): squared length 2^e up to rounding.
  op.trivial = spectral::scaled_trivial(g, rho, op.e, 32);
  return op;
}

Result<SpectralOperator<double>> spectral_operator_f64(const Graph& g, const SpectralParams& params) {
  R1_TRY(check_graph(g));
  R1_ASSIGN(const fx::Q32 rho, spectral_rho(g, params));
  SpectralOperator<double> op;
  op.graph = &g;
  op.n = g.n;
  op.e = spectral::scale_exponent(g.n);
  op.rho = rho;
  const std::size_t n = g.n;
  // D_i as the correctly rounded double of the exact integer times 2^-32; sum D likewise.
  auto exact_to_double = [](u128 v) {
    fx::ExactSum s;
    s.add_term(static_cast<i128>(v >> 1));  // two halves keep each term below 2^127
    s.add_term(static_cast<i128>(v - (v >> 1)));
    return spectral::to_double_scaled(s, 32);
  };
  std::vector<double> d(n);
  u128 sum_d = 0;
  for (std::uint32_t i = 0; i < g.n; ++i) {
    const u128 di = regularised_degree(g, i, rho);
    d[i] = exact_to_double(di);
    sum_d += di;
  }
  const double sum_dd = exact_to_double(sum_d);
  op.m.resize(g.col.size());
  for (std::uint32_t i = 0; i < g.n; ++i)
    for (std::uint64_t k = g.row_ptr[i]; k < g.row_ptr[i + 1]; ++k)
      op.m[k] = (static_cast<double>(g.w[k]) * 0x1p-32) / std::sqrt(d[i] * d[g.col[k]]);
  if (rho.raw > 0) {
    op.g.resize(n);
    const double r = rho.to_double(), nd = static_cast<double>(g.n);
    for (std::uint32_t i = 0; i < g.n; ++i) op.g[i] = std::sqrt(r / (nd * d[i]));
  }
  op.trivial.resize(n);
  const double scale = std::ldexp(1.0, op.e);
  for (std::uint32_t i = 0; i < g.n; ++i) op.trivial[i] = std::sqrt(scale * d[i] / sum_dd);
  return op;
}

// ---- application (R1-SPEC-005) --------------------------------------------------------------------

// How far ahead, in stored entries, a block application prefetches the row of the block it will
// gather (both ends of the row, which may straddle two cache lines). At 10^6 particles the
// block (n x 7 entries, 56 MB) is larger than the caches and the gathers are the operator's
// cost; a prefetch changes no bit. The hint fetches into the second-level cache
// (fx::gather_hint), where 64-96 entries ahead did best for accel/cpu's rows.
constexpr std::uint64_t kGatherAhead = 96;

namespace {

// c_col = RNE(sum_j g_j x_j): the rank-one coefficient of each column, rounded once to Q32 (all
// zero when rho = 0).
std::vector<std::int64_t> rank_one_coefficients(const SpectralOperator<fx::Q32>& op, const fx::Q32* x, std::size_t ldx,
                                                std::size_t count, bool par) {
  const std::size_t n = op.n;
  const std::vector<fx::Q32>& g = op.g;
  std::vector<std::int64_t> c(count, 0);
  if (!g.empty()) {
    tbb::enumerable_thread_specific<std::vector<FastExact>> parts([count] { return std::vector<FastExact>(count); });
    spectral::for_row_blocks(n, par, [&](std::size_t lo, std::size_t hi) {
      std::vector<FastExact>& acc = parts.local();
      for (std::size_t j = lo; j < hi; ++j)
        for (std::size_t col = 0; col < count; ++col) acc[col].add(static_cast<i128>(g[j].raw) * x[j * ldx + col].raw);
    });
    for (std::size_t col = 0; col < count; ++col) {
      FastExact total;
      for (const auto& p : parts) total.merge(p[col]);  // exact: the merge order plays no part
      c[col] = total.round_shift(32);
    }
  }
  return c;
}

}  // namespace

template <>
bool SpectralOperator<fx::Q32>::apply_three_term(const fx::Q32* x, std::size_t ld, fx::Q32* p, std::size_t count,
                                                 double alpha, double beta, double gamma, bool parallel) const {
  if (rows == nullptr || ld < count) return false;
  const std::vector<std::int64_t> c = rank_one_coefficients(*this, x, ld, count, parallel && n >= spectral::kParallelMin);
  return rows->apply_three_term(x, ld, g.empty() ? std::span<const std::int64_t>() : std::span<const std::int64_t>(c), p,
                                count, alpha, beta, gamma);
}

template <>
bool SpectralOperator<double>::apply_three_term(const double*, std::size_t, double*, std::size_t, double, double, double,
                                                bool) const {
  return false;
}

template <>
void SpectralOperator<fx::Q32>::apply_block(const fx::Q32* x, std::size_t ldx, fx::Q32* y, std::size_t ldy,
                                            std::size_t count, bool parallel) const {
  const Graph& gr = *graph;
  const bool par = parallel && n >= spectral::kParallelMin;
  const std::vector<std::int64_t> c = rank_one_coefficients(*this, x, ldx, count, par);
  if (rows != nullptr) {
    // A backend's rows (R1-SPEC-073): the same exact sums, rounded once. Every application goes
    // to them: they may hold the operator's entries while m is released (R1-SPEC-076).
    const auto coef = g.empty() ? std::span<const std::int64_t>() : std::span<const std::int64_t>(c);
    if (ldx == count && ldy == count) {
      rows->apply(x, coef, y, count);
    } else if (ldx != ldy || ldx < count || !rows->apply_strided(x, ldx, coef, y, count)) {
      std::vector<fx::Q32> xc(n * count), yc(n * count);
      for (std::size_t i = 0; i < n; ++i)
        for (std::size_t col = 0; col < count; ++col) xc[i * count + col] = x[i * ldx + col];
      rows->apply(xc.data(), coef, yc.data(), count);
      for (std::size_t i = 0; i < n; ++i)
        for (std::size_t col = 0; col < count; ++col) y[i * ldy + col] = yc[i * count + col];
    }
    return;
  }
  const i128 one = i128{1} << 32;
  const std::uint64_t nnz = gr.row_ptr[n];
  spectral::for_row_blocks(n, par, [&](std::size_t lo, std::size_t hi) {
    // Unsigned: a speculative sum may wrap (defined behaviour); it is used only when it cannot.
    std::vector<u128> sum(count);
    std::vector<std::uint64_t> xbits(count);
    for (std::size_t i = lo; i < hi; ++i) {
      // Fast path: plain i128 row sums, taken only when they provably cannot overflow. Every term
      // (x_i 2^32, m_ik x_k, g_i c) is below 2^(mw + xw), mw and xw the bit widths of the row's
      // largest m or g raw (at least 33, for the 2^32 factor) and largest x raw or c, so the
      // len + 2 terms stay below 2^(mw + xw + bit_width(len + 2)); at most 126 bits means the
      // sum fits. The sum is exact either way, so the path taken never changes a bit
      // (R1-SPEC-005). Basis vectors carry raws up to ~2^52 (R1-SPEC-011): rows stay fast.
      std::uint64_t mbits = 0;
      for (std::size_t col = 0; col < count; ++col) {
        const std::int64_t xi = x[i * ldx + col].raw;
        sum[col] = static_cast<u128>(static_cast<i128>(xi) * one);
        xbits[col] = spectral::magnitude_bits(xi);
      }
      for (std::uint64_t k = gr.row_ptr[i]; k < gr.row_ptr[i + 1]; ++k) {
        if (k + kGatherAhead < nnz) {
          const fx::Q32* ahead = x + static_cast<std::size_t>(gr.col[k + kGatherAhead]) * ldx;
          fx::gather_hint(ahead);
          fx::gather_hint(ahead + count - 1);
        }
        const std::int64_t mk = m[k].raw;
        const fx::Q32* xr = x + static_cast<std::size_t>(gr.col[k]) * ldx;
        mbits |= spectral::magnitude_bits(mk);
        for (std::size_t col = 0; col < count; ++col) {
          sum[col] -= static_cast<u128>(static_cast<i128>(mk) * xr[col].raw);
          xbits[col] |= spectral::magnitude_bits(xr[col].raw);
        }
      }
      if (!g.empty()) {
        mbits |= spectral::magnitude_bits(g[i].raw);
        for (std::size_t col = 0; col < count; ++col) {
          sum[col] -= static_cast<u128>(static_cast<i128>(g[i].raw) * c[col]);
          xbits[col] |= spectral::magnitude_bits(c[col]);
        }
      }
      const int mw = std::max(static_cast<int>(std::bit_width(mbits)), 33);
      const int lw = static_cast<int>(std::bit_width(gr.row_ptr[i + 1] - gr.row_ptr[i] + 2));
      for (std::size_t col = 0; col < count; ++col) {
        if (mw + static_cast<int>(std::bit_width(xbits[col])) + lw <= 126) {
          const i128 r = fx::detail::rne_shift(static_cast<i128>(sum[col]), 32);
          if (!fx::detail::fits_i64(r)) fx::detail::throw_overflow("spectral round");
          y[i * ldy + col] = fx::Q32::from_raw(static_cast<std::int64_t>(r));
          continue;
        }
        FastExact acc;
        acc.add(static_cast<i128>(x[i * ldx + col].raw) * one);
        for (std::uint64_t k = gr.row_ptr[i]; k < gr.row_ptr[i + 1]; ++k)
          acc.add(-(static_cast<i128>(m[k].raw) * x[static_cast<std::size_t>(gr.col[k]) * ldx + col].raw));
        if (!g.empty()) acc.add(-(static_cast<i128>(g[i].raw) * c[col]));
        y[i * ldy + col] = fx::Q32::from_raw(acc.round_shift(32));
      }
    }
  });
}

template <>
void SpectralOperator<double>::apply_block(const double* x, std::size_t ldx, double* y, std::size_t ldy,
                                           std::size_t count, bool parallel) const {
  const Graph& gr = *graph;
  const bool par = parallel && n >= spectral::kParallelMin;
  // c_col = the fixed pairwise dot of g and column col (R1-NUM-051).
  std::vector<double> c(count, 0.0);
  if (!g.empty()) {
    std::vector<double> xc(n);
    for (std::size_t col = 0; col < count; ++col) {
      for (std::size_t j = 0; j < n; ++j) xc[j] = x[j * ldx + col];
      const std::span<const double> gs(g), xs(xc);
      c[col] = par ? fx::parallel_pairwise_dot(gs, xs) : fx::pairwise_dot(gs, xs);
    }
  }
  // Row i: S = the pairwise sum (R1-NUM-051) of m_ik x_k in column order; y_i = (x_i - S) - g_i c.
  spectral::for_row_blocks(n, par, [&](std::size_t lo, std::size_t hi) {
    std::vector<double> p;
    for (std::size_t i = lo; i < hi; ++i) {
      const std::uint64_t b = gr.row_ptr[i], e_ = gr.row_ptr[i + 1];
      p.resize(e_ - b);
      for (std::size_t col = 0; col < count; ++col) {
        for (std::uint64_t k = b; k < e_; ++k) p[k - b] = m[k] * x[static_cast<std::size_t>(gr.col[k]) * ldx + col];
        double r = x[i * ldx + col] - fx::pairwise_sum(p);
        if (!g.empty()) r = r - g[i] * c[col];
        y[i * ldy + col] = r;
      }
    }
  });
}

}  // namespace r1
