// Hemera internals (R1-HASH-002..011, R1-HASH-020): lazy Goldilocks arithmetic, the lane-batched
// permutation, the sponge and tree state layout; shared by the permutation, sponge, bulk paths, tests.
#pragma once

#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "r1/fixedpoint/goldilocks.hpp"
#include "r1/fixedpoint/hemera.hpp"

namespace r1::hemera::detail {

// Lazy field arithmetic. A residue is held as any 64-bit representative (x or x + p when
// x < 2^64 - p), so most results skip the final "subtract p if >= p"; gl::canonical() picks the
// canonical one where a value leaves the permutation or is compared with zero. Congruence is all
// the permutation needs, so the output equals the canonical definition bit for bit.
namespace lazy {

using u64 = std::uint64_t;
using gl::EPSILON;
using gl::mask_of;

// EPSILON when `carry` is set, else 0, without a branch. Carries of field arithmetic are coin
// flips, and compilers may turn a select on one back into a branch (clang 14 does, measured 2x
// slower from mispredictions). The empty asm hides where the mask came from so the arithmetic form
// stays; it emits no instruction and names no register, so it is the same on every target.
[[gnu::always_inline]] inline u64 epsilon_if(bool carry) {
  u64 m = mask_of(carry);
  __asm__("" : "+r"(m));
  return m & EPSILON;
}

// Any 128-bit value to a representative below 2^64: the gl::reduce128 fold without its last step.
[[gnu::always_inline]] inline u64 reduce(u128 x) {
  const u64 lo = static_cast<u64>(x);
  const u64 hi = static_cast<u64>(x >> 64);
  const u64 hi_hi = hi >> 32;
  const u64 hi_lo = hi & EPSILON;
  // 2^96 = -1: subtract hi_hi. On borrow the wrapped value is >= 2^64 - 2^32 and the lost 2^64
  // is worth EPSILON, which then cannot borrow again. A borrow needs lo < hi_hi < 2^32, about
  // one product in 2^32, so this is a branch the predictor always gets right: measured 15-25%
  // faster than the masked form, which lengthens every multiplication's dependency chain.
  u64 t0;
  if (__builtin_expect(__builtin_sub_overflow(lo, hi_hi, &t0), 0)) t0 -= EPSILON;
  // 2^64 = EPSILON: hi_lo * EPSILON <= (2^32 - 1)^2. The carry of this sum is a coin flip, so it
  // is masked, not branched on; with it the sum is at most 2^64 - 2^33, so adding EPSILON cannot
  // carry a second time.
  const u64 t1 = hi_lo * EPSILON;
  u64 t2;
  const bool carry = __builtin_add_overflow(t0, t1, &t2);
  return t2 + epsilon_if(carry);
}

// A sum of a few 64-bit values (below 2^96) to a representative below 2^64: the high word times
// EPSILON fits 64 bits, and one carry leaves room to add EPSILON once more.
[[gnu::always_inline]] inline u64 fold(u128 x) {
  const u64 lo = static_cast<u64>(x);
  const u64 t = static_cast<u64>(x >> 64) * EPSILON;
  const u64 s = lo + t;
  return s + epsilon_if(s < t);
}

[[gnu::always_inline]] inline u64 mul(u64 a, u64 b) { return reduce(static_cast<u128>(a) * b); }

// a + c for any a and a canonical c (< p): with a carry the wrapped sum is below p - 1, so the
// EPSILON it is worth fits without a second carry.
[[gnu::always_inline]] inline u64 add_canonical(u64 a, u64 c) {
  const u64 s = a + c;
  return s + epsilon_if(s < c);
}

// x^(p-2) by the addition chain of gl::pow_p_minus_2 (63 squarings, 8 multiplications).
[[gnu::always_inline]] inline u64 pow_p_minus_2(u64 x) {
  auto sq = [](u64 a, int n) {
    for (int j = 0; j < n; ++j) a = mul(a, a);
    return a;
  };
  const u64 e1 = x;
  const u64 e3 = mul(sq(mul(sq(e1, 1), e1), 1), e1);  // x^(2^3 - 1)
  const u64 e6 = mul(sq(e3, 3), e3);                   // x^(2^6 - 1)
  const u64 e12 = mul(sq(e6, 6), e6);                  // x^(2^12 - 1)
  const u64 e24 = mul(sq(e12, 12), e12);               // x^(2^24 - 1)
  const u64 e30 = mul(sq(e24, 6), e6);                 // x^(2^30 - 1)
  const u64 e31 = mul(sq(e30, 1), e1);                 // x^(2^31 - 1)
  const u64 b = sq(e31, 1);                            // x^(2^32 - 2)
  return mul(sq(b, 32), mul(b, e1));                   // x^((2^32 - 2) 2^32 + 2^32 - 1)
}

// x_k^(p-2) for L lanes with one field inversion (Montgomery's trick): prefix products, one
// x^(p-2) of the last prefix, then a backward pass peels off each lane's inverse: 71 + 3 (L - 1)
// multiplications instead of 71 L. x^(p-2) maps 0 to 0 but 0 has no inverse, and one zero lane
// would zero the whole product: each zero is replaced by 1 for the product and its result masked
// back to 0, branch-free.
template <std::size_t L>
[[gnu::always_inline]] inline void invert_lanes(u64 (&x)[L]) {
  u64 a[L], keep[L], prefix[L];
  for (std::size_t k = 0; k < L; ++k) {
    const u64 c = gl::canonical(x[k]);  // the one representative of zero is 0 after this
    const bool zero = c == 0;
    a[k] = c | static_cast<u64>(zero);
    keep[k] = mask_of(!zero);
  }
  prefix[0] = a[0];
  for (std::size_t k = 1; k < L; ++k) prefix[k] = mul(prefix[k - 1], a[k]);
  u64 inv = pow_p_minus_2(prefix[L - 1]);  // (a_0 ... a_{L-1})^-1
  for (std::size_t k = L - 1; k > 0; --k) {
    x[k] = mul(inv, prefix[k - 1]) & keep[k];  // a_k^-1 = (a_0 ... a_k)^-1 (a_0 ... a_{k-1})
    inv = mul(inv, a[k]);                      // (a_0 ... a_{k-1})^-1
  }
  x[0] = inv & keep[0];
}

}  // namespace lazy

// Permutes L independent states in lockstep; the result equals permute() on each state. Each
// partial round shares one field inversion across the lanes (lazy::invert_lanes).
template <std::size_t L>
void permute_lanes(State* states);

// Cuts n independent items into lockstep groups: LANES wide, then 8, 4, 2, 1 for the rest (the
// lane counts permute_lanes is built for); one at a time when `batching` is off. Calls
// run(std::integral_constant<std::size_t, L>, first) per group. A remainder is not padded to 16
// lanes: a padded batch costs 16 states of work, while narrower groups cost in proportion (per
// state, measured: 16 lanes 1.9 us, 8 2.2, 4 2.6, 2 3.4, 1 5.1).
template <class Run>
void split_lanes(std::size_t n, bool batching, Run&& run) {
  static_assert(LANES == 16, "split_lanes and the permute_lanes instantiations assume 16 lanes");
  std::size_t i = 0;
  if (!batching) {
    for (; i < n; ++i) run(std::integral_constant<std::size_t, 1>{}, i);
    return;
  }
  for (; n - i >= 16; i += 16) run(std::integral_constant<std::size_t, 16>{}, i);
  if (n - i >= 8) run(std::integral_constant<std::size_t, 8>{}, i), i += 8;
  if (n - i >= 4) run(std::integral_constant<std::size_t, 4>{}, i), i += 4;
  if (n - i >= 2) run(std::integral_constant<std::size_t, 2>{}, i), i += 2;
  if (n - i >= 1) run(std::integral_constant<std::size_t, 1>{}, i);
}

// Permutes n independent states: lanes of LANES while batching is on, then smaller lane counts
// for the rest; one state at a time while it is off.
void permute_states(State* states, std::size_t n);

// Counts calls of permute_lanes with more than one lane (relaxed; for tests that prove which
// path ran).
std::uint64_t lane_batches();

// Sponge layout. Domain tags (state[11]): 0 plain, 1 keyed, 2 derive-key context, 3 derive-key
// material.
inline constexpr std::uint64_t DOMAIN_HASH = 0;
inline constexpr std::uint64_t DOMAIN_KEYED = 1;
inline constexpr std::uint64_t DOMAIN_DERIVE_CONTEXT = 2;
inline constexpr std::uint64_t DOMAIN_DERIVE_MATERIAL = 3;

// Capacity layout (state[8..15]): 8 chunk counter, 9 tree flags, 10 input length, 11 domain tag.
inline constexpr std::size_t CAP_COUNTER = 8;
inline constexpr std::size_t CAP_FLAGS = 9;
inline constexpr std::size_t CAP_LENGTH = 10;
inline constexpr std::size_t CAP_DOMAIN = 11;

inline constexpr std::uint64_t FLAG_ROOT = 1;
inline constexpr std::uint64_t FLAG_PARENT = 2;
inline constexpr std::uint64_t FLAG_CHUNK = 4;

// Adds one 56-byte block into the rate: seven little-endian bytes per element, always below p, so
// the chunk needs no reduction and the field addition is the only one.
inline void absorb_rate(State& s, const std::uint8_t* block) {
  for (std::size_t i = 0; i < RATE; ++i) {
    std::uint64_t v = 0;
    for (std::size_t b = 0; b < 7; ++b) v |= static_cast<std::uint64_t>(block[7 * i + b]) << (8 * b);
    s[i] = gl::add(gl::Fp::from_u64(s[i]), gl::Fp::from_u64(v)).v;
  }
}

// The finalisation block: the `rest` (< 56) trailing input bytes, 0x01, zeros to 56 bytes; the
// total byte count goes to state[10] so that inputs differing only in trailing zeros differ.
inline void absorb_final(State& s, const std::uint8_t* rest, std::size_t rest_len, std::uint64_t total) {
  std::uint8_t pad[RATE_BYTES] = {};
  for (std::size_t i = 0; i < rest_len; ++i) pad[i] = rest[i];
  pad[rest_len] = 0x01;
  absorb_rate(s, pad);
  s[CAP_LENGTH] = gl::Fp::from_u64(total).v;
}

// Elements 0..3 as 8-byte little-endian words.
inline Digest digest_of(const State& s) {
  Digest d{};
  for (std::size_t i = 0; i < 4; ++i)
    for (std::size_t b = 0; b < 8; ++b) d[8 * i + b] = static_cast<std::uint8_t>(s[i] >> (8 * b));
  return d;
}

// A digest back to four elements. Digests are canonical; any 64-bit word is reduced so that keys
// of arbitrary bytes stay well defined.
inline void digest_words(const Digest& d, std::uint64_t* out) {
  for (std::size_t i = 0; i < 4; ++i) {
    std::uint64_t v = 0;
    for (std::size_t b = 0; b < 8; ++b) v |= static_cast<std::uint64_t>(d[8 * i + b]) << (8 * b);
    out[i] = gl::Fp::from_u64(v).v;
  }
}

// The state that binds a chunk's plain digest to its position: digest in elements 0..3, counter in
// state[8], CHUNK (| ROOT for a sole chunk) in state[9]; one permutation gives the leaf digest.
inline State leaf_state(const Digest& chunk_digest, std::uint64_t counter, bool is_root) {
  State s{};
  digest_words(chunk_digest, s.data());
  s[CAP_COUNTER] = gl::Fp::from_u64(counter).v;
  s[CAP_FLAGS] = FLAG_CHUNK | (is_root ? FLAG_ROOT : 0);
  return s;
}

// A parent: the two child digests fill the 8-element rate exactly; PARENT (| ROOT at the top) in
// state[9]; one permutation.
inline State node_state(const Digest& left, const Digest& right, bool is_root) {
  State s{};
  digest_words(left, s.data());
  digest_words(right, s.data() + 4);
  s[CAP_FLAGS] = FLAG_PARENT | (is_root ? FLAG_ROOT : 0);
  return s;
}

}  // namespace r1::hemera::detail
