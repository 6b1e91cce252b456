// Synthetic layouts for the hierarchy tests and benchmark: integer-only (counter RNG), so the
// same points on every machine (R1-HIER-061 tests, R1-TEST-001).
#pragma once

#include <array>
#include <cstdint>
#include <numeric>
#include <vector>

#include "r1/fixedpoint/counter_rng.hpp"
#include "r1/reference/hierarchy.hpp"

namespace r1::hier_test {

enum class Shape { kUniform, kBlobs, kLine, kPlane, kStar, kCoincident, kSpikes };

struct Layout {
  std::vector<std::array<Q32, 3>> pos;
  std::vector<Q32> phi;
  std::vector<Color> color;
  std::vector<ParticleId> ids;
};

inline constexpr std::int64_t kUnit = std::int64_t{1} << 32;  // one scene unit as a Q32 raw

// Q32 raws > 0 summing to exactly 2^32, proportional to the weights (largest remainder, ties to
// the lower index), each at least 1.
inline std::vector<Q32> normalise_phi(const std::vector<std::uint64_t>& w) {
  const std::size_t n = w.size();
  const u128 total = std::accumulate(w.begin(), w.end(), u128{0});
  const u128 spare = static_cast<u128>(kUnit) - n;  // one raw each is reserved
  std::vector<Q32> phi(n);
  std::vector<std::pair<u128, std::size_t>> rem(n);
  u128 given = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const u128 num = static_cast<u128>(w[i]) * spare;
    phi[i].raw = 1 + static_cast<std::int64_t>(num / total);
    given += num / total;
    rem[i] = {num % total, i};
  }
  std::sort(rem.begin(), rem.end(), [](const auto& a, const auto& b) { return a.first != b.first ? a.first > b.first : a.second < b.second; });
  for (std::size_t k = 0; given < spare; ++k, ++given) ++phi[rem[k].second].raw;
  return phi;
}

// Distinct ids: 28 random bytes, then the index (big-endian) so no two can collide.
inline ParticleId make_id(std::uint64_t seed, std::uint64_t i) {
  ParticleId id{};
  for (std::size_t k = 0; k < 28; ++k) id[k] = static_cast<std::uint8_t>(rng::bits(seed, i, 100 + k / 8) >> (8 * (k % 8)));
  for (std::size_t k = 0; k < 4; ++k) id[28 + k] = static_cast<std::uint8_t>(i >> (8 * (3 - k)));
  return id;
}

// Uniform raw in [-half, half) scene units.
inline std::int64_t centred(std::uint64_t seed, std::uint64_t item, std::uint64_t dim, std::int64_t half_units) {
  return static_cast<std::int64_t>(rng::uniform_below(seed, item, dim, static_cast<std::uint64_t>(2 * half_units * kUnit))) -
         half_units * kUnit;
}

// Irwin-Hall(4) - 2 in raw units: about normal, standard deviation 0.577 units, |x| < 2 units.
inline std::int64_t bump(std::uint64_t seed, std::uint64_t item, std::uint64_t dim) {
  std::int64_t s = 0;
  for (std::uint64_t k = 0; k < 4; ++k) s += rng::uniform_q32(seed, item, dim * 4 + k);
  return s - 2 * kUnit;
}

inline Layout make_layout(Shape shape, std::size_t n, std::uint64_t seed) {
  Layout L;
  L.pos.resize(n);
  std::vector<std::uint64_t> w(n);
  L.color.resize(n);
  L.ids.resize(n);
  constexpr std::uint64_t kBlobs = 20, kSpikes = 12;
  for (std::size_t i = 0; i < n; ++i) {
    std::array<std::int64_t, 3> p{};
    for (std::uint64_t d = 0; d < 3; ++d) {
      switch (shape) {
        case Shape::kUniform: p[d] = centred(seed, i, d, 500); break;
        case Shape::kBlobs: {
          const std::uint64_t b = rng::uniform_below(seed, i, 10, kBlobs);
          p[d] = centred(seed + 1, b, d, 450) + 20 * bump(seed, i, d);
          break;
        }
        case Shape::kLine: p[d] = d == 0 ? centred(seed, i, d, 500) : 0; break;
        case Shape::kPlane: p[d] = d < 2 ? centred(seed, i, d, 500) : 0; break;
        case Shape::kStar: p[d] = i == 0 ? 0 : (d == 0 ? 100 * kUnit : 0); break;
        case Shape::kCoincident: p[d] = static_cast<std::int64_t>(d + 1) * kUnit; break;
        case Shape::kSpikes: {
          // Rays from the origin, density growing towards it, like a sparse graph's spectral layout.
          const std::uint64_t s = rng::uniform_below(seed, i, 11, kSpikes);
          const std::int64_t t = rng::uniform_q32(seed, i, 12);  // [0, 1) as a raw
          const std::int64_t t2 = static_cast<std::int64_t>((static_cast<i128>(t) * t) >> 32);
          const std::int64_t dir = centred(seed + 2, s, d, 500);
          p[d] = static_cast<std::int64_t>((static_cast<i128>(dir) * t2) >> 32) + bump(seed, i, d) / 4;
          break;
        }
      }
      L.pos[i][d] = Q32::from_raw(p[d]);
    }
    // Heavy-tailed focus: a few particles carry much of it, many share tiny equal values.
    const std::uint64_t u = rng::uniform_below(seed, i, 13, 1000);
    w[i] = u < 900 ? 1 : u * u;
    static constexpr std::array<Color, 6> kPalette = {
        Color{230, 60, 60}, Color{60, 200, 80}, Color{70, 90, 230}, Color{240, 200, 40}, Color{160, 60, 200}, Color{40, 200, 210}};
    L.color[i] = kPalette[rng::uniform_below(seed, i, 14, kPalette.size())];
    L.ids[i] = make_id(seed, i);
  }
  L.phi = normalise_phi(w);
  return L;
}

}  // namespace r1::hier_test
