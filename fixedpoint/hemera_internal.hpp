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

// x_c^(p-2) for C independent values by the addition chain of gl::pow_p_minus_2 (63 squarings,
// 8 multiplications). Each step is taken for all C values before the next, so the C dependency
// chains interleave: one chain is bound by the multiplication's latency, several share it.
template <std::size_t C>
[[gnu::always_inline]] inline void pow_p_minus_2_n(u64 (&x)[C]) {
  using V = u64[C];
  auto sq = [](V& a, int n) {
    for (int j = 0; j < n; ++j)
      for (std::size_t c = 0; c < C; ++c) a[c] = mul(a[c], a[c]);
  };
  auto times = [](V& a, const V& b) {
    for (std::size_t c = 0; c < C; ++c) a[c] = mul(a[c], b[c]);
  };
  auto copy = [](V& a, const V& b) {
    for (std::size_t c = 0; c < C; ++c) a[c] = b[c];
  };
  V e1, e3, e6, e12, e24, t;
  copy(e1, x);
  copy(e3, e1), sq(e3, 1), times(e3, e1), sq(e3, 1), times(e3, e1);  // x^(2^3 - 1)
  copy(e6, e3), sq(e6, 3), times(e6, e3);                            // x^(2^6 - 1)
  copy(e12, e6), sq(e12, 6), times(e12, e6);                         // x^(2^12 - 1)
  copy(e24, e12), sq(e24, 12), times(e24, e12);                      // x^(2^24 - 1)
  copy(t, e24), sq(t, 6), times(t, e6);                              // x^(2^30 - 1)
  sq(t, 1), times(t, e1);                                            // x^(2^31 - 1)
  sq(t, 1);                                                          // b = x^(2^32 - 2)
  copy(x, t), times(x, e1);                                          // b x
  sq(t, 32), times(x, t);                                            // b^(2^32) b x
}

[[gnu::always_inline]] inline u64 pow_p_minus_2(u64 x) {
  u64 v[1] = {x};
  pow_p_minus_2_n<1>(v);
  return v[0];
}

// x_k^(p-2) for C M lanes with C field inversions (Montgomery's trick on each run of M lanes:
// lanes c M .. c M + M - 1 form chain c): prefix products, one x^(p-2) of each chain's last
// prefix, then a backward pass peels off each lane's inverse: 71 C + 3 (M - 1) C multiplications
// instead of 71 C M. The C chains run interleaved (pow_p_minus_2_n), which hides most of the
// multiplication's latency. x^(p-2) maps 0 to 0 but 0 has no inverse, and one zero lane would
// zero its chain's product: each zero is replaced by 1 for the product and its result masked
// back to 0, branch-free.
template <std::size_t C, std::size_t M>
[[gnu::always_inline]] inline void invert_chains(u64* x) {
  u64 a[C][M], keep[C][M], prefix[C][M], inv[C];
  for (std::size_t c = 0; c < C; ++c)
    for (std::size_t k = 0; k < M; ++k) {
      const u64 v = gl::canonical(x[c * M + k]);  // the one representative of zero is 0 after this
      const bool zero = v == 0;
      a[c][k] = v | static_cast<u64>(zero);
      keep[c][k] = mask_of(!zero);
    }
  for (std::size_t c = 0; c < C; ++c) prefix[c][0] = a[c][0];
  for (std::size_t k = 1; k < M; ++k)
    for (std::size_t c = 0; c < C; ++c) prefix[c][k] = mul(prefix[c][k - 1], a[c][k]);
  for (std::size_t c = 0; c < C; ++c) inv[c] = prefix[c][M - 1];
  pow_p_minus_2_n<C>(inv);  // (a_0 ... a_{M-1})^-1 of each chain
  for (std::size_t k = M - 1; k > 0; --k)
    for (std::size_t c = 0; c < C; ++c) {
      x[c * M + k] = mul(inv[c], prefix[c][k - 1]) & keep[c][k];  // a_k^-1 = (a_0 ... a_k)^-1 (a_0 ... a_{k-1})
      inv[c] = mul(inv[c], a[c][k]);                             // (a_0 ... a_{k-1})^-1
    }
  for (std::size_t c = 0; c < C; ++c) x[c * M] = inv[c] & keep[c][0];
}

// All L lanes as one chain.
template <std::size_t L>
[[gnu::always_inline]] inline void invert_lanes(u64 (&x)[L]) {
  invert_chains<1, L>(x);
}

}  // namespace lazy

// Permutes L independent states in lockstep; the result equals permute() on each state. Each
// partial round shares one field inversion across the lanes (lazy::invert_lanes).
template <std::size_t L>
void permute_lanes(State* states);

// Cuts n independent items into lockstep groups: LANES wide, then 32, 16, 8, 4, 2, 1 for the
// rest (the lane counts permute_lanes is built for); one at a time when `batching` is off. Calls
// run(std::integral_constant<std::size_t, L>, first) per group. A remainder is not padded to a
// full group: a padded batch costs LANES states of work, while narrower groups cost in
// proportion.
template <class Run>
void split_lanes(std::size_t n, bool batching, Run&& run) {
  static_assert(LANES == 64, "split_lanes and the permute_lanes instantiations assume 64 lanes");
  std::size_t i = 0;
  if (!batching) {
    for (; i < n; ++i) run(std::integral_constant<std::size_t, 1>{}, i);
    return;
  }
  for (; n - i >= 64; i += 64) run(std::integral_constant<std::size_t, 64>{}, i);
  if (n - i >= 32) run(std::integral_constant<std::size_t, 32>{}, i), i += 32;
  if (n - i >= 16) run(std::integral_constant<std::size_t, 16>{}, i), i += 16;
  if (n - i >= 8) run(std::integral_constant<std::size_t, 8>{}, i), i += 8;
  if (n - i >= 4) run(std::integral_constant<std::size_t, 4>{}, i), i += 4;
  if (n - i >= 2) run(std::integral_constant<std::size_t, 2>{}, i), i += 2;
  if (n - i >= 1) run(std::integral_constant<std::size_t, 1>{}, i);
}

// R1-HASH-004's loop for L sponges in lockstep: `blocks` full 56-byte blocks of each data[k]
// absorbed into st[k], the states permuted after each block (so canonical when blocks > 0;
// untouched when blocks = 0, as for inputs shorter than one block).
template <std::size_t L>
void absorb_blocks(State* st, const std::uint8_t* const* data, std::size_t blocks);

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
