// Choosing r_0 (tau_0) from the data: the target, the radius ladder and the bisection
// (R1-HIER-030..033).
#pragma once

#include <array>
#include <cstdint>
#include <span>

#include "levels.hpp"
#include "r1/spec/progress.hpp"

namespace r1::hier {

// Ladder steps: j = 0 .. kLadderSteps, ratio 2^(1/8) per step (R1-HIER-031).
inline constexpr std::uint32_t kLadderSteps = 512;

// T = ceil(n / 10^4): four levels of about ten-fold reduction each (R1-HIER-030).
std::uint64_t top_target(std::size_t n);

// D = ceil(sqrt(sum_d (hi_d - lo_d)^2)) over the points' bounding box (R1-HIER-031).
std::int64_t diameter_bound(std::span<const Point> points);

// rho_j = floor(D * F[j mod 8] / 2^(32 + floor(j / 8))) (R1-HIER-031).
std::int64_t ladder_radius(std::int64_t diameter, std::uint32_t j);

struct RadiusChoice {
  std::int64_t radius0_raw = 0;
  std::array<Level, kLevels> levels;  // built with radius0_raw
  std::uint32_t evaluations = 0;      // radii evaluated (the final one included when it was not cached;
                                      // with `parallel`, speculative ones too)
};

// The bisection of R1-HIER-032 over `particles` (tree0 built over their positions). With
// `parallel`, radii the bisection may ask for next are evaluated beside the one it asks for now,
// on TBB workers; it then walks the same path to the same radius (R1-HIER-070).
RadiusChoice choose_radius(const Items& particles, KdTree& tree0, const ProgressFn& progress, bool parallel = false);

}  // namespace r1::hier
