// Tensor buffers of the 13.1 trait's Clifford calls (spec/backends.md R1-BKD-013,
// R1-FMT-030): u32 n, u32 d, then n x d IEEE doubles row-major, all little-endian.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "r1/spec/status.hpp"

namespace r1::format {

std::vector<std::uint8_t> tensor_bytes(std::uint32_t n, std::uint32_t d, std::span<const double> values);
// ({n, d}, values); an input error when the header and the size disagree.
Result<std::pair<std::array<std::uint32_t, 2>, std::vector<double>>> parse_tensor_bytes(std::span<const std::uint8_t> b);

}  // namespace r1::format
