// Entry points of the spectral embedding: parameter checks, the dense path for small graphs, the
// Lanczos path, and the outputs (R1-SPEC-007, R1-SPEC-020, R1-SPEC-050..052, R1-SPEC-060..064).
#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <type_traits>

#include "block_lanczos.hpp"
#include "jacobi.hpp"
#include "r1/solvers/panel.hpp"
#include "r1/solvers/spectral.hpp"
#include "trivial_vector.hpp"

namespace r1 {

namespace {

using spectral::Eigenpair;
using spectral::Panel;
using spectral::PanelOps;

using spectral::kSpectralSeed;
// Eigenpairs wanted above the trivial one: u_2..u_6 (R-1.0 3.1 and 5.1).
constexpr std::uint32_t kWant = 5;
// Graphs whose deflated space has at most this many dimensions are solved densely (R1-SPEC-050).
constexpr std::uint32_t kDenseMax = 64;

double as_double(fx::Q32 v) { return v.to_double(); }
double as_double(double v) { return v; }

using spectral::basis_frac;

// v in the panel's units: Q32 raws RNE(v 2^frac) (ldexp is exact, from_double rounds once); fp64 v.
template <class Scalar>
Scalar from_double(double v, int frac);
template <>
fx::Q32 from_double<fx::Q32>(double v, int frac) {
  return fx::Q32::from_double(std::ldexp(v, frac - 32));
}
template <>
double from_double<double>(double v, int) {
  return v;
}

// D^(1/2) 1 in the panel's units: Q32 recomputed exactly at frac bits, fp64 the operator's.
std::vector<fx::Q32> panel_trivial(const Graph& g, const SpectralOperator<fx::Q32>& op, int frac) {
  return spectral::scaled_trivial(g, op.rho, op.e, frac);
}
std::vector<double> panel_trivial(const Graph&, const SpectralOperator<double>& op, int) { return op.trivial; }

// The factor that turns panel units into the output's (Q32 raws at 2^-32; fp64 unchanged).
double output_units(fx::Q32*, int frac) { return std::ldexp(1.0, 32 - frac); }
double output_units(double*, int) { return 1.0; }

// The dense path (R1-SPEC-050..051): the operator as an n x n double matrix, the trivial
// direction removed by a Householder reflection, cyclic Jacobi on the (n-1) x (n-1) rest.
template <class Scalar>
std::vector<Eigenpair<Scalar>> dense_pairs(const SpectralOperator<Scalar>& op, const PanelOps<Scalar>& ops,
                                           std::span<const Scalar> trivial, std::uint32_t want, std::uint32_t& matvecs,
                                           std::uint32_t& passes) {
  const std::size_t n = op.n;
  const Graph& gr = *op.graph;
  std::vector<double> a(n * n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    a[i * n + i] = 1.0;
    for (std::uint64_t k = gr.row_ptr[i]; k < gr.row_ptr[i + 1]; ++k) a[i * n + gr.col[k]] -= as_double(op.m[k]);
  }
  if (!op.g.empty())
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = 0; j < n; ++j) a[i * n + j] -= as_double(op.g[i]) * as_double(op.g[j]);
  // Unit trivial vector s; v = s + e_0 (s_0 > 0 because every D_i > 0), H = I - 2 v v^T / v^T v
  // maps s to -e_0, so columns 1..n-1 of H are an orthonormal basis of the complement of s.
  std::vector<double> s(n);
  double ss = 0;
  for (std::size_t i = 0; i < n; ++i) {
    s[i] = as_double(op.trivial[i]);
    ss = ss + s[i] * s[i];
  }
  const double norm = std::sqrt(ss);
  for (double& x : s) x = x / norm;
  std::vector<double> v = s;
  v[0] = v[0] + 1.0;
  double vv = 0;
  for (const double x : v) vv = vv + x * x;
  std::vector<double> h(n * n);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j) h[i * n + j] = (i == j ? 1.0 : 0.0) - 2.0 * v[i] * v[j] / vv;
  // B = H A H, each product summed over k in ascending order.
  auto matmul = [n](const std::vector<double>& x, const std::vector<double>& y) {
    std::vector<double> z(n * n);
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = 0; j < n; ++j) {
        double t = 0;
        for (std::size_t k = 0; k < n; ++k) t = t + x[i * n + k] * y[k * n + j];
        z[i * n + j] = t;
      }
    return z;
  };
  const std::vector<double> b = matmul(h, matmul(a, h));
  const std::size_t r = n - 1;
  std::vector<double> inner(r * r);
  for (std::size_t i = 0; i < r; ++i)
    for (std::size_t j = 0; j < r; ++j) inner[i * r + j] = b[(i + 1) * n + (j + 1)];
  const spectral::JacobiResult eig = spectral::jacobi_eigen(r, std::move(inner));
  // Entries scaled to squared length 2^e like the Lanczos vectors (R1-SPEC-011); the Rayleigh
  // quotients and residuals in one block application (columns 0..want-1, scratch after them).
  const double root = std::sqrt(std::ldexp(1.0, op.e));
  Panel<Scalar> p(n, 2 * std::size_t{want} + 1);
  p.set_column(2 * std::size_t{want}, trivial);
  for (std::uint32_t c = 0; c < want; ++c)
    for (std::size_t i = 0; i < n; ++i) {
      double u = 0;
      for (std::size_t k = 0; k < r; ++k) u = u + h[i * n + k + 1] * eig.vectors[k * r + c];
      p.at(i, c) = from_double<Scalar>(u * root, ops.frac_bits());
    }
  std::vector<std::uint32_t> xs(want), ys(want);
  for (std::uint32_t c = 0; c < want; ++c) {
    xs[c] = c;
    ys[c] = want + c;
  }
  std::vector<double> lambda(want), residual(want);
  spectral::rayleigh_block<Scalar>(op, ops, p, xs, ys, 2 * want, lambda, residual);
  matvecs += want;
  ++passes;
  std::vector<Eigenpair<Scalar>> pairs;
  for (std::uint32_t c = 0; c < want; ++c) pairs.push_back(Eigenpair<Scalar>{p.copy_column(c), lambda[c], residual[c]});
  std::stable_sort(pairs.begin(), pairs.end(), [](const auto& x, const auto& z) { return x.lambda < z.lambda; });
  return pairs;
}

// The kernels: a backend's (options.q32_kernels) or the portable ones.
template <class Scalar>
std::unique_ptr<PanelOps<Scalar>> make_ops(std::size_t n, int e, const SpectralOptions& options, int frac) {
  if constexpr (std::is_same_v<Scalar, fx::Q32>) {
    if (options.q32_kernels) {
      auto k = options.q32_kernels(n, e, options.parallel, frac);
      if (!k || k->size() != n || k->scale_exponent() != e || k->frac_bits() != frac)
        throw std::runtime_error("spectral: the backend's kernels do not match the panel");
      return k;
    }
  }
  return std::make_unique<PanelOps<Scalar>>(n, e, options.parallel, frac);
}

template <class Scalar>
Result<Spectrum<Scalar>> embed(const Graph& g, const SpectralParams& params, const ProgressFn& progress,
                               const SpectralOptions& options, Result<SpectralOperator<Scalar>> op_result) {
  if (!op_result) return op_result.status();
  if constexpr (std::is_same_v<Scalar, fx::Q32>) {
    // A backend may decline an operator (no rows): the host's rows run it.
    if (options.q32_rows) op_result->rows = options.q32_rows(*op_result);
  }
  const SpectralOperator<Scalar>& op = *op_result;
  // Rows that hold M's entries serve every application of the iterative solve: the operator's
  // own copy goes until the outputs need it (R1-SPEC-076).
  [[maybe_unused]] bool released = false;
  if constexpr (std::is_same_v<Scalar, fx::Q32>) {
    if (op.rows != nullptr && op.rows->holds_entries() && g.n - 1 > kDenseMax) {
      std::vector<Scalar>().swap(op_result->m);
      released = true;
    }
  }
  if (options.operator_ready) options.operator_ready();
  Spectrum<Scalar> out;
  out.n = g.n;
  out.rho = op.rho.to_double();
  const std::unique_ptr<PanelOps<Scalar>> ops_ptr = make_ops<Scalar>(g.n, op.e, options, basis_frac(op.e));
  const PanelOps<Scalar>& ops = *ops_ptr;
  const std::vector<Scalar> trivial = panel_trivial(g, op, ops.frac_bits());
  const std::uint32_t want = std::min<std::uint32_t>(kWant, g.n - 1);
  std::vector<Eigenpair<Scalar>> pairs;
  if (g.n - 1 <= kDenseMax) {
    pairs = dense_pairs(op, ops, std::span<const Scalar>(trivial), want, out.matvecs, out.passes);
  } else {
    const spectral::BlockLanczosConfig cfg = spectral::canonical_config(g.n, want, params, kSpectralSeed);
    auto lz = spectral::block_lanczos<Scalar>(op, ops, trivial, cfg, progress);
    pairs = std::move(lz.pairs);
    out.restarts = lz.cycles - 1;
    out.matvecs += lz.matvecs;
    out.passes += lz.passes;
  }
  // Outputs (R1-SPEC-060..063): lambda_1 = 0 with the residual of the trivial vector, then the
  // pairs ascending, unit vectors u = x / ||x|| rounded once per entry; missing ones are zero.
  Panel<Scalar> p(g.n, 2);
  p.set_column(0, trivial);
  op.apply_block(p.column(0), p.cols(), p.column(1), p.cols(), 1, options.parallel);
  ++out.matvecs;
  ++out.passes;
  out.eigenvalues[0] = 0;
  out.residuals[0] = std::sqrt(ops.dot(p, 1, 1) / ops.dot(p, 0, 0));
  out.found = static_cast<std::uint32_t>(pairs.size());
  for (std::size_t c = 0; c < 5; ++c) {
    out.u[c].assign(g.n, Scalar{});
    if (c >= pairs.size()) continue;
    out.eigenvalues[c + 1] = pairs[c].lambda;
    out.residuals[c + 1] = pairs[c].residual;
    p.set_column(0, pairs[c].x);
    const double length = std::sqrt(std::ldexp(ops.dot(p, 0, 0), op.e));
    ops.scale(p, 0, output_units(static_cast<Scalar*>(nullptr), ops.frac_bits()) / length);
    out.u[c] = p.copy_column(0);
  }
  // The sums an incremental epoch carries (R1-INC-038): one more block application, the
  // certificate's rather than the solve's, so spectral_work does not count it. They read M's
  // entries row by row, so released entries come back first (the basis is gone by now).
  if constexpr (std::is_same_v<Scalar, fx::Q32>) {
    if (released) op.rows->restore_entries(op_result->m);
    residual_sums(op, out, options.parallel);
  }
  return out;
}

Status check_params(const SpectralParams& p) {
  // basis >= 4 block steps leaves room for the want + b kept Ritz vectors and two blocks
  // (R1-SPEC-021); 200 steps (1000 columns) bounds the memory and the Rayleigh-Ritz cost.
  if (p.basis < 4 || p.basis > 200) return Status::input("spectral: basis must be 4..200 block steps (got " + std::to_string(p.basis) + ")");
  if (p.filter_degree > 64) return Status::input("spectral: filter degree must be 0..64 (got " + std::to_string(p.filter_degree) + ")");
  if (!(p.tolerance > 0) || !std::isfinite(p.tolerance))
    return Status::input("spectral: tolerance must be a positive number");
  return Status::ok();
}

template <class Scalar, class MakeOp>
Result<Spectrum<Scalar>> guarded(const Graph& g, const SpectralParams& params, const ProgressFn& progress,
                                 const SpectralOptions& options, MakeOp make_op) {
  R1_TRY(check_params(params));
  try {
    return embed<Scalar>(g, params, progress, options, make_op(g, params));
  } catch (const fx::OverflowError& e) {
    return Status::internal(std::string("spectral: fixed-point overflow (") + e.what() + ")");
  } catch (const fx::DomainError& e) {
    return Status::internal(std::string("spectral: fixed-point domain error (") + e.what() + ")");
  } catch (const std::runtime_error& e) {
    return Status::internal(e.what());
  }
}

}  // namespace

Result<Spectrum<fx::Q32>> spectral_embedding_q32(const Graph& g, const SpectralParams& params, const ProgressFn& progress,
                                                 const SpectralOptions& options) {
  return guarded<fx::Q32>(g, params, progress, options, spectral_operator_q32);
}

Result<Spectrum<double>> spectral_embedding_f64(const Graph& g, const SpectralParams& params, const ProgressFn& progress,
                                                const SpectralOptions& options) {
  return guarded<double>(g, params, progress, options, spectral_operator_f64);
}

}  // namespace r1
