// Choosing r_0 (tau_0) from the data: the target, the radius ladder and the bisection
// (R1-HIER-030..033).
#include "radius_search.hpp"

#include <algorithm>
#include <limits>
#include <optional>
#include <utility>

#include "r1/fixedpoint/q32.hpp"

namespace r1::hier {

namespace {

// F[b] = round(2^32 * 2^(-b/8)), b = 0..7 (R1-HIER-031): the fractional steps of the ladder as
// Q32 raws, written out so that no elementary-function implementation is part of the rule. A
// test recomputes them with 60-digit arithmetic.
constexpr std::array<std::uint64_t, 8> kLadderFraction = {4294967296u, 3938502376u, 3611622603u, 3311872529u,
                                                          3037000500u, 2784941738u, 2553802834u, 2341847524u};

}  // namespace

std::uint64_t top_target(std::size_t n) {
  // Why 10^4: four levels, each about an order of magnitude coarser (DESIGN decision 8).
  constexpr std::uint64_t kTotalReduction = 10'000;
  return (static_cast<std::uint64_t>(n) + kTotalReduction - 1) / kTotalReduction;
}

std::int64_t diameter_bound(std::span<const Point> points) {
  if (points.empty()) return 0;
  Point lo = points[0], hi = points[0];
  for (const Point& p : points)
    for (std::size_t d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], p[d]);
      hi[d] = std::max(hi[d], p[d]);
    }
  u128 g = 0;
  for (std::size_t d = 0; d < 3; ++d) {
    const auto e = static_cast<u128>(static_cast<std::uint64_t>(hi[d] - lo[d]));  // < 2^61 (R1-HIER-003)
    g += e * e;
  }
  u128 s = fx::detail::isqrt(g);
  if (s * s < g) ++s;  // ceiling: D bounds every pair distance from above
  return static_cast<std::int64_t>(s);  // < 2^61 * sqrt(3) < 2^63
}

std::int64_t ladder_radius(std::int64_t diameter, std::uint32_t j) {
  const u128 scaled = static_cast<u128>(diameter) * kLadderFraction[j % 8];  // < 2^63 * 2^32
  const std::uint32_t shift = 32 + j / 8;
  if (shift >= 128) return 0;
  return static_cast<std::int64_t>(scaled >> shift);  // floor, R1-HIER-031
}

RadiusChoice choose_radius(const Items& particles, KdTree& tree0, const ProgressFn& progress) {
  const std::uint64_t target = top_target(particles.size());
  const std::int64_t diameter = diameter_bound(particles.pos);
  // At most the final check at rho_512, nine bisection steps and one rebuild of the answer.
  constexpr std::uint64_t kMaxEvaluations = 11;
  RadiusChoice out;
  auto evaluate = [&](std::uint32_t j) {
    ++out.evaluations;
    report(progress, "hierarchy", out.evaluations, kMaxEvaluations);
    return cluster_levels(particles, tree0, ladder_radius(diameter, j), target);
  };

  // R1-HIER-032: r0 = 0 when merging only coincident items already meets the target.
  if (auto zero = evaluate(kLadderSteps)) {
    out.radius0_raw = 0;
    out.levels = std::move(*zero);
    return out;
  }
  std::uint32_t lo = 0, hi = kLadderSteps;
  std::optional<std::array<Level, kLevels>> lo_levels;  // the levels of rho_lo once evaluated
  while (hi - lo > 1) {
    const std::uint32_t mid = (lo + hi) / 2;
    if (auto levels = evaluate(mid)) {
      lo = mid;
      lo_levels = std::move(levels);
    } else {
      hi = mid;
    }
  }
  out.radius0_raw = ladder_radius(diameter, lo);
  if (!lo_levels) {
    // rho_0 = D passes by construction (R1-HIER-031), so no limit is needed for it.
    lo_levels = cluster_levels(particles, tree0, out.radius0_raw, std::numeric_limits<std::uint64_t>::max());
    ++out.evaluations;
  }
  out.levels = std::move(*lo_levels);
  report(progress, "hierarchy", kMaxEvaluations, kMaxEvaluations);
  return out;
}

}  // namespace r1::hier
