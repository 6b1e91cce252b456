// Inputs for the spectral kernels' tests (accel/cpu and accel/vulkan against the portable
// kernels): counter-based random panels and combination coefficients, so every kernel suite sees
// the same cases.
#pragma once

#include <cstdint>
#include <vector>

#include "r1/fixedpoint/counter_rng.hpp"
#include "r1/solvers/panel.hpp"

namespace r1::test {

// A panel whose column c has entries of about bits[c] bits (random signs).
inline spectral::Panel<fx::Q32> random_panel(std::size_t n, const std::vector<int>& bits, std::uint64_t seed) {
  spectral::Panel<fx::Q32> p(n, bits.size());
  for (std::size_t c = 0; c < bits.size(); ++c)
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint64_t r = rng::bits(seed, i, c);
      const int b = bits[c];
      const std::int64_t v =
          b >= 63 ? static_cast<std::int64_t>(r) : static_cast<std::int64_t>(r >> (64 - b)) - (std::int64_t{1} << (b - 1));
      p.at(i, c) = fx::Q32::from_raw(v);
    }
  return p;
}

// `count` coefficients for combination case `ci` over the whole allowed range (-8, 8): large ones,
// tiny ones (1e-12) and moderate ones, the first one the range's edge.
inline std::vector<double> combine_coefficients(std::size_t ci, std::size_t count) {
  std::vector<double> coef(count);
  for (std::size_t j = 0; j < count; ++j) {
    const std::uint64_t r = rng::bits(0xc0ef, ci, j);
    const double u = static_cast<double>(static_cast<std::int64_t>(r >> 11) - (std::int64_t{1} << 52)) * 0x1p-52;
    coef[j] = j % 7 == 0 ? u * 7.999999 : (j % 7 == 1 ? u * 1e-12 : u * 0.75);
  }
  if (count > 0) coef[0] = -7.999999999;
  return coef;
}

}  // namespace r1::test
