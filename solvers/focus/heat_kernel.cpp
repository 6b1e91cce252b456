// Heat kernel: Bessel-function Chebyshev coefficients in 256-bit fixed point and the sub-stepped
// Chebyshev recurrence in the walk matrix N, Q32 and fp64 (R1-FOC-040..044, R1-FOC-082).
#include "heat_kernel.hpp"

#include <boost/multiprecision/cpp_int.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace r1 {

namespace {

using boost::multiprecision::cpp_int;

// Fractional bits of the fixed-point evaluation: the accumulated truncation error stays below
// 2^-240 (R1-FOC-044), far below the 2^-33 that decides a Q32 rounding.
constexpr unsigned kFracBits = 256;
// tau in (0, 64] (R1-FOC-002) and K <= 32: the caps of the validated parameters.
constexpr std::int64_t kTauMaxRaw = std::int64_t{64} << 32;
constexpr std::uint32_t kDegreeMax = 32;

// v * 2^-256 rounded to nearest Q32, ties to the even raw.
Q32 round_to_q32(const cpp_int& v) {
  constexpr unsigned kShift = kFracBits - 32;
  cpp_int q = v >> kShift;
  const cpp_int rem = v - (q << kShift);
  const cpp_int half = cpp_int(1) << (kShift - 1);
  if (rem > half || (rem == half && (q & 1) != 0)) ++q;
  return Q32::from_raw(q.convert_to<std::int64_t>());
}

// v * 2^-256 (v >= 0) rounded to the nearest double, ties to even: keep the top 53 bits and round
// on the rest. Every non-zero v gives at least 2^-256, a normal double, so ldexp is exact.
double round_to_double(const cpp_int& v) {
  if (v == 0) return 0.0;
  const unsigned bits = boost::multiprecision::msb(v) + 1;
  if (bits <= 53) return std::ldexp(static_cast<double>(v.convert_to<std::uint64_t>()), -static_cast<int>(kFracBits));
  const unsigned shift = bits - 53;
  cpp_int mant = v >> shift;
  const cpp_int rem = v - (mant << shift);
  const cpp_int half = cpp_int(1) << (shift - 1);
  if (rem > half || (rem == half && (mant & 1) != 0)) ++mant;  // 2^53 after a carry is still exact
  return std::ldexp(static_cast<double>(mant.convert_to<std::uint64_t>()), static_cast<int>(shift) - static_cast<int>(kFracBits));
}

}  // namespace

HeatCoefficients heat_coefficients(Q32 tau, std::uint32_t degree) {
  if (tau.raw <= 0 || tau.raw > kTauMaxRaw) throw std::invalid_argument("heat_coefficients: tau must lie in (0, 64]");
  if (degree > kDegreeMax) throw std::invalid_argument("heat_coefficients: degree must be at most 32");
  HeatCoefficients out;
  // s = tau lambda_max / 2 = tau (lambda_max = 2, R1-FOC-042); m = ceil(s / 2), exact on the raw.
  const std::int64_t two_raw = std::int64_t{2} << 32;
  const std::int64_t m = (tau.raw + two_raw - 1) / two_raw;
  out.substeps = static_cast<std::uint32_t>(m);

  const cpp_int one = cpp_int(1) << kFracBits;
  // sigma = tau / m = tau.raw / (m 2^32), and x = sigma / 2, each truncated to 2^-256.
  const cpp_int sigma = (cpp_int(tau.raw) << (kFracBits - 32)) / m;
  const cpp_int x = (cpp_int(tau.raw) << (kFracBits - 33)) / m;

  // e^-sigma = sum_j (-sigma)^j / j!: each magnitude from the previous by one multiply and one
  // division, truncated; sigma <= 2, so the terms shrink from j = 2 on and reach 0 by j ~ 60.
  cpp_int e_minus = 0;
  {
    cpp_int term = one;
    for (std::uint32_t j = 0; term != 0; ++j) {
      e_minus += (j % 2 == 0) ? term : cpp_int(-term);
      term = term * sigma / (one * (j + 1));
    }
  }
  for (std::uint32_t k = 0; k <= degree; ++k) {
    // x^k / k!, then I_k(sigma) = sum_j x^(2j+k) / (j! (j+k)!), term by term.
    cpp_int lead = one;
    for (std::uint32_t i = 1; i <= k; ++i) lead = lead * x / (one * i);
    cpp_int bessel = 0;
    cpp_int term = lead;
    for (std::uint32_t j = 0; term != 0; ++j) {
      bessel += term;
      term = term * x * x / (one * one * (j + 1) * (j + 1 + k));
    }
    // c_k = (2 - [k = 0]) e^-sigma I_k(sigma), truncated once more to 2^-256.
    const cpp_int c = e_minus * bessel * (k == 0 ? 1 : 2) / one;
    out.q32.push_back(round_to_q32(c));
    out.f64.push_back(round_to_double(c));
  }
  return out;
}

namespace focus {

void heat_q32(const OperatorsQ32& ops, const HeatCoefficients& coeff, std::span<const Q32> x, std::vector<Q32>& out,
              HeatScratch* scratch, const std::vector<Q32>* walk_of_x) {
  const std::uint32_t n = ops.n();
  // Rows from m on are empty (build_local's ring): N x = x there, so within a sub-step every t_k
  // equals t_0 on them, and their sum is (sum_k c_k) t_0, exactly as the recurrence computes it
  // (t_1 = RNE(t_0 2^32) = t_0, t_(k+1) = RNE(2 t_k 2^32 - t_(k-1) 2^32) = t_0). The loops run on
  // the rows before m only: the work is the region's, the bits those of the full recurrence.
  const std::uint32_t m = ops.fixed_from();
  const std::size_t terms = coeff.q32.size();
  const bool parallel = ops.parallel();
  i128 c_sum = 0;  // at most 33 coefficients below 2^33 each
  for (const Q32 c : coeff.q32) c_sum += c.raw;
  HeatScratch own;
  HeatScratch& w = scratch != nullptr ? *scratch : own;
  std::vector<Q32>&t0 = w.t0, &t1 = w.t1, &t2 = w.t2;
  t0.assign(x.begin(), x.end());
  t1.resize(n);
  if (ops.on_products()) t2.resize(n);  // a product writes apart from what it reads
  std::vector<i128>& acc = w.acc;  // sum_k c_k t_k exactly: K + 1 <= 33 terms below 2^96 each
  acc.resize(m);
  const std::int64_t c0 = coeff.q32[0].raw;
  for (std::uint32_t sub = 0; sub < coeff.substeps; ++sub) {
    std::copy(t0.begin() + m, t0.end(), t1.begin() + m);
    if (ops.on_products()) {
      // The same recurrence with each product on the backend's (R1-FOC-092): a whole-graph
      // operator, so m = n.
      if (terms > 1) ops.walk(t0, t1);
      for_rows(parallel, m, [&](std::uint32_t b, std::uint32_t e) {
        for (std::uint32_t i = b; i < e; ++i)
          acc[i] = static_cast<i128>(c0) * t0[i].raw + (terms > 1 ? static_cast<i128>(coeff.q32[1].raw) * t1[i].raw : 0);
      });
      for (std::size_t k = 2; k < terms; ++k) {
        ops.chebyshev_step(t1, t0, t2);
        const std::int64_t ck = coeff.q32[k].raw;
        for_rows(parallel, m, [&](std::uint32_t b, std::uint32_t e) {
          for (std::uint32_t i = b; i < e; ++i) acc[i] += static_cast<i128>(ck) * t2[i].raw;
        });
        std::swap(t0, t1);
        std::swap(t1, t2);
      }
    } else {
      const std::int64_t c1 = terms > 1 ? coeff.q32[1].raw : 0;
      for_rows(parallel, m, [&](std::uint32_t b, std::uint32_t e) {
        for (std::uint32_t i = b; i < e; ++i) {
          acc[i] = static_cast<i128>(c0) * t0[i].raw;
          if (terms == 1) continue;
          // t_1 = N t_0, the caller's in the first sub-step when it formed it.
          t1[i] = sub == 0 && walk_of_x != nullptr ? (*walk_of_x)[i] : Q32::from_raw(round_q32(ops.walk_row(i, t0.data())));
          acc[i] += static_cast<i128>(c1) * t1[i].raw;
        }
      });
      for (std::size_t k = 2; k < terms; ++k) {
        const std::int64_t ck = coeff.q32[k].raw;
        for_rows(parallel, m, [&](std::uint32_t b, std::uint32_t e) {
          for (std::uint32_t i = b; i < e; ++i) {
            // t_(k+1),i = RNE(2 sum_j N(i, j) t_k,j - t_(k-1),i), one rounding. Row i is the only
            // reader of t_(k-1),i, so t_(k+1),i takes its place: two vectors, not three, beside
            // the gathers (R1-FOC-090).
            const i128 exact = 2 * ops.walk_row(i, t1.data()) - (static_cast<i128>(t0[i].raw) << 32);
            t0[i] = Q32::from_raw(round_q32(exact));
            acc[i] += static_cast<i128>(ck) * t0[i].raw;
          }
        });
        std::swap(t0, t1);
      }
    }
    // The sub-step result, rounded once; it is the next sub-step's t_0.
    for_rows(parallel, m, [&](std::uint32_t b, std::uint32_t e) {
      for (std::uint32_t i = b; i < e; ++i) t0[i] = Q32::from_raw(round_q32(acc[i]));
    });
    for (std::uint32_t i = m; i < n; ++i) t0[i] = Q32::from_raw(round_q32(c_sum * t0[i].raw));
  }
  // The result leaves through a swap: `out`'s old buffer is the next call's t_0.
  out.swap(t0);
}

void heat_f64(const OperatorsF64& ops, const HeatCoefficients& coeff, std::span<const double> x, std::vector<double>& out) {
  const std::uint32_t n = ops.n();
  const std::size_t terms = coeff.f64.size();
  std::vector<double> t0(x.begin(), x.end()), t1, t2(n), acc(n);
  for (std::uint32_t sub = 0; sub < coeff.substeps; ++sub) {
    for (std::uint32_t i = 0; i < n; ++i) acc[i] = coeff.f64[0] * t0[i];
    if (terms > 1) {
      ops.walk(t0, t1);
      for (std::uint32_t i = 0; i < n; ++i) acc[i] = acc[i] + coeff.f64[1] * t1[i];
    }
    for (std::size_t k = 2; k < terms; ++k) {
      const double ck = coeff.f64[k];
      for_rows(ops.parallel(), n, [&](std::uint32_t b, std::uint32_t e) {
        std::vector<double> buf;
        for (std::uint32_t i = b; i < e; ++i) {
          t2[i] = 2.0 * ops.walk_row(i, t1.data(), buf) - t0[i];
          acc[i] = acc[i] + ck * t2[i];  // left to right in k (R1-FOC-082)
        }
      });
      std::swap(t0, t1);
      std::swap(t1, t2);
    }
    t0 = acc;
  }
  out = std::move(t0);
}

}  // namespace focus
}  // namespace r1
