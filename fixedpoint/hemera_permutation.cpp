// The Hemera permutation, one state or L states in lockstep (R1-HASH-002, R1-HASH-003, R1-HASH-020).
#include <atomic>

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
// formed first and overlaps with the inversion.
template <std::size_t L>
[[gnu::always_inline]] inline void partial_round(State* st, std::size_t r) {
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
    State& s = st[k];
    // Sixteen summands below 2^64: the 128-bit sum stays below 2^68 and folds once. Each
    // d_i x_i + sum stays below 2^128: (2^64 - 1)^2 + 2^64 - 1 < 2^128.
    const u64 sum = lazy::fold(rest[k] + x[k]);
    s[0] = lazy::reduce(static_cast<u128>(kInternalDiag[0]) * x[k] + sum);
    for (std::size_t i = 1; i < WIDTH; ++i) s[i] = lazy::reduce(static_cast<u128>(kInternalDiag[i]) * s[i] + sum);
  }
}

std::atomic<std::uint64_t> g_lane_batches{0};
std::atomic<bool> g_batching{true};

}  // namespace

template <std::size_t L>
void permute_lanes(State* st) {
  if constexpr (L > 1) g_lane_batches.fetch_add(1, std::memory_order_relaxed);
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

}  // namespace r1::hemera
