// The heat kernel exp(-tau L_rw) as sub-stepped degree-K Chebyshev polynomials in the walk matrix N,
// in Q32 and fp64 (R1-FOC-040..044, R1-FOC-082).
#pragma once

#include <span>
#include <vector>

#include "focus_operators.hpp"
#include "r1/solvers/focus.hpp"

namespace r1::focus {

// out = H(x): `coeff.substeps` sub-steps of sum_k c_k T_k(N) x, every entry rounded once per
// recurrence step and once per sub-step result (R1-FOC-043).
// `scratch`, when given, holds the recurrence's vectors from one call to the next (the focus steps
// call it T(eps) times), so no call allocates and touches fresh pages for them; it changes no bit.
struct HeatScratch {
  std::vector<Q32> t0, t1, t2;
  std::vector<i128> acc;
};
// `walk_of_x`, when given, is N x as OperatorsQ32::walk computes it (the focus step forms it with
// the springs, OperatorsQ32::springs_and_walk): the first sub-step's t_1.
void heat_q32(const OperatorsQ32& ops, const HeatCoefficients& coeff, std::span<const Q32> x, std::vector<Q32>& out,
              HeatScratch* scratch = nullptr, const std::vector<Q32>* walk_of_x = nullptr);
// The same in doubles: t_(k+1) = 2 N t_k - t_(k-1), h = c_0 t_0 + ... + c_K t_K left to right.
void heat_f64(const OperatorsF64& ops, const HeatCoefficients& coeff, std::span<const double> x, std::vector<double>& out);

}  // namespace r1::focus
