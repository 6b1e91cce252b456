// Thick-restart Lanczos with full re-orthogonalisation, locking and a fresh-start check for
// missed multiplicities (R1-SPEC-020..035), templated over the numeric domain.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "r1/reference/spectral.hpp"
#include "r1/spec/progress.hpp"
#include "vector_kernels.hpp"

namespace r1::spectral {

struct LanczosConfig {
  std::uint32_t want = 5;      // eigenpairs above the deflated trivial one
  std::uint32_t basis = 32;    // m: Lanczos vectors per cycle (R1-SPEC-021)
  std::uint32_t keep = 12;     // Ritz vectors kept at a thick restart (R1-SPEC-026)
  double tolerance = 1e-9;     // residual target (R1-SPEC-028)
  std::uint32_t max_cycles = 1000;
  std::uint64_t seed = 0;      // counter-RNG key of start and fresh vectors (R1-SPEC-030)
};

template <class Scalar>
struct Eigenpair {
  std::vector<Scalar> x;  // scaled: <x, x> = 1 up to rounding (R1-SPEC-011)
  double lambda = 0;      // Rayleigh quotient <x, L x> / <x, x>
  double residual = 0;    // ||L x - lambda x|| / ||x||
};

template <class Scalar>
struct LanczosOutcome {
  std::vector<Eigenpair<Scalar>> pairs;  // ascending lambda, `want` of them
  std::uint32_t cycles = 0, matvecs = 0;
  bool converged = false;
};

// The exact Rayleigh quotient and residual of x (R1-SPEC-061), using y and r as scratch.
template <class Scalar>
void rayleigh(const SpectralOperator<Scalar>& op, const VectorOps<Scalar>& ops, std::span<const Scalar> x,
              std::vector<Scalar>& y, std::vector<Scalar>& r, double& lambda, double& residual);

template <class Scalar>
LanczosOutcome<Scalar> thick_restart_lanczos(const SpectralOperator<Scalar>& op, const VectorOps<Scalar>& ops,
                                             const LanczosConfig& config, const ProgressFn& progress);

// A Lanczos coefficient below this is a breakdown (an invariant subspace): w is dropped and the
// next vector is a fresh random one (R1-SPEC-024). Dropping w perturbs the Lanczos relation by
// beta, which then floors every Ritz residual, so the threshold must sit below the residual
// tolerances in use (1e-9 by default) and near the Q32 rounding level: 2^-36 (1.5e-11). A w
// just above it is mostly rounding noise, but any unit vector orthogonal to the basis continues
// a valid Lanczos relation; the unit-scale second Gram-Schmidt pass restores its orthogonality
// and rejects it (a breakdown after all) when over half of it lay in the basis.
inline constexpr double kBreakdown = 0x1p-36;

}  // namespace r1::spectral
