// Exact roundings the spectral solver needs beyond fixedpoint/ (R1-SPEC-010..014): RNE square
// roots of ratios, RNE shifts and correctly rounded doubles of exact sums, exact Q32 x double.
#pragma once

#include <bit>
#include <cstdint>
#include <optional>

#include "r1/fixedpoint/exact_sum.hpp"
#include "r1/fixedpoint/int128.hpp"
#include "r1/fixedpoint/q32.hpp"

namespace r1::spectral {

// ---- 256-bit unsigned integers, only what the square-root rounding needs -------------------

struct U256 {
  u128 lo = 0, hi = 0;
  friend constexpr bool operator==(const U256&, const U256&) = default;
  friend constexpr bool operator<(const U256& a, const U256& b) { return a.hi != b.hi ? a.hi < b.hi : a.lo < b.lo; }
  friend constexpr bool operator<=(const U256& a, const U256& b) { return !(b < a); }
};

// The exact product of two 128-bit values.
constexpr U256 mul_wide(u128 a, u128 b) {
  const u128 mask = 0xFFFFFFFFFFFFFFFFu;
  const u128 a0 = a & mask, a1 = a >> 64, b0 = b & mask, b1 = b >> 64;
  const u128 p00 = a0 * b0, p01 = a0 * b1, p10 = a1 * b0, p11 = a1 * b1;
  // Middle column: the high half of p00 plus the low halves of p01 and p10 (at most 3 * (2^64 - 1)).
  const u128 mid = (p00 >> 64) + (p01 & mask) + (p10 & mask);
  U256 r;
  r.lo = (p00 & mask) | (mid << 64);
  r.hi = p11 + (p01 >> 64) + (p10 >> 64) + (mid >> 64);
  return r;
}

constexpr U256 shl(U256 a, int s) {  // 0 < s < 128
  return U256{a.lo << s, (a.hi << s) | (a.lo >> (128 - s))};
}

// The integer nearest to sqrt(num / den), ties to even (R1-SPEC-010), for den > 0,
// num < 2^254 and a root below 2^63. A double gives a first guess; exact 256-bit comparisons
// then move it to the right integer, so the result never depends on the guess's rounding.
// q is correct when (2q - 1)^2 den <= 4 num < (2q + 1)^2 den, i.e. q - 1/2 <= sqrt(num/den) < q + 1/2.
std::uint64_t rne_sqrt_ratio(U256 num, u128 den);

// ---- rounding an exact sum ------------------------------------------------------------------

// RNE(V / 2^s) of the exact value V held by `sum` (V counts units of 2^-64; the result counts
// units of 2^(s-64)), for 1 <= s <= 127. std::nullopt when it does not fit int64.
std::optional<std::int64_t> round_shift(const fx::ExactSum& sum, int s);

// The double nearest to V * 2^-k (ties to even), computed from the integer's bits (R1-SPEC-012):
// no floating-point operation rounds before the final one, so it is the correctly rounded
// value on every machine. Results below the normal range are flushed to the nearest multiple
// of 2^-1074 by the final std::ldexp (never reached by the solver's magnitudes).
double to_double_scaled(const fx::ExactSum& sum, int k);

// ---- Q32 times a double, rounded once -------------------------------------------------------

// RNE(x * f): the product of the Q32 value and the exact binary value of the finite double f,
// rounded once to Q32 (R1-SPEC-013). Throws fx::OverflowError when it does not fit.
inline fx::Q32 mul_exact(fx::Q32 x, double f) {
  const auto bits = std::bit_cast<std::uint64_t>(f);
  const int biased = static_cast<int>((bits >> 52) & 0x7FF);
  std::int64_t mant = static_cast<std::int64_t>(bits & ((std::uint64_t{1} << 52) - 1));
  int exp2 = 0;  // f = mant * 2^exp2
  if (biased == 0) {
    exp2 = -1074;  // subnormal or zero
  } else {
    mant |= std::int64_t{1} << 52;
    exp2 = biased - 1075;
  }
  if ((bits >> 63) != 0) mant = -mant;
  const i128 p = static_cast<i128>(x.raw) * mant;  // |p| < 2^63 * 2^53: exact
  if (p == 0) return fx::Q32::zero();
  if (exp2 >= 0) {
    // The result must fit int64: |p| * 2^exp2 < 2^63 (multiplication, not a shift of a negative).
    const i128 limit = exp2 >= 63 ? 0 : (i128{1} << (63 - exp2));
    if (p >= limit || p <= -limit) fx::detail::throw_overflow("spectral scale");
    const i128 r = p * (i128{1} << exp2);
    if (!fx::detail::fits_i64(r)) fx::detail::throw_overflow("spectral scale");
    return fx::Q32::from_raw(static_cast<std::int64_t>(r));
  }
  // |p| < 2^116, so a shift of 117 or more leaves less than half a unit: the result is 0.
  if (-exp2 > 117) return fx::Q32::zero();
  const i128 r = fx::detail::rne_shift(p, -exp2);
  if (!fx::detail::fits_i64(r)) fx::detail::throw_overflow("spectral scale");
  return fx::Q32::from_raw(static_cast<std::int64_t>(r));
}

// A coefficient of a linear combination as an integer multiple of 2^-60 (R1-SPEC-013): the
// double's exact value rounded once, ties to even. |c| < 8 is required (the callers' bounds);
// a NaN or larger magnitude throws fx::OverflowError.
inline std::int64_t coef60(double c) {
  if (!(c > -8.0 && c < 8.0)) fx::detail::throw_overflow("spectral coefficient");
  // c * 2^60 is exact in double (a power-of-two scaling of a normal or subnormal value whose
  // magnitude stays below 2^63); from_raw of the Q32 path would round twice, so round here:
  const auto bits = std::bit_cast<std::uint64_t>(c);
  const int biased = static_cast<int>((bits >> 52) & 0x7FF);
  std::int64_t mant = static_cast<std::int64_t>(bits & ((std::uint64_t{1} << 52) - 1));
  int exp2 = 0;
  if (biased == 0) {
    exp2 = -1074;
  } else {
    mant |= std::int64_t{1} << 52;
    exp2 = biased - 1075;
  }
  if ((bits >> 63) != 0) mant = -mant;
  const int shift = exp2 + 60;  // c * 2^60 = mant * 2^shift
  if (mant == 0) return 0;
  if (shift >= 0) return mant * (std::int64_t{1} << shift);  // |c| < 8 keeps this below 2^63
  if (-shift > 60) return 0;             // |mant| < 2^53: below half a unit
  return static_cast<std::int64_t>(fx::detail::rne_shift(mant, -shift));
}

}  // namespace r1::spectral
