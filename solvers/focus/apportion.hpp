// Largest-remainder apportionment into caller-owned buffers, for the per-row transitions and the
// simplex projection (R1-FOC-010, R1-FOC-051).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "r1/fixedpoint/int128.hpp"
#include "r1/fixedpoint/q32.hpp"

namespace r1::focus {

// Reusable buffers, so that apportioning a million short rows allocates once.
struct ApportionScratch {
  std::vector<u128> remainder;
  std::vector<std::uint32_t> order;
  std::vector<std::uint64_t> rem64;    // the fast path's remainders (sum below 2^64)
  std::vector<std::uint16_t> bucket_of;  // each remainder's bucket
  std::vector<std::uint32_t> buckets;    // and the 2^16 bucket counts
};

// out_i = the share of `total` (< 2^63) for weights w (R1-FOC-010); out.size() == w.size() >= 1,
// w.size() < 2^32, and sum w < 2^96 (true for any 2^32 weights below 2^64).
void apportion_into(std::uint64_t total, std::span<const std::uint64_t> w, std::span<std::int64_t> out,
                    ApportionScratch& scratch);
// The same shares by the plain algorithm (exact quotients, nth_element over every remainder):
// what apportion_into does below 4096 weights, and the oracle its fast path is tested against.
void apportion_into_plain(std::uint64_t total, std::span<const std::uint64_t> w, std::span<std::int64_t> out,
                          ApportionScratch& scratch);

// Proj onto `total` raws (R1-FOC-051 with 2^32 replaced by total; R1-INC-051): out_i = 1 +
// apportion(total - n, max(v_i - 1, 0)), so the raws sum to exactly `total` and each is at least
// 1. std::invalid_argument unless 1 <= n <= total <= 2^32 and out has n entries.
void project_onto(std::span<const fx::Q32> v, std::uint64_t total, std::span<fx::Q32> out);

}  // namespace r1::focus
