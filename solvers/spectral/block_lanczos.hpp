// Block thick-restart Lanczos with full re-orthogonalisation and locking (R1-SPEC-020..035),
// templated over the numeric domain.
#pragma once

#include <algorithm>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "r1/solvers/panel.hpp"
#include "r1/solvers/spectral.hpp"
#include "r1/spec/progress.hpp"

namespace r1::spectral {

struct BlockLanczosConfig {
  std::uint32_t want = 5;      // eigenpairs above the deflated trivial one
  std::uint32_t block = 7;     // b: vectors per block, at least `want` (R1-SPEC-021)
  std::uint32_t basis = 98;    // m: basis columns per cycle, a multiple of b (R1-SPEC-021)
  std::uint32_t keep = 36;     // Ritz vectors kept at a thick restart, want + b <= keep <= m - 2b (R1-SPEC-026)
  double tolerance = 1e-9;     // residual target (R1-SPEC-028)
  std::uint32_t max_cycles = 1001;
  std::uint64_t seed = 0;      // counter-RNG key of start and fresh vectors (R1-SPEC-030)
  // The Chebyshev filter (R1-SPEC-080..083): its degree (0 or 1: none), the cycle after which it
  // starts, the least index of the Ritz value that places its damped interval, and the most
  // filtered cycles before the solve goes on without it.
  std::uint32_t filter_degree = 0;
  std::uint32_t filter_after = 1;
  std::uint32_t filter_index = 5;
  std::uint32_t filter_cycles = 64;
};

// The counter-RNG key of every random vector: the ASCII bytes "r1-spect" (R1-SPEC-030).
inline constexpr std::uint64_t kSpectralSeed = 0x72312d7370656374u;

// The fraction bits of the solver's Q32 vectors (R1-SPEC-011): 48, fewer when n is so large that
// a unit vector's entries (up to 2^(e/2) in value, twice that after L~) would leave int64.
inline int basis_frac(int e) { return std::min(48, 60 - (e + 1) / 2); }

// The Chebyshev filter of R1-SPEC-080..082: K = -p(L~), p the degree-d Chebyshev polynomial of
// the first kind on the damped interval [a, 2] mapped to [-1, 1], scaled so that p(al) = 1 (Zhou
// and Saad's scaled recurrence). On [a, 2] |K| <= band = |K(a)|; on [0, a] K is increasing and
// below -band. Every scalar is plain IEEE arithmetic in a fixed order (no FMA).
struct ChebyshevFilter {
  std::uint32_t degree = 0;
  double a = 0, al = 0;
  bool on() const { return degree > 1; }
  double e() const { return (2 - a) / 2; }
  double c() const { return (2 + a) / 2; }
  double s1() const { return e() / (al - c()); }
  // K(lambda) and dK/dlambda by the scalar recurrence and its derivative.
  std::pair<double, double> value_slope(double lam) const;
  double value(double lam) const { return value_slope(lam).first; }
  // The lambda in [0, a] with K(lambda) = theta (K increasing there): 64 bisection steps.
  double preimage(double theta) const;
  // A Ritz pair of K with value theta and residual estimate est_k: the estimate for L~
  // (R1-SPEC-082): mu = preimage(theta); components near mu shrink by
  // the slope K'(mu), those on the damped interval by at least |theta| - band over a distance of
  // at most 2. A Ritz value inside the damped band has none (infinity).
  double residual_estimate(double theta, double est_k) const;
};

// The configuration spectral_embedding_* runs with on n particles for `want` pairs (R1-SPEC-021,
// R1-SPEC-026, R1-SPEC-034), n - 1 > 64 (the dense path below).
BlockLanczosConfig canonical_config(std::uint32_t n, std::uint32_t want, const SpectralParams& params, std::uint64_t seed);

template <class Scalar>
struct Eigenpair {
  std::vector<Scalar> x;  // scaled: <x, x> = 1 up to rounding (R1-SPEC-011)
  double lambda = 0;      // Rayleigh quotient <x, L x> / <x, x>
  double residual = 0;    // ||L x - lambda x|| / ||x||
};

template <class Scalar>
struct LanczosOutcome {
  std::vector<Eigenpair<Scalar>> pairs;  // ascending lambda, `want` of them
  std::uint32_t cycles = 0;
  std::uint32_t matvecs = 0;  // vectors L~ was applied to
  std::uint32_t passes = 0;   // block applications: passes over the operator, each for up to `block` vectors
  std::uint32_t robust_blocks = 0;  // blocks the robust Gram-Schmidt path orthonormalised
  bool converged = false;
};

// The exact Rayleigh quotients and residuals of the columns xs (R1-SPEC-061) in one block
// application, using the columns ys (as many, both runs contiguous and ascending) as scratch.
// The residual is taken in the complement of the trivial vector, panel column `trivial`: the
// solver's space (R1-SPEC-020), where the rounded operator's imperfect null vector leaves no floor.
template <class Scalar>
void rayleigh_block(const SpectralOperator<Scalar>& op, const PanelOps<Scalar>& ops, Panel<Scalar>& p, Cols xs, Cols ys,
                    std::uint32_t trivial, std::span<double> lambda, std::span<double> residual);

// `trivial` is D^(1/2) 1 with unit scaled length in the panel's units (R1-SPEC-006, R1-SPEC-011).
template <class Scalar>
LanczosOutcome<Scalar> block_lanczos(const SpectralOperator<Scalar>& op, const PanelOps<Scalar>& ops,
                                     std::span<const Scalar> trivial, const BlockLanczosConfig& config,
                                     const ProgressFn& progress);

// The canonical start block (R1-SPEC-030): the first `block` basis vectors, for tests of the
// multiplicity argument's hypothesis (proofs/spectral_multiplicity.md).
template <class Scalar>
std::vector<std::vector<Scalar>> start_block(const SpectralOperator<Scalar>& op, const PanelOps<Scalar>& ops,
                                             std::span<const Scalar> trivial, const BlockLanczosConfig& config);

// A new column whose length after the first Gram-Schmidt pass is below this is a breakdown (an
// invariant subspace): it is replaced by a fresh random vector and its coupling is 0
// (R1-SPEC-024). Dropping it perturbs the Lanczos relation by at most this much, which then floors
// every Ritz residual, so the threshold must sit below the residual tolerances in use (1e-9 by
// default) and near the Q32 rounding level: 2^-36 (1.5e-11). A column just above it is mostly
// rounding noise, but any unit vector orthogonal to the basis continues a valid Lanczos relation;
// the unit-scale second pass restores its orthogonality and rejects it (a breakdown after all)
// when over half of it lay in the basis.
inline constexpr double kBreakdown = 0x1p-36;

// A fused Gram-Schmidt pass (R1-SPEC-023) declines when a pivot of the projected Gram matrix is
// at most this times the column's squared length before the pass: the Gram matrix is formed in
// fp64 as G - C^T C, whose rounding (about 2^-52 of G) must stay far below the pivot for the
// Cholesky factor to be accurate; 2^-30 leaves the first pass accurate to ~2^-22, which the second
// pass (at unit scale) then brings to the rounding level.
inline constexpr double kPivotFloor = 0x1p-30;
// A fused pass scales coefficients of 8 or more down by 2^-k and its result up by 2^k, giving up k
// bits of the 48 (R1-SPEC-011); beyond 20 it declines and the robust path runs.
inline constexpr int kMaxScaleBits = 20;
// A fused pass leaves out the list columns whose coefficients are all at most this: the new
// column is orthogonal to them within it already (2^-44, far below the 2^-30 of the default
// tolerance; every pass measures all of them, so none grows past it unseen).
inline constexpr double kApplyFloor = 0x1p-40;

}  // namespace r1::spectral
