// The Goldilocks prime field p = 2^64 - 2^32 + 1 and the Q32 <-> field encoding (R1-NUM-020..023).
#pragma once

#include <cstdint>
#include <optional>

#include "r1/fixedpoint/int128.hpp"

namespace r1::gl {

inline constexpr std::uint64_t P = 0xFFFFFFFF00000001ull;
// 2^64 mod p = 2^32 - 1: the constant every reduction folds the high word with.
inline constexpr std::uint64_t EPSILON = 0xFFFFFFFFull;

// An element of F_p, always held in canonical form (value < p).
struct Fp {
  std::uint64_t v = 0;

  constexpr Fp() = default;
  // Reduces any 64-bit value: a value >= p has exactly one multiple of p to drop.
  static constexpr Fp from_u64(std::uint64_t x) { return Fp{x >= P ? x - P : x, Raw{}}; }
  constexpr std::uint64_t value() const { return v; }

  friend constexpr bool operator==(Fp a, Fp b) { return a.v == b.v; }

 private:
  struct Raw {};
  constexpr Fp(std::uint64_t x, Raw) : v(x) {}
  friend constexpr Fp add(Fp, Fp);
  friend constexpr Fp sub(Fp, Fp);
  friend constexpr Fp reduce128(u128);
};

constexpr Fp add(Fp a, Fp b) {
  // a + b < 2p < 2^65: add in 64 bits, and on carry the lost 2^64 is worth EPSILON mod p.
  std::uint64_t s = a.v + b.v;
  std::uint64_t carry = s < a.v;
  std::uint64_t r = s + carry * EPSILON;  // cannot carry again: s < 2p - 2^64 when carry is set
  return Fp{r >= P ? r - P : r, Fp::Raw{}};
}

constexpr Fp sub(Fp a, Fp b) {
  std::uint64_t d = a.v - b.v;
  std::uint64_t borrow = a.v < b.v;
  // On borrow the wrapped result is d + 2^64; subtracting EPSILON gives d + p.
  return Fp{d - borrow * EPSILON, Fp::Raw{}};
}

constexpr Fp neg(Fp a) { return sub(Fp{}, a); }

// Reduces a 128-bit value mod p using 2^64 = 2^32 - 1 and 2^96 = -1 (mod p).
constexpr Fp reduce128(u128 x) {
  const std::uint64_t lo = static_cast<std::uint64_t>(x);
  const std::uint64_t hi = static_cast<std::uint64_t>(x >> 64);
  const std::uint64_t hi_hi = hi >> 32;
  const std::uint64_t hi_lo = hi & EPSILON;
  // x = lo + hi_lo * 2^64 + hi_hi * 2^96 = lo + hi_lo * EPSILON - hi_hi (mod p)
  std::uint64_t t0 = lo - hi_hi;
  if (lo < hi_hi) t0 -= EPSILON;  // borrow: the wrapped value carries an extra 2^64 = EPSILON
  const std::uint64_t t1 = hi_lo * EPSILON;  // < 2^64
  std::uint64_t t2 = t0 + t1;
  if (t2 < t0) t2 += EPSILON;  // carry of 2^64 is worth EPSILON
  return Fp{t2 >= P ? t2 - P : t2, Fp::Raw{}};
}

constexpr Fp mul(Fp a, Fp b) { return reduce128(static_cast<u128>(a.v) * b.v); }
constexpr Fp square(Fp a) { return mul(a, a); }

// a^e by square-and-multiply, most significant bit first.
constexpr Fp pow(Fp a, std::uint64_t e) {
  Fp r = Fp::from_u64(1);
  for (int bit = 63; bit >= 0; --bit) {
    r = square(r);
    if ((e >> bit) & 1u) r = mul(r, a);
  }
  return r;
}

// a^(p-2) by a fixed addition chain (63 squarings, 8 multiplications); maps 0 to 0, which is
// the Hemera partial-round S-box. For a != 0 it is the multiplicative inverse.
Fp pow_p_minus_2(Fp a);

// The multiplicative inverse; std::nullopt for 0, which has none.
std::optional<Fp> inverse(Fp a);

// Q32 <-> field encoding (R1-NUM-023): a raw Q32 integer r maps to r (r >= 0) or p + r (r < 0);
// residues above (p-1)/2 decode as negative. Only |r| <= (p-1)/2 is encodable.
inline constexpr std::int64_t ENCODE_MAX = static_cast<std::int64_t>((P - 1) / 2);
std::optional<Fp> encode(std::int64_t raw);
std::int64_t decode(Fp a);

}  // namespace r1::gl
