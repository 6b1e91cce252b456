// The Hemera permutation, one state or L states in lockstep (R1-HASH-002, R1-HASH-003, R1-HASH-020),
// its rounds on AVX-512 where the CPU has it (R1-HASH-023).
#include <atomic>

#if defined(__x86_64__)
#define R1_HEMERA_AVX512 1
#include <immintrin.h>
#else
#define R1_HEMERA_AVX512 0
#endif

#include "hemera_constants.inc"
#include "hemera_internal.hpp"

namespace r1::hemera {

namespace detail {

namespace {

using lazy::u64;

constexpr bool all_canonical(const auto& table) {
  for (const u64 c : table)
    if (c >= gl::P) return false;
  return true;
}
// lazy::add_canonical needs canonical round constants; the published table has only such values.
static_assert(all_canonical(kRoundFull) && all_canonical(kRoundPartial));

// External matrix circ(2 M4, M4, M4, M4): M4 on each group of four, then each element gains the
// sum of the elements in its position (i mod 4) over the four groups. Computed exactly in 128
// bits: each output is at most 35 inputs (M4 row sum 7, times 2 + 1 + 1 + 1), below 2^70, and is
// folded once.
[[gnu::always_inline]] inline void external(State& s) {
  u128 t[WIDTH];
  for (std::size_t g = 0; g < 4; ++g) {
    const u128 a = s[4 * g], b = s[4 * g + 1], c = s[4 * g + 2], d = s[4 * g + 3];
    // M4 rows: [2 3 1 1], [1 2 3 1], [1 1 2 3], [3 1 1 2]
    const u128 sum = (a + b) + (c + d);
    t[4 * g + 0] = sum + a + (b + b);  // 2a + 3b + c + d
    t[4 * g + 1] = sum + b + (c + c);  // a + 2b + 3c + d
    t[4 * g + 2] = sum + c + (d + d);  // a + b + 2c + 3d
    t[4 * g + 3] = sum + d + (a + a);  // 3a + b + c + 2d
  }
  for (std::size_t j = 0; j < 4; ++j) {
    const u128 col = (t[j] + t[4 + j]) + (t[8 + j] + t[12 + j]);
    for (std::size_t g = 0; g < 4; ++g) s[4 * g + j] = lazy::fold(t[4 * g + j] + col);
  }
}

// Add the round's constants, x -> x^7 on all sixteen elements, external matrix.
[[gnu::always_inline]] inline void full_round(State& s, std::size_t r) {
  for (std::size_t i = 0; i < WIDTH; ++i) {
    const u64 x = lazy::add_canonical(s[i], kRoundFull[WIDTH * r + i]);
    const u64 x2 = lazy::mul(x, x);
    const u64 x3 = lazy::mul(x2, x);
    const u64 x4 = lazy::mul(x2, x2);
    s[i] = lazy::mul(x3, x4);
  }
  external(s);
}

// One partial round on L lanes: constant and x^(p-2) on element 0, then the internal matrix
// x'_i = d_i x_i + sum_j x_j. The sum of elements 1..15 does not depend on the S-box, so it is
// formed first and overlaps with the inversion. The S-box part: element 0 of each lane's state
// becomes x^(p-2) and sum[k] the lane's sum of all sixteen elements after it (folded: sixteen
// summands below 2^64 stay below 2^68).
template <std::size_t L>
[[gnu::always_inline]] inline void partial_sbox(State* st, std::size_t r, u64 (&sum)[L]) {
  u64 x[L];
  u128 rest[L];
  for (std::size_t k = 0; k < L; ++k) {
    x[k] = lazy::add_canonical(st[k][0], kRoundPartial[r]);
    u128 acc = 0;
    for (std::size_t i = 1; i < WIDTH; ++i) acc += st[k][i];
    rest[k] = acc;
  }
  if constexpr (L == 1) {
    x[0] = lazy::pow_p_minus_2(x[0]);  // maps 0 to 0 by itself: no batch, nothing to mask
  } else {
    lazy::invert_lanes<L>(x);
  }
  for (std::size_t k = 0; k < L; ++k) {
    st[k][0] = x[k];
    sum[k] = lazy::fold(rest[k] + x[k]);
  }
}

template <std::size_t L>
[[gnu::always_inline]] inline void partial_round(State* st, std::size_t r) {
  u64 sum[L];
  partial_sbox<L>(st, r, sum);
  // Each d_i x_i + sum stays below 2^128: (2^64 - 1)^2 + 2^64 - 1 < 2^128.
  for (std::size_t k = 0; k < L; ++k)
    for (std::size_t i = 0; i < WIDTH; ++i) st[k][i] = lazy::reduce(static_cast<u128>(kInternalDiag[i]) * st[k][i] + sum[k]);
}

#if R1_HEMERA_AVX512
// The same rounds with eight elements of a state per AVX-512 vector (R1-HASH-023): every
// multiplication is lazy::mul's, lane by lane (the 128-bit product from four 32-bit products,
// then lazy::reduce's steps with masks for its carry and borrow), so every value, representative
// included, is the scalar rounds'.
// GCC 12 reports the shift builtins' undefined pass-through operand inside avx512fintrin.h as
// uninitialized (a false positive: every lane of these shifts is defined). Clang has no such
// warning group.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
namespace avx {

#define R1_AVX512 __attribute__((target("avx512f"), always_inline)) inline

R1_AVX512 __m512i splat(u64 v) { return _mm512_set1_epi64(static_cast<long long>(v)); }

// lazy::reduce of the 128-bit value hi 2^64 + lo.
R1_AVX512 __m512i reduce(__m512i lo, __m512i hi) {
  const __m512i eps = splat(gl::EPSILON);
  const __m512i hh = _mm512_srli_epi64(hi, 32), hl = _mm512_and_si512(hi, eps);
  const __mmask8 borrow = _mm512_cmplt_epu64_mask(lo, hh);
  __m512i t0 = _mm512_sub_epi64(lo, hh);
  t0 = _mm512_mask_sub_epi64(t0, borrow, t0, eps);
  const __m512i t1 = _mm512_sub_epi64(_mm512_slli_epi64(hl, 32), hl);  // hl EPSILON
  const __m512i t2 = _mm512_add_epi64(t0, t1);
  return _mm512_mask_add_epi64(t2, _mm512_cmplt_epu64_mask(t2, t1), t2, eps);
}

// The 128-bit products a b as (lo, hi).
R1_AVX512 void product(__m512i a, __m512i b, __m512i& lo, __m512i& hi) {
  const __m512i ah = _mm512_srli_epi64(a, 32), bh = _mm512_srli_epi64(b, 32);
  const __m512i p00 = _mm512_mul_epu32(a, b), p01 = _mm512_mul_epu32(a, bh);
  const __m512i p10 = _mm512_mul_epu32(ah, b), p11 = _mm512_mul_epu32(ah, bh);
  const __m512i mid = _mm512_add_epi64(p01, p10);
  const __mmask8 mid_carry = _mm512_cmplt_epu64_mask(mid, p01);  // worth 2^96
  lo = _mm512_add_epi64(p00, _mm512_slli_epi64(mid, 32));
  const __mmask8 lo_carry = _mm512_cmplt_epu64_mask(lo, p00);
  hi = _mm512_add_epi64(p11, _mm512_srli_epi64(mid, 32));
  hi = _mm512_mask_add_epi64(hi, lo_carry, hi, splat(1));
  hi = _mm512_mask_add_epi64(hi, mid_carry, hi, splat(std::uint64_t{1} << 32));
}

R1_AVX512 __m512i mul(__m512i a, __m512i b) {
  __m512i lo, hi;
  product(a, b, lo, hi);
  return reduce(lo, hi);
}

R1_AVX512 __m512i add_canonical(__m512i a, __m512i c) {
  const __m512i s = _mm512_add_epi64(a, c);
  return _mm512_mask_add_epi64(s, _mm512_cmplt_epu64_mask(s, c), s, splat(gl::EPSILON));
}

R1_AVX512 void full_round(State& s, std::size_t r) {
  for (std::size_t h = 0; h < WIDTH; h += 8) {
    const __m512i x = add_canonical(_mm512_loadu_si512(s.data() + h), _mm512_loadu_si512(kRoundFull.data() + WIDTH * r + h));
    const __m512i x2 = mul(x, x);
    _mm512_storeu_si512(s.data() + h, mul(mul(x2, x), mul(x2, x2)));
  }
  external(s);
}

template <std::size_t L>
R1_AVX512 void partial_round(State* st, std::size_t r) {
  u64 sum[L];
  partial_sbox<L>(st, r, sum);
  for (std::size_t k = 0; k < L; ++k) {
    const __m512i add = splat(sum[k]);
    for (std::size_t h = 0; h < WIDTH; h += 8) {
      __m512i lo, hi;
      product(_mm512_loadu_si512(kInternalDiag.data() + h), _mm512_loadu_si512(st[k].data() + h), lo, hi);
      lo = _mm512_add_epi64(lo, add);
      hi = _mm512_mask_add_epi64(hi, _mm512_cmplt_epu64_mask(lo, add), hi, splat(1));
      _mm512_storeu_si512(st[k].data() + h, reduce(lo, hi));
    }
  }
}

// Element-major rounds (R1-HASH-023): vector i holds element i of eight states, so the external
// matrix and the partial rounds' sums are vector additions, and a partial round's S-box inputs of
// all lanes sit side by side for the shared inversion. Values are any 64-bit representatives of
// their residues, not the scalar rounds' representatives; every state leaves canonical, so the
// output is the same.

// A sum of a few 64-bit values kept as the sums of their 32-bit halves: value = lo + hi 2^32.
// Up to 64 summands below 2^32 each stay below 2^38 in a 64-bit lane, so no addition carries.
struct Halves {
  __m512i lo, hi;
};

R1_AVX512 Halves halves(__m512i x) { return {_mm512_and_si512(x, splat(0xFFFFFFFFull)), _mm512_srli_epi64(x, 32)}; }

R1_AVX512 Halves operator+(Halves a, Halves b) { return {_mm512_add_epi64(a.lo, b.lo), _mm512_add_epi64(a.hi, b.hi)}; }

// lo + hi 2^32 (lo, hi < 2^38) to a representative below 2^64: hi 2^32 = (hi mod 2^32) 2^32 +
// (hi >> 32) 2^64, and 2^64 = EPSILON. Each of the two additions may carry once; the wrapped sum
// is then below 2^38, so adding the EPSILON the carry is worth cannot carry again.
R1_AVX512 __m512i combine(Halves v) {
  const __m512i eps = splat(gl::EPSILON);
  const __m512i shifted = _mm512_slli_epi64(v.hi, 32);
  __m512i x = _mm512_add_epi64(v.lo, shifted);
  x = _mm512_mask_add_epi64(x, _mm512_cmplt_epu64_mask(x, shifted), x, eps);
  const __m512i top = _mm512_srli_epi64(v.hi, 32);
  const __m512i t = _mm512_sub_epi64(_mm512_slli_epi64(top, 32), top);  // top EPSILON < 2^38
  const __m512i y = _mm512_add_epi64(x, t);
  return _mm512_mask_add_epi64(y, _mm512_cmplt_epu64_mask(y, t), y, eps);
}

// The external matrix on the sixteen element vectors: each output sums at most 35 inputs.
R1_AVX512 void external_soa(__m512i* s) {
  Halves t[WIDTH];
  for (std::size_t g = 0; g < 4; ++g) {
    const Halves a = halves(s[4 * g]), b = halves(s[4 * g + 1]), c = halves(s[4 * g + 2]), d = halves(s[4 * g + 3]);
    const Halves sum = (a + b) + (c + d);
    t[4 * g + 0] = sum + a + (b + b);  // 2a + 3b + c + d
    t[4 * g + 1] = sum + b + (c + c);  // a + 2b + 3c + d
    t[4 * g + 2] = sum + c + (d + d);  // a + b + 2c + 3d
    t[4 * g + 3] = sum + d + (a + a);  // 3a + b + c + 2d
  }
  for (std::size_t j = 0; j < 4; ++j) {
    const Halves col = (t[j] + t[4 + j]) + (t[8 + j] + t[12 + j]);
    for (std::size_t g = 0; g < 4; ++g) s[4 * g + j] = combine(t[4 * g + j] + col);
  }
}

R1_AVX512 void full_round_soa(__m512i* s, std::size_t r) {
  for (std::size_t i = 0; i < WIDTH; ++i) {
    const __m512i x = add_canonical(s[i], splat(kRoundFull[WIDTH * r + i]));
    const __m512i x2 = mul(x, x);
    s[i] = mul(mul(x2, x), mul(x2, x2));
  }
  external_soa(s);
}

// One partial round on V groups of eight states: the S-box inputs of all 8 V lanes are inverted
// together (lazy::invert_chains in two interleaved chains: at 64 lanes four chains measured 3%
// slower, eight 10%), after each group's sum of elements 1..15 is formed.
template <std::size_t V>
R1_AVX512 void partial_round_soa(__m512i (*s)[WIDTH], std::size_t r) {
  constexpr std::size_t C = V < 2 ? V : 2;
  alignas(64) u64 x[8 * V];
  Halves rest[V];
  const __m512i c = splat(kRoundPartial[r]);
  for (std::size_t g = 0; g < V; ++g) {
    _mm512_store_si512(x + 8 * g, add_canonical(s[g][0], c));
    Halves acc = halves(s[g][1]);
    for (std::size_t i = 2; i < WIDTH; ++i) acc = acc + halves(s[g][i]);
    rest[g] = acc;
  }
  lazy::invert_chains<C, 8 * V / C>(x);
  for (std::size_t g = 0; g < V; ++g) {
    const __m512i inv = _mm512_load_si512(x + 8 * g);
    const __m512i sum = combine(rest[g] + halves(inv));  // sixteen summands
    s[g][0] = inv;
    for (std::size_t i = 0; i < WIDTH; ++i) {
      // d_i x_i + sum < 2^128: the product's high word is at most 2^64 - 2.
      __m512i lo, hi;
      product(splat(kInternalDiag[i]), s[g][i], lo, hi);
      lo = _mm512_add_epi64(lo, sum);
      hi = _mm512_mask_add_epi64(hi, _mm512_cmplt_epu64_mask(lo, sum), hi, splat(1));
      s[g][i] = reduce(lo, hi);
    }
  }
}

#undef R1_AVX512

}  // namespace avx

template <std::size_t L>
__attribute__((target("avx512f"))) void permute_avx512(State* st) {
  for (std::size_t k = 0; k < L; ++k) external(st[k]);
  for (std::size_t r = 0; r < 4; ++r)
    for (std::size_t k = 0; k < L; ++k) avx::full_round(st[k], r);
  for (std::size_t r = 0; r < 16; ++r) avx::partial_round<L>(st, r);
  for (std::size_t r = 4; r < 8; ++r)
    for (std::size_t k = 0; k < L; ++k) avx::full_round(st[k], r);
  for (std::size_t k = 0; k < L; ++k)
    for (std::size_t i = 0; i < WIDTH; ++i) st[k][i] = gl::canonical(st[k][i]);
}

// The rounds of R1-HASH-002 on V groups of eight element-major states.
template <std::size_t V>
__attribute__((target("avx512f"), always_inline)) inline void rounds_soa(__m512i (*s)[WIDTH]) {
  for (std::size_t g = 0; g < V; ++g) avx::external_soa(s[g]);
  for (std::size_t r = 0; r < 4; ++r)
    for (std::size_t g = 0; g < V; ++g) avx::full_round_soa(s[g], r);
  for (std::size_t r = 0; r < 16; ++r) avx::partial_round_soa<V>(s, r);
  for (std::size_t r = 4; r < 8; ++r)
    for (std::size_t g = 0; g < V; ++g) avx::full_round_soa(s[g], r);
}

static_assert(sizeof(State) == WIDTH * sizeof(u64), "states are laid out back to back");

// Element i of states 8 g .. 8 g + 7 as one vector, and back (made canonical).
__attribute__((target("avx512f"), always_inline)) inline __m512i state_index() {
  return _mm512_setr_epi64(0, 16, 32, 48, 64, 80, 96, 112);
}

template <std::size_t V>
__attribute__((target("avx512f"), always_inline)) inline void load_soa(const State* st, __m512i (*s)[WIDTH]) {
  for (std::size_t g = 0; g < V; ++g)
    for (std::size_t i = 0; i < WIDTH; ++i) s[g][i] = _mm512_i64gather_epi64(state_index(), st[8 * g].data() + i, 8);
}

template <std::size_t V>
__attribute__((target("avx512f"), always_inline)) inline void store_soa(__m512i (*s)[WIDTH], State* st) {
  const __m512i p = avx::splat(gl::P), eps = avx::splat(gl::EPSILON);
  for (std::size_t g = 0; g < V; ++g)
    for (std::size_t i = 0; i < WIDTH; ++i) {
      const __m512i v = s[g][i];
      const __m512i canon = _mm512_mask_add_epi64(v, _mm512_cmpge_epu64_mask(v, p), v, eps);  // v - p
      _mm512_i64scatter_epi64(st[8 * g].data() + i, state_index(), canon, 8);
    }
}

template <std::size_t V>
__attribute__((target("avx512f"))) void permute_soa(State* st) {
  __m512i s[V][WIDTH];
  load_soa<V>(st, s);
  rounds_soa<V>(s);
  store_soa<V>(s, st);
}

// R1-HASH-004 for 8 V sponges at once: `blocks` full blocks of each input absorbed and permuted,
// the states element-major from the first block to the last. Rate element i of a block is bytes
// 7 i .. 7 i + 6, read as the 8-byte word at 7 i - 1 shifted down by a byte (at 0 for element 0,
// masked to 56 bits), so no read leaves the block.
template <std::size_t V>
__attribute__((target("avx512f"))) void absorb_soa(State* st, const std::uint8_t* const* data, std::size_t blocks) {
  __m512i s[V][WIDTH];
  __m512i base[V];
  for (std::size_t g = 0; g < V; ++g) base[g] = _mm512_loadu_si512(data + 8 * g);  // the lanes' addresses
  load_soa<V>(st, s);
  const __m512i low56 = avx::splat((std::uint64_t{1} << 56) - 1);
  for (std::size_t b = 0; b < blocks; ++b) {
    for (std::size_t g = 0; g < V; ++g) {
      const __m512i block = _mm512_add_epi64(base[g], avx::splat(b * RATE_BYTES));
      for (std::size_t i = 0; i < RATE; ++i) {
        const __m512i at = _mm512_add_epi64(block, avx::splat(i == 0 ? 0 : 7 * i - 1));
        const __m512i word = _mm512_i64gather_epi64(at, nullptr, 1);
        const __m512i chunk = i == 0 ? _mm512_and_si512(word, low56) : _mm512_srli_epi64(word, 8);
        s[g][i] = avx::add_canonical(s[g][i], chunk);  // chunk < 2^56 < p
      }
    }
    rounds_soa<V>(s);
  }
  store_soa<V>(s, st);
}

#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif

bool cpu_has_avx512() {
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx512f");
}
#else
bool cpu_has_avx512() { return false; }
#endif

std::atomic<std::uint64_t> g_lane_batches{0};
std::atomic<bool> g_batching{true};
// Asked on first use, not in a static initialiser: code that hashes while another translation
// unit's statics are initialised (a benchmark's registration reading an epoch) must not find it
// still false, which would run the scalar rounds.
bool has_avx512() {
  static const bool has = cpu_has_avx512();
  return has;
}
std::atomic<bool> g_vector{true};

}  // namespace

template <std::size_t L>
void permute_lanes(State* st) {
  if constexpr (L > 1) g_lane_batches.fetch_add(1, std::memory_order_relaxed);
#if R1_HEMERA_AVX512
  if (has_avx512() && g_vector.load(std::memory_order_relaxed)) {
    if constexpr (L % 8 == 0) return permute_soa<L / 8>(st);
    else return permute_avx512<L>(st);
  }
#endif
  // Inputs may be any 64-bit words: every lazy operation accepts any representative.
  for (std::size_t k = 0; k < L; ++k) external(st[k]);
  for (std::size_t r = 0; r < 4; ++r)
    for (std::size_t k = 0; k < L; ++k) full_round(st[k], r);
  for (std::size_t r = 0; r < 16; ++r) partial_round<L>(st, r);
  for (std::size_t r = 4; r < 8; ++r)
    for (std::size_t k = 0; k < L; ++k) full_round(st[k], r);
  // Lazy values are below 2^64 < 2p: one conditional subtraction makes them canonical.
  for (std::size_t k = 0; k < L; ++k)
    for (std::size_t i = 0; i < WIDTH; ++i) st[k][i] = gl::canonical(st[k][i]);
}

template void permute_lanes<1>(State*);
template void permute_lanes<2>(State*);
template void permute_lanes<4>(State*);
template void permute_lanes<8>(State*);
template void permute_lanes<16>(State*);
template void permute_lanes<32>(State*);
template void permute_lanes<64>(State*);

template <std::size_t L>
void absorb_blocks(State* st, const std::uint8_t* const* data, std::size_t blocks) {
#if R1_HEMERA_AVX512
  if constexpr (L % 8 == 0) {
    if (blocks > 0 && has_avx512() && g_vector.load(std::memory_order_relaxed)) {
      g_lane_batches.fetch_add(1, std::memory_order_relaxed);
      return absorb_soa<L / 8>(st, data, blocks);
    }
  }
#endif
  for (std::size_t b = 0; b < blocks; ++b) {
    for (std::size_t k = 0; k < L; ++k) absorb_rate(st[k], data[k] + b * RATE_BYTES);
    permute_lanes<L>(st);
  }
}

template void absorb_blocks<1>(State*, const std::uint8_t* const*, std::size_t);
template void absorb_blocks<2>(State*, const std::uint8_t* const*, std::size_t);
template void absorb_blocks<4>(State*, const std::uint8_t* const*, std::size_t);
template void absorb_blocks<8>(State*, const std::uint8_t* const*, std::size_t);
template void absorb_blocks<16>(State*, const std::uint8_t* const*, std::size_t);
template void absorb_blocks<32>(State*, const std::uint8_t* const*, std::size_t);
template void absorb_blocks<64>(State*, const std::uint8_t* const*, std::size_t);

void permute_states(State* st, std::size_t n) {
  split_lanes(n, g_batching.load(std::memory_order_relaxed),
              [&](auto lanes, std::size_t first) { permute_lanes<decltype(lanes)::value>(st + first); });
}

std::uint64_t lane_batches() { return g_lane_batches.load(std::memory_order_relaxed); }

}  // namespace detail

void permute(State& s) { detail::permute_lanes<1>(&s); }

void permute_many(std::span<State> states) { detail::permute_states(states.data(), states.size()); }

void set_lane_batching(bool on) { detail::g_batching.store(on, std::memory_order_relaxed); }

bool lane_batching() { return detail::g_batching.load(std::memory_order_relaxed); }

void set_vector_rounds(bool on) { detail::g_vector.store(on, std::memory_order_relaxed); }

bool vector_rounds() { return detail::has_avx512() && detail::g_vector.load(std::memory_order_relaxed); }

}  // namespace r1::hemera
