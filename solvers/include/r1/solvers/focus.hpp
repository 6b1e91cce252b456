// Focus phi*: the tri-kernel fixed point in Q32 and fp64, the simplex projection, T(eps) and the
// heat-kernel coefficients (R1-FOC-001..091, spec/focus.md).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "r1/spec/epoch.hpp"
#include "r1/spec/graph.hpp"
#include "r1/spec/progress.hpp"
#include "r1/spec/status.hpp"

namespace r1 {

// A backend's exact Q32 sparse product (R1-FOC-092): over a CSR matrix of raws fixed when it is
// made, apply(x) returns y_i = RNE(sum_k val_k x_(col_k) / 2^32) for every row, an exact sum
// rounded once, ties to even (an empty row: x_i when `empty_rows_identity`, else 0). A row that
// rounds outside int64 is an error, as it is on the host. A factory may decline a matrix (no
// product): the solver then keeps its row loops for every product.
class ExactProduct {
 public:
  virtual ~ExactProduct() = default;
  virtual Result<std::vector<std::int64_t>> apply(std::span<const std::int64_t> x) = 0;
};
using ExactProductFactory = std::function<Result<std::unique_ptr<ExactProduct>>(
    std::span<const std::uint64_t> row_ptr, std::span<const std::uint32_t> col, std::span<const std::int64_t> val,
    bool empty_rows_identity)>;

struct FocusOptions {
  // Runs the row loops of every sparse product on TBB threads. Each row is the same pure
  // function of the previous vector, so the result is bit-identical to the serial one
  // (R1-FOC-090); off by default because the reference is single-threaded.
  bool parallel = false;
  // When set, the whole-graph products (the walks of the heat kernel and the diffusion's
  // in-link sums) run on products made by this factory (R1-FOC-092): the same bits. The local
  // update (update_focus_q32) keeps the row loops.
  ExactProductFactory products;
  // The Q32 step is a function of phi alone, so once an iterate equals the one one or two steps
  // back, the later steps only repeat those two and the T(eps)-th iterate is known without them
  // (R1-FOC-093): the same bits. False runs every step (the switch the tests use).
  bool stop_at_repeat = true;
};

// The tri-kernel iteration phi <- Proj(l_d D(phi) + l_s S(phi) + l_h H(phi)) from Proj(u), run for
// exactly T(eps) steps. `lambda2` is the second smallest eigenvalue of the normalized Laplacian
// (0 for a disconnected graph), in [0, 2]. Bad parameters or graph: input error; a broken
// invariant: internal error. The Q32 phi raws sum to exactly 2^32 and are all >= 1.
Result<Focus<Q32>> compute_focus_q32(const Graph& g, const TriKernelParams& params, double lambda2,
                                     const ProgressFn& progress = {}, const FocusOptions& options = {});
// The local update of an incremental epoch (R1-INC-050..054): the same T(eps) steps on the
// particles of `region` (ascending, distinct) only, every other particle frozen at `start.phi`
// (raws at least 1, one entry per particle) and the region's ring held as fixed points of the walk;
// each step projects the region onto the raws the frozen particles leave of 2^32, so the result
// sums to exactly 2^32, every raw at least 1, and frozen particles keep their bits. With the
// region every particle and the start the projected prior it is compute_focus_q32's result; with
// no region it is the start. Input error when the frozen raws leave fewer than one raw per region
// particle (with no region: when they do not sum to exactly 2^32).
// The heat term on the region is `start.heat + H_local(x) - H_local(start)` (R1-INC-052, one
// entry per particle; unused when lambda_h = 0): with start.heat the exact heat of the start and
// the region every particle, the update is compute_focus_q32's. The result's heat is start.heat
// outside the region and that term at the result inside.
// `start.plogp`, when set, is the exact sum of phi ln phi over start.phi (raws below 1 adding
// nothing): the result's is then updated on the region only (R1-INC-054); unset, it is summed
// over every particle. The start's arrays are taken over, so the work is the region's.
Result<Focus<Q32>> update_focus_q32(const Graph& g, const TriKernelParams& params, double lambda2, Focus<Q32> start,
                                    std::span<const std::uint32_t> region, const ProgressFn& progress = {},
                                    const FocusOptions& options = {});
// phi ln phi on the 2^-64 scale of fx::ExactSum: x.raw * fx::log(x).raw, 0 for a raw below 1
// (R1-FOC-071, R1-INC-054).
i128 phi_log_phi(Q32 x);
// The heat term H(x) of R1-FOC-043 over the whole graph (what Focus::heat holds).
Result<std::vector<Q32>> heat_term_q32(const Graph& g, const TriKernelParams& params, std::span<const Q32> x,
                                       const FocusOptions& options = {});
// The particles within h hops of `seeds` in A_sym (breadth first), ascending (R1-INC-021).
std::vector<std::uint32_t> within_hops(const Graph& g, std::span<const std::uint32_t> seeds, std::uint32_t h);
// The same algorithm in IEEE doubles with pairwise reductions (R1-FOC-080..083).
Result<Focus<double>> compute_focus_f64(const Graph& g, const TriKernelParams& params, double lambda2,
                                        const ProgressFn& progress = {}, const FocusOptions& options = {});

// The first min(n, kCyberankPlaces) particles by phi descending, ties to the lower index
// (R1-FOC-070): what Focus::cyberank holds.
std::vector<std::uint32_t> cyberank_places(std::span<const Q32> phi);

// Fills the graph's focus summary (Graph::prior, dangling, max_degree; R1-IN-059) from its
// degrees and out-rows. n = 0: nothing.
void summarise_for_focus(Graph& g);

// Checks the ranges of R1-FOC-002 and that the three weights sum to exactly 1.
Status validate_tri_kernel_params(const TriKernelParams& params);

// ---- simplex (R1-FOC-010, R1-FOC-051..053) ------------------------------------------------------

// Largest-remainder apportionment of `total` (< 2^63) over `weights` (R1-FOC-010): shares sum to
// exactly `total`, each is the floor or ceiling of total * w_i / sum w, ties of the remainder go
// to the lower index; all-zero weights count as equal. std::invalid_argument for no weights.
std::vector<std::int64_t> apportion(std::uint64_t total, std::span<const std::uint64_t> weights);

// Proj(v): raws sum to exactly 2^32, each >= 1; the identity on vectors already on the Q32
// simplex with positive raws. std::invalid_argument unless 1 <= v.size() < 2^32.
std::vector<Q32> project_to_simplex_q32(std::span<const Q32> v);
// The fp64 projection: max(v_i, 2^-32) divided by their pairwise sum. Same size limits.
std::vector<double> project_to_simplex_f64(std::span<const double> v);
// An fp64 phi converted to Q32 by the canonical rule: Proj(from_double(phi_i)). Input error for a
// non-finite or out-of-range value or an empty vector.
Result<std::vector<Q32>> simplex_from_f64(std::span<const double> phi);

// ---- steps (R1-FOC-060..061) --------------------------------------------------------------------

struct FocusPlan {
  Q32 kappa;                   // contraction estimate
  double norm_l = 0;           // ||L|| = 2 max degree (Gershgorin), as a double
  std::uint32_t steps = 0;     // T(eps), capped
};

// kappa and T(eps) for this graph, parameters and lambda2 (validated as compute_focus_* does).
Result<FocusPlan> plan_focus_steps(const Graph& g, const TriKernelParams& params, double lambda2);
// ceil(log2(eps) / log2(kappa)) from the Q32 logarithms' raws, clamped to [1, max_steps];
// kappa >= 1: max_steps; kappa <= 0: 1. Requires eps in (0, 1) and max_steps >= 1.
std::uint32_t steps_for_kappa(Q32 kappa, Q32 eps, std::uint32_t max_steps);

// ---- heat kernel (R1-FOC-042..044) ---------------------------------------------------------------

struct HeatCoefficients {
  std::uint32_t substeps = 0;       // m = ceil(tau / 2)
  std::vector<Q32> q32;             // c_0..c_K, each correctly rounded to Q32
  std::vector<double> f64;          // the same, nearest double (correctly rounded for c_k >= 2^-180,
                                    // within 2^-240 below that, R1-FOC-044)
};

// c_k = (2 - [k = 0]) e^-sigma I_k(sigma), sigma = tau / m, for k = 0..degree, from 256-bit fixed
// point. Requires 0 < tau <= 64 and degree <= 32 (std::invalid_argument otherwise).
HeatCoefficients heat_coefficients(Q32 tau, std::uint32_t degree);

}  // namespace r1
