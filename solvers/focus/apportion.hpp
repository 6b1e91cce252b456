// Largest-remainder apportionment into caller-owned buffers, for the per-row transitions and the
// simplex projection (R1-FOC-010, R1-FOC-051).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "r1/fixedpoint/int128.hpp"

namespace r1::focus {

// Reusable buffers, so that apportioning a million short rows allocates once.
struct ApportionScratch {
  std::vector<u128> remainder;
  std::vector<std::uint32_t> order;
};

// out_i = the share of `total` (< 2^63) for weights w (R1-FOC-010); out.size() == w.size() >= 1,
// w.size() < 2^32, and sum w < 2^96 (true for any 2^32 weights below 2^64).
void apportion_into(std::uint64_t total, std::span<const std::uint64_t> w, std::span<std::int64_t> out,
                    ApportionScratch& scratch);

}  // namespace r1::focus
