// The deflated vector D^(1/2) 1 as exact Q32-family raws at any scale (R1-SPEC-006, R1-SPEC-011).
#pragma once

#include <vector>

#include "r1/fixedpoint/q32.hpp"
#include "r1/spec/graph.hpp"

namespace r1::spectral {

// t_i raw = the integer nearest to sqrt(2^(2 frac + e) D_i / sum_j D_j) (ties to even), D = degree
// + rho: D^(1/2) 1 with squared length 2^e, in units of 2^-frac. 2 frac + e <= 120.
std::vector<fx::Q32> scaled_trivial(const Graph& g, fx::Q32 rho, int e, int frac);

}  // namespace r1::spectral
