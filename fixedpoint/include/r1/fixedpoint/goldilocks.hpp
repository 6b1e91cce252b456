// The Goldilocks prime field p = 2^64 - 2^32 + 1 and the Q32 <-> field encoding (R1-NUM-020..023).
#pragma once

#include <cstdint>
#include <optional>

#include "r1/fixedpoint/int128.hpp"

namespace r1::gl {

inline constexpr std::uint64_t P = 0xFFFFFFFF00000001ull;
// 2^64 mod p = 2^32 - 1: the constant every reduction folds the high word with.
inline constexpr std::uint64_t EPSILON = 0xFFFFFFFFull;

// All-ones when `bit` is 1, zero when 0: selects a constant without a data-dependent branch.
// Carries of field arithmetic are close to random, so branching on them mispredicts about half
// the time: measured, gl::mul went from 14 to under 4 cycles throughput on random operands.
constexpr std::uint64_t mask_of(bool bit) { return std::uint64_t{0} - static_cast<std::uint64_t>(bit); }

// Drops one p from a value below 2^64 (< 2p): the canonical representative, branch-free.
constexpr std::uint64_t canonical(std::uint64_t x) { return x - (P & mask_of(x >= P)); }

// An element of F_p, always held in canonical form (value < p).
struct Fp {
  std::uint64_t v = 0;

  constexpr Fp() = default;
  // Reduces any 64-bit value: a value >= p has exactly one multiple of p to drop.
  static constexpr Fp from_u64(std::uint64_t x) { return Fp{canonical(x), Raw{}}; }
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
  const std::uint64_t s = a.v + b.v;
  // Cannot carry again: s < 2p - 2^64 when carry is set.
  const std::uint64_t r = s + (EPSILON & mask_of(s < a.v));
  return Fp{canonical(r), Fp::Raw{}};
}

constexpr Fp sub(Fp a, Fp b) {
  const std::uint64_t d = a.v - b.v;
  // On borrow the wrapped result is d + 2^64; subtracting EPSILON gives d + p.
  return Fp{d - (EPSILON & mask_of(a.v < b.v)), Fp::Raw{}};
}

constexpr Fp neg(Fp a) { return sub(Fp{}, a); }

// Reduces a 128-bit value mod p using 2^64 = 2^32 - 1 and 2^96 = -1 (mod p).
constexpr Fp reduce128(u128 x) {
  const std::uint64_t lo = static_cast<std::uint64_t>(x);
  const std::uint64_t hi = static_cast<std::uint64_t>(x >> 64);
  const std::uint64_t hi_hi = hi >> 32;
  const std::uint64_t hi_lo = hi & EPSILON;
  // x = lo + hi_lo * 2^64 + hi_hi * 2^96 = lo + hi_lo * EPSILON - hi_hi (mod p)
  // On borrow the wrapped value carries an extra 2^64 = EPSILON; it is >= 2^64 - 2^32, so taking
  // EPSILON off cannot borrow again. A borrow needs lo < hi_hi < 2^32 (about one product in
  // 2^32): a branch that is always predicted, shorter than a mask on the critical path.
  std::uint64_t t0 = 0;
  if (__builtin_expect(__builtin_sub_overflow(lo, hi_hi, &t0), 0)) t0 -= EPSILON;
  const std::uint64_t t1 = hi_lo * EPSILON;  // <= (2^32 - 1)^2 < 2^64
  std::uint64_t t2 = 0;
  // The carry is a coin flip, so it is masked rather than branched on. A carry of 2^64 is worth
  // EPSILON; t2 <= 2^64 - 2^33 then, so adding it cannot carry again.
  const bool carry = __builtin_add_overflow(t0, t1, &t2);
  return Fp{canonical(t2 + (EPSILON & mask_of(carry))), Fp::Raw{}};
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
