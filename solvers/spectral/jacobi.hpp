// Cyclic Jacobi eigensolver for small dense symmetric matrices in fp64 (R1-SPEC-040..042): fixed
// sweep order, fixed stopping rule, plain IEEE + - * / sqrt, so its output is the same bits on
// every machine.
#pragma once

#include <cstddef>
#include <vector>

namespace r1::spectral {

struct JacobiResult {
  std::vector<double> values;   // ascending; equal values keep their diagonal order
  std::vector<double> vectors;  // m x m row-major: column c is the unit eigenvector of values[c]
  int sweeps = 0;               // sweeps run
};

// Eigen-decomposition of the symmetric m x m matrix `a` (row-major; only the upper triangle is
// read). Sweeps visit (p, q), p < q, row by row; a sweep starts only while the off-diagonal
// mass exceeds 2^-106 of the Frobenius mass, at most kJacobiMaxSweeps sweeps.
JacobiResult jacobi_eigen(std::size_t m, std::vector<double> a);

// Jacobi converges quadratically: 6 to 10 sweeps reach the stopping rule for the matrices the
// solver builds; the cap only bounds pathological input.
inline constexpr int kJacobiMaxSweeps = 64;

}  // namespace r1::spectral
