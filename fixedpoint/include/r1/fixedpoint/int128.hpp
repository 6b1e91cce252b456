// 128-bit integer aliases used by exact products and wide accumulation (R1-NUM-002).
#pragma once

#include <cstdint>

namespace r1 {

// GCC and Clang provide 128-bit integers as an extension; naming them once here keeps
// -Wpedantic-style diagnostics out of every file that needs an exact 64x64 product.
__extension__ typedef __int128 i128;
__extension__ typedef unsigned __int128 u128;

inline constexpr u128 u128_max = ~u128{0};
inline constexpr i128 i128_max = static_cast<i128>(u128_max >> 1);
inline constexpr i128 i128_min = -i128_max - 1;

}  // namespace r1
