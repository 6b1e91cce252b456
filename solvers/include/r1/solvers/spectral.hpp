// The canonical spectral embedding (R-1.0 section 3, decisions 4-6; spec/spectral.md
// R1-SPEC-001..072): lambda_1..6 and u_2..u_6 of the regularised normalised Laplacian by
// thick-restart Lanczos, in Q32 (canonical) and fp64.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "r1/spec/epoch.hpp"
#include "r1/spec/graph.hpp"
#include "r1/spec/progress.hpp"
#include "r1/spec/status.hpp"

namespace r1 {

namespace spectral {
template <class Scalar>
class PanelOps;

// A backend's rows of the Q32 operator (R1-SPEC-073): for `count` columns of a compact n x count
// block (row i, column c at x[i * count + c]) and their rank-one coefficients `coef` (empty when
// rho = 0), y_i,c = RNE((x_i,c 2^32 - sum_k M_ik x_k,c - g_i coef_c) / 2^32), the exact sum rounded
// once: SpectralOperator<Q32>::apply_block's rows bit for bit. A row outside Q32 throws
// fx::OverflowError; a device failure std::runtime_error.
class BlockRows {
 public:
  virtual ~BlockRows() = default;
  virtual void apply(const fx::Q32* x, std::span<const std::int64_t> coef, fx::Q32* y, std::size_t count) = 0;
  // The same on blocks whose rows are ld >= count entries apart (row i, column c at x[i * ld + c]
  // and y[i * ld + c]); the entries of a row past count are neither read nor written. The solver's
  // compact blocks of fewer than 8 columns have rows of whole 64-byte lines (R1-SPEC-074). False
  // (the default), with nothing written: the rows take compact blocks only, and the operator
  // copies to and from compact blocks around apply().
  virtual bool apply_strided(const fx::Q32* /*x*/, std::size_t /*ld*/, std::span<const std::int64_t> /*coef*/,
                             fx::Q32* /*y*/, std::size_t /*count*/) {
    return false;
  }
  // The filter's step fused with the application (R1-SPEC-075): with s = L~ x (the rows above),
  // p <- spectral::three_term(n ld, s, x, p, alpha, beta, gamma) on blocks of rows ld >= count
  // entries apart whose entries past count are zero in x and p (they stay zero), without an
  // n x ld block for s. The same bits as applying and then running the recurrence. False (the
  // default), with nothing written: the solver does exactly that.
  virtual bool apply_three_term(const fx::Q32* /*x*/, std::size_t /*ld*/, std::span<const std::int64_t> /*coef*/,
                                fx::Q32* /*p*/, std::size_t /*count*/, double /*alpha*/, double /*beta*/,
                                double /*gamma*/) {
    return false;
  }
  // True when the rows keep M's entries themselves, exactly (R1-SPEC-076): the solver may then
  // release SpectralOperator::m while the rows serve its applications, and restore_entries gives
  // the entries back bit for bit. False (the default): the rows read the operator's.
  virtual bool holds_entries() const { return false; }
  virtual void restore_entries(std::vector<fx::Q32>& /*m*/) const {}
};
}  // namespace spectral

template <class Scalar>
struct SpectralOperator;
// Makes a backend's rows for an operator (which outlives them), or none to decline it (the host's
// rows then run it).
using Q32RowsFactory = std::function<std::unique_ptr<spectral::BlockRows>(const SpectralOperator<fx::Q32>& op)>;

// The Q32 kernels for a panel of n rows under the scaled inner product 2^-e with frac fraction
// bits (spectral::PanelOps's constructor arguments).
using Q32KernelFactory =
    std::function<std::unique_ptr<spectral::PanelOps<fx::Q32>>(std::size_t n, int e, bool parallel, int frac)>;

namespace spectral {
// e minimal with 2^e >= n (R1-SPEC-011): the scale of the inner product.
int scale_exponent(std::uint32_t n);
// The raw of M_ij = w_ij / sqrt(D_i D_j) (R1-SPEC-003), D in Q32 raws.
fx::Q32 m_entry(std::int64_t w, u128 di, u128 dj);
}  // namespace spectral

// Some rows of L~ with rho = 0 (R1-SPEC-001..005), for the incremental update (spec/incremental.md
// R1-INC-038): the M entries of the listed rows only, over any CSR with per-particle weighted
// degrees, and their exact products, bit for bit the rows SpectralOperator<Q32>::apply_block
// computes before its rounding.
struct RowOperatorQ32 {
  std::vector<std::uint32_t> rows;  // the rows, in the caller's order
  std::vector<std::uint64_t> ptr;   // rows.size() + 1 offsets into col and m
  std::vector<std::uint32_t> col;
  std::vector<fx::Q32> m;

  static RowOperatorQ32 build(std::span<const std::uint64_t> row_ptr, std::span<const std::uint32_t> col,
                              std::span<const std::int64_t> w, std::span<const std::uint64_t> degree,
                              std::span<const std::uint32_t> rows, bool parallel = false);
  // Writes image[rows[a] * 5 + c] = x_i 2^32 - sum_k M_ik x_k for row i = rows[a], x_j =
  // cols[c][j].raw * 2^shift (five columns, each indexed by particle).
  void numerators(std::span<const std::vector<fx::Q32>> cols, int shift, std::vector<i128>& image, bool parallel = false) const;
};

namespace spectral {
using ResidualSums = std::array<std::array<fx::ExactSum, 3>, 5>;
// y_i = RNE(numerator / 2^32) (R1-SPEC-005's one rounding).
std::int64_t image_raw(i128 numerator);
// Adds sign * (x_i^2, x_i y_i, y_i^2) of particle i, five columns, into sums (Spectrum::sums).
void add_row_sums(std::span<const std::vector<fx::Q32>> cols, int shift, std::uint32_t i, const i128* numerators, int sign,
                  ResidualSums& sums);
}  // namespace spectral

// How the solver runs, never what it computes: every setting gives the same bytes.
struct SpectralOptions {
  // TBB tasks for the operator and vector kernels (R1-SPEC-071). Bit-identical to serial.
  bool parallel = false;
  // The Q32 vector kernels the driver runs on (R1-SOL-002); empty: the portable ones
  // (spectral::PanelOps). A backend passes its own here; the bytes must not change.
  Q32KernelFactory q32_kernels;
  // The Q32 operator's rows for the solver's block applications (R1-SPEC-073); empty: the
  // host's. The bytes must not change.
  Q32RowsFactory q32_rows;
  // Called once the operator (and a backend's rows) are formed: from then on the solve reads of
  // the graph only n, row_ptr, col, degree and component_size (R1-EPO-006).
  std::function<void()> operator_ready;
};

// The operator the solver iterates on (R1-SPEC-001..006), for export and tests:
//     L~ x = x - M x - g (g^T x),   M_ij = w_ij / sqrt(D_i D_j),  D = degree + rho,
//     g_i = sqrt(rho / (n D_i))  (g empty when rho = 0).
// `trivial` is the deflated vector D^(1/2) 1 scaled to squared length 2^e (R1-SPEC-011).
template <class Scalar>
struct SpectralOperator {
  const Graph* graph = nullptr;  // the CSR pattern (row_ptr, col); must outlive the operator
  std::uint32_t n = 0;
  int e = 0;                     // scaled inner product <x, y> = 2^-e sum x_i y_i, 2^e >= n
  fx::Q32 rho;                   // regularisation actually used
  std::vector<Scalar> m;         // per stored entry of the graph, M_ij
  std::vector<Scalar> g;         // rank-one factor; empty when rho = 0
  std::vector<Scalar> trivial;   // D^(1/2) 1, squared length 2^e
  // Q32: a backend's rows (SpectralOptions::q32_rows), which apply_block runs compact blocks on.
  std::shared_ptr<spectral::BlockRows> rows;

  // y = L~ x (R1-SPEC-005): Q32, every row one exact sum rounded once; fp64, fixed pairwise rows.
  void apply(const Scalar* x, Scalar* y, bool parallel = false) const { apply_block(x, 1, y, 1, 1, parallel); }
  // The same for `count` vectors at once (one pass over the operator): column c of x is
  // x[i * ldx + c], of y y[i * ldy + c]; each column's result is apply() of that column. x and y
  // must not overlap.
  void apply_block(const Scalar* x, std::size_t ldx, Scalar* y, std::size_t ldy, std::size_t count,
                   bool parallel = false) const;
  // BlockRows::apply_three_term through the backend's rows, the rank-one coefficients formed as
  // apply_block forms them. False, with nothing written, where no rows fuse the step (the host's,
  // fp64): the caller applies and then runs the recurrence.
  bool apply_three_term(const Scalar* x, std::size_t ld, Scalar* p, std::size_t count, double alpha, double beta,
                        double gamma, bool parallel = false) const;
};

// rho by decision 4 (R1-SPEC-002): the forced value, else 0 for a connected graph and the mean
// weighted degree otherwise, as Q32. Input errors: a negative, non-finite or out-of-range
// forced value; rho = 0 with an isolated particle.
Result<fx::Q32> spectral_rho(const Graph& g, const SpectralParams& params);

Result<SpectralOperator<fx::Q32>> spectral_operator_q32(const Graph& g, const SpectralParams& params);
Result<SpectralOperator<double>> spectral_operator_f64(const Graph& g, const SpectralParams& params);

// Spectrum::image and ::sums (R1-INC-038) of the spectrum's five stored vectors, scaled by
// 2^(e / 2); left empty (sums_shift -1) when it holds fewer than five vectors or op.rho > 0.
void residual_sums(const SpectralOperator<fx::Q32>& op, Spectrum<fx::Q32>& s, bool parallel = false);
namespace spectral {
// Spectrum::image and ::sums of any five vectors over every particle (one pass over op).
void image_and_sums(const SpectralOperator<fx::Q32>& op, std::span<const std::vector<fx::Q32>> cols, int shift,
                    std::vector<i128>& image, ResidualSums& sums, bool parallel = false);
}  // namespace spectral

// The embedding: eigenvalues, residuals and unit vectors u_2..u_6 (R1-SPEC-060..064).
// Input errors: an empty graph, bad params (basis < 12, tolerance not positive), rho = 0 with an
// isolated particle. Q32 overflow inside the solver is an internal error naming the stage.
Result<Spectrum<fx::Q32>> spectral_embedding_q32(const Graph& g, const SpectralParams& params,
                                                 const ProgressFn& progress = {}, const SpectralOptions& options = {});
Result<Spectrum<double>> spectral_embedding_f64(const Graph& g, const SpectralParams& params,
                                                const ProgressFn& progress = {}, const SpectralOptions& options = {});

}  // namespace r1
