// Choosing r_0 (tau_0) from the data: the target, the radius ladder and the bisection, serial or
// with speculative evaluations on several workers (R1-HIER-030..033, R1-HIER-070).
#include "radius_search.hpp"

#include <algorithm>
#include <limits>
#include <map>
#include <optional>
#include <utility>
#include <vector>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

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

RadiusChoice choose_radius(const Items& particles, KdTree& tree0, const ProgressFn& progress, bool parallel) {
  const std::uint64_t target = top_target(particles.size());
  const std::int64_t diameter = diameter_bound(particles.pos);
  // At most the final check at rho_512, nine bisection steps and one rebuild of the answer.
  constexpr std::uint64_t kMaxEvaluations = 11;
  RadiusChoice out;
  // Results by ladder step: the levels when rho_j passes, std::nullopt when it fails.
  std::map<std::uint32_t, std::optional<std::array<Level, kLevels>>> known;
  const Neighbours neighbours = Neighbours::of(tree0, parallel);
  // A step whose level-0 bound already fails is known without a build (R1-HIER-071).
  auto known_cheaply = [&](std::uint32_t step) {
    if (known.count(step)) return true;
    if (!surely_fails(particles.size(), ladder_radius(diameter, step), target, neighbours)) return false;
    known[step] = std::nullopt;
    return true;
  };
  // The step the bisection builds next in [lo, hi], given what is known: the steps known cheaply
  // on the way are settled.
  auto next_build = [&](std::uint32_t lo, std::uint32_t hi) -> std::optional<std::uint32_t> {
    while (hi - lo > 1) {
      const std::uint32_t mid = (lo + hi) / 2;
      if (!known_cheaply(mid)) return mid;
      (known[mid] ? lo : hi) = mid;
    }
    return std::nullopt;
  };
  // With `parallel` and at least four workers, each round builds the step the bisection needs now
  // and the ones it builds next if that one fails and if it passes, each on its own copy of
  // tree0. (On fewer workers the parallel leader loop of each build already keeps them busy:
  // measured, two builds at once on two cores take longer than one after the other.) Which steps
  // are built changes how long the search takes, never the path it walks or its answer.
  const int workers = parallel && tbb::this_task_arena::max_concurrency() >= 4 ? 3 : 1;
  std::vector<KdTree> trees;
  auto build = [&](std::uint32_t step, std::optional<std::uint32_t> on_fail, std::optional<std::uint32_t> on_pass) {
    std::vector<std::uint32_t> steps{step};
    if (workers >= 2 && on_fail) steps.push_back(*on_fail);
    if (workers >= 3 && on_pass) steps.push_back(*on_pass);
    if (steps.size() == 1) {
      known[step] = cluster_levels(particles, tree0, ladder_radius(diameter, step), target, &neighbours, parallel);
    } else {
      while (trees.size() < steps.size() - 1) trees.push_back(tree0);
      std::vector<std::optional<std::array<Level, kLevels>>> got(steps.size());
      tbb::parallel_for(std::size_t{0}, steps.size(), [&](std::size_t i) {
        KdTree& tree = i == 0 ? tree0 : trees[i - 1];
        got[i] = cluster_levels(particles, tree, ladder_radius(diameter, steps[i]), target, &neighbours, parallel);
      });
      for (std::size_t i = 0; i < steps.size(); ++i) known[steps[i]] = std::move(got[i]);
    }
    out.evaluations += static_cast<std::uint32_t>(steps.size());
    report(progress, "hierarchy", std::min<std::uint64_t>(out.evaluations, kMaxEvaluations - 1), kMaxEvaluations);
  };

  // R1-HIER-032: r0 = 0 when merging only coincident items already meets the target.
  if (!known_cheaply(kLadderSteps)) {
    const auto on_fail = workers >= 2 ? next_build(0, kLadderSteps) : std::nullopt;
    build(kLadderSteps, on_fail, std::nullopt);
  }
  if (known[kLadderSteps]) {
    out.radius0_raw = 0;
    out.levels = std::move(*known[kLadderSteps]);
    report(progress, "hierarchy", kMaxEvaluations, kMaxEvaluations);
    return out;
  }
  std::uint32_t lo = 0, hi = kLadderSteps;
  while (hi - lo > 1) {
    const std::uint32_t mid = (lo + hi) / 2;
    if (!known_cheaply(mid)) {
      const auto on_fail = workers >= 2 ? next_build(lo, mid) : std::nullopt;
      const auto on_pass = workers >= 3 ? next_build(mid, hi) : std::nullopt;
      build(mid, on_fail, on_pass);
    }
    (known[mid] ? lo : hi) = mid;
  }
  out.radius0_raw = ladder_radius(diameter, lo);
  auto found = known.find(lo);
  if (found != known.end() && found->second) {
    out.levels = std::move(*found->second);
  } else {
    // rho_0 = D passes by construction (R1-HIER-031), so no limit is needed for it.
    out.levels = std::move(
        *cluster_levels(particles, tree0, out.radius0_raw, std::numeric_limits<std::uint64_t>::max(), &neighbours, parallel));
    ++out.evaluations;
  }
  report(progress, "hierarchy", kMaxEvaluations, kMaxEvaluations);
  return out;
}

}  // namespace r1::hier
