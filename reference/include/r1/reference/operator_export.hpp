// The spectral operator's Matrix Market export (R1-SPEC-070): file output, so it lives with the
// reference's writers rather than in the solver.
#pragma once

#include <string>

#include "r1/solvers/spectral.hpp"
#include "r1/spec/status.hpp"

namespace r1 {

// Writes the sparse part I - M of the operator as Matrix Market "coordinate real symmetric"
// (lower triangle, 1-based, values with 17 significant digits, which reproduce every double and
// so every Q32 entry exactly), atomically (R1-ERR-003). When rho > 0, comment lines
// "%r1-rank-one i g_i" (1-based) carry g, and the operator is that matrix minus g g^T
// (R1-SPEC-070).
template <class Scalar>
Status write_operator_matrix_market(const SpectralOperator<Scalar>& op, const std::string& path);

}  // namespace r1
