// Counter-based randomness (decision 11, R1-NUM-060..062): every random value is a pure function
// of (seed, item, dimension) through Philox4x32-10 (Salmon et al., SC 2011). No generator state,
// so results cannot depend on call order or thread count.
#pragma once

#include <array>
#include <cstdint>

#include "r1/fixedpoint/int128.hpp"

namespace r1::rng {

using Ctr = std::array<std::uint32_t, 4>;
using Key = std::array<std::uint32_t, 2>;

// Philox4x32 with 10 rounds, the Random123 reference parameters.
constexpr Ctr philox4x32_10(Ctr c, Key k) {
  constexpr std::uint32_t M0 = 0xD2511F53u, M1 = 0xCD9E8D57u;
  constexpr std::uint32_t W0 = 0x9E3779B9u, W1 = 0xBB67AE85u;
  for (int r = 0; r < 10; ++r) {
    if (r > 0) {
      k[0] += W0;
      k[1] += W1;
    }
    const std::uint64_t p0 = static_cast<std::uint64_t>(M0) * c[0];
    const std::uint64_t p1 = static_cast<std::uint64_t>(M1) * c[2];
    c = Ctr{static_cast<std::uint32_t>(p1 >> 32) ^ c[1] ^ k[0], static_cast<std::uint32_t>(p1),
            static_cast<std::uint32_t>(p0 >> 32) ^ c[3] ^ k[1], static_cast<std::uint32_t>(p0)};
  }
  return c;
}

// 64 random bits for (seed, item, dim): counter = (item, dim), key = seed.
constexpr std::uint64_t bits(std::uint64_t seed, std::uint64_t item, std::uint64_t dim) {
  const Ctr out = philox4x32_10(Ctr{static_cast<std::uint32_t>(item), static_cast<std::uint32_t>(item >> 32),
                                    static_cast<std::uint32_t>(dim), static_cast<std::uint32_t>(dim >> 32)},
                                Key{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32)});
  return (static_cast<std::uint64_t>(out[1]) << 32) | out[0];
}

// Dimensions used by callers must stay below 2^56: the top byte numbers rejection retries.
inline constexpr std::uint64_t kDimLimit = std::uint64_t{1} << 56;

// A uniform integer in [0, n), n > 0, without bias: Lemire's multiply-shift with rejection;
// retry k draws bits at dimension dim + k * 2^56 (still a pure function of the arguments).
constexpr std::uint64_t uniform_below(std::uint64_t seed, std::uint64_t item, std::uint64_t dim, std::uint64_t n) {
  const std::uint64_t threshold = (0 - n) % n;  // 2^64 mod n
  for (std::uint64_t k = 0;; ++k) {
    const u128 m = static_cast<u128>(bits(seed, item, dim + (k << 56))) * n;
    if (static_cast<std::uint64_t>(m) >= threshold) return static_cast<std::uint64_t>(m >> 64);
  }
}

// A uniform Q32 fraction in [0, 1): the raw value is 32 random bits.
constexpr std::int64_t uniform_q32(std::uint64_t seed, std::uint64_t item, std::uint64_t dim) {
  return static_cast<std::int64_t>(bits(seed, item, dim) >> 32);
}

// A uniform double in [0, 1) with 53 random bits (exact: an integer times 2^-53).
constexpr double uniform_double(std::uint64_t seed, std::uint64_t item, std::uint64_t dim) {
  return static_cast<double>(bits(seed, item, dim) >> 11) * 0x1p-53;
}

}  // namespace r1::rng
