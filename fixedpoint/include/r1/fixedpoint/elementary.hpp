// Deterministic elementary functions on Q32 in pure integer arithmetic (R1-NUM-040..049).
#pragma once

#include <span>

#include "r1/fixedpoint/int128.hpp"
#include "r1/fixedpoint/q32.hpp"

namespace r1::fx {

// Every function below returns the exact value rounded to nearest within
//     |result - f(x)| <= 1/2 + 2^-20 ulp        (ulp = 2^-32)            (R1-NUM-041)
// i.e. correctly rounded unless f(x) lies within 2^-20 ulp of a rounding midpoint. They
// evaluate in a 128-bit fixed-point intermediate with 120 fractional bits; the argument is in
// proofs/elementary_error.md and fixedpoint/elementary_test.cpp measures it against
// Boost.Multiprecision cpp_bin_float_50. Results are bit-identical on every machine: no floating
// point, no tables beyond the constants in elementary.cpp. Exact cases stay exact: exp(0) = 1,
// log(1) = 0, exp2(k) and log2(2^k) for integers k, sin(0) = atan(0) = tanh(0) = 0, cos(0) = 1,
// sigmoid(0) = 1/2, pow(x, 0) = 1, pow(1, y) = 1.
inline constexpr int kElementaryBoundLog2 = -20;  // the 2^-20 above

// Correctly rounded constants: RNE(c * 2^32) (checked by ElementaryConstants.* tests).
inline constexpr Q32 kPi{13493037705};
inline constexpr Q32 kHalfPi{6746518852};
inline constexpr Q32 kTwoPi{26986075409};
inline constexpr Q32 kLn2{2977044472};
inline constexpr Q32 kE{11674931555};

// e^x. OverflowError when the rounded result exceeds Q32::max() (x > 21.4876...); x <= -23
// (e^x < 2^-33, under half an ulp) gives 0.
Q32 exp(Q32 x);
// 2^x. OverflowError for x >= 31; x <= -33 gives 0 (2^-33 is a tie and goes to the even 0).
Q32 exp2(Q32 x);
// Natural and base-2 logarithms. DomainError for x <= 0. Never overflow (|log2 x| <= 32).
Q32 log(Q32 x);
Q32 log2(Q32 x);
// x^y = 2^(y log2 x) for x > 0, with one rounding. pow(0, y) is 0 for y > 0 and 1 for y = 0.
// DomainError for x < 0 and for x = 0, y < 0; OverflowError when the result exceeds the range;
// results below half an ulp round to 0.
Q32 pow(Q32 x, Q32 y);
// Sine and cosine with exact argument reduction: valid over the whole Q32 range.
Q32 sin(Q32 x);
Q32 cos(Q32 x);
// atan2(y, x) in [-kPi, kPi], the angle of the vector (x, y). Without a signed zero,
// atan2(0, x < 0) = kPi and atan2(0, 0) = 0 (as C's atan2(+0, +0)).
Q32 atan2(Q32 y, Q32 x);
// atan(x) = atan2(x, 1), in [-kHalfPi, kHalfPi].
Q32 atan(Q32 x);
// Hyperbolic tangent; rounds to exactly +-1 for |x| >= 11.8 or so.
Q32 tanh(Q32 x);
// The logistic function 1 / (1 + e^-x); rounds to exactly 0 or 1 for |x| >= 22.9 or so.
Q32 sigmoid(Q32 x);

namespace detail {
// The fixed-point constants the functions compute with, exposed so that a test re-derives each
// one: value = c * 2^scale rounded to nearest, except "half_pi_hi", which is the floor (its
// remainder is "half_pi_lo" at 2^(scale + 64)). `arg` is i for the CORDIC angles atan(2^-i).
struct WideConstant {
  const char* name;
  int arg;
  u128 value;
  int scale;
};
std::span<const WideConstant> elementary_constants();
}  // namespace detail

}  // namespace r1::fx
