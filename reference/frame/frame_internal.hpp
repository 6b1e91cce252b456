// Shared helpers of the frame stage: the correctly rounded integer-to-double conversion (R1-FRM-031, R1-FRM-037).
#pragma once

#include <cmath>
#include <cstdint>

#include "r1/fixedpoint/int128.hpp"

namespace r1::frame_detail {

// The exact unsigned integer rounded once to double, ties to even, by integer shifting (no
// dependence on the compiler's 128-bit conversion routine); scaling by a power of two is exact.
inline double to_double_rne(u128 u) {
  int bits = 0;
  for (u128 t = u; t != 0; t >>= 1) ++bits;
  if (bits <= 53) return static_cast<double>(static_cast<std::uint64_t>(u));
  const int shift = bits - 53;
  u128 q = u >> shift;
  const u128 rem = u & ((u128{1} << shift) - 1);
  const u128 half = u128{1} << (shift - 1);
  if (rem > half || (rem == half && (q & 1) != 0)) ++q;  // q may reach 2^53: still exact
  return std::ldexp(static_cast<double>(static_cast<std::uint64_t>(q)), shift);
}

inline double to_double_rne(i128 v) {
  const bool neg = v < 0;
  const double d = to_double_rne(neg ? u128{0} - static_cast<u128>(v) : static_cast<u128>(v));
  return neg ? -d : d;
}

}  // namespace r1::frame_detail
