// Entry points of the spectral embedding: parameter checks, the dense path for small graphs, the
// Lanczos path, and the outputs (R1-SPEC-007, R1-SPEC-020, R1-SPEC-050..052, R1-SPEC-060..064).
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "jacobi.hpp"
#include "lanczos.hpp"
#include "r1/reference/spectral.hpp"
#include "vector_kernels.hpp"

namespace r1 {

namespace {

using spectral::Eigenpair;
using spectral::VectorOps;

// The counter-RNG key of every random vector: the ASCII bytes "r1-spect" (R1-SPEC-030).
constexpr std::uint64_t kSpectralSeed = 0x72312d7370656374u;
// Eigenpairs wanted above the trivial one: u_2..u_6 (R-1.0 3.1 and 5.1).
constexpr std::uint32_t kWant = 5;
// Default cap on restarts when SpectralParams::max_restarts is 0 (R1-SPEC-034): far above the
// cycles any measured graph needed (spec/spectral.md, performance), so it only stops a solve
// that cannot reach the tolerance.
constexpr std::uint32_t kDefaultMaxRestarts = 1000;

double as_double(fx::Q32 v) { return v.to_double(); }
double as_double(double v) { return v; }
template <class Scalar>
Scalar from_double(double v);
template <>
fx::Q32 from_double<fx::Q32>(double v) {
  return fx::Q32::from_double(v);
}
template <>
double from_double<double>(double v) {
  return v;
}

// The dense path (R1-SPEC-050..051): the operator as an n x n double matrix, the trivial
// direction removed by a Householder reflection, cyclic Jacobi on the (n-1) x (n-1) rest.
template <class Scalar>
std::vector<Eigenpair<Scalar>> dense_pairs(const SpectralOperator<Scalar>& op, const VectorOps<Scalar>& ops,
                                           std::uint32_t want, std::uint32_t& matvecs) {
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
  // Entries scaled to squared length 2^e like the Lanczos vectors (R1-SPEC-011).
  const double root = std::sqrt(std::ldexp(1.0, op.e));
  std::vector<Eigenpair<Scalar>> pairs;
  std::vector<Scalar> y(n), res(n);
  for (std::uint32_t c = 0; c < want; ++c) {
    Eigenpair<Scalar> p;
    p.x.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      double u = 0;
      for (std::size_t k = 0; k < r; ++k) u = u + h[i * n + k + 1] * eig.vectors[k * r + c];
      p.x[i] = from_double<Scalar>(u * root);
    }
    spectral::rayleigh<Scalar>(op, ops, p.x, y, res, p.lambda, p.residual);
    ++matvecs;
    pairs.push_back(std::move(p));
  }
  std::stable_sort(pairs.begin(), pairs.end(), [](const auto& x, const auto& z) { return x.lambda < z.lambda; });
  return pairs;
}

template <class Scalar>
Result<Spectrum<Scalar>> embed(const Graph& g, const SpectralParams& params, const ProgressFn& progress,
                               const SpectralOptions& options, Result<SpectralOperator<Scalar>> op_result) {
  if (!op_result) return op_result.status();
  const SpectralOperator<Scalar>& op = *op_result;
  Spectrum<Scalar> out;
  out.n = g.n;
  out.rho = op.rho.to_double();
  const VectorOps<Scalar> ops(g.n, op.e, options.parallel);
  const std::uint32_t want = std::min<std::uint32_t>(kWant, g.n - 1);
  std::vector<Eigenpair<Scalar>> pairs;
  // Dense when the deflated space has at most 2m dimensions (R1-SPEC-050): a Krylov basis of m
  // vectors plus locked and fresh vectors would need most of the space anyway.
  if (g.n - 1 <= 2 * params.basis) {
    pairs = dense_pairs(op, ops, want, out.matvecs);
  } else {
    spectral::LanczosConfig cfg;
    cfg.want = want;
    cfg.basis = params.basis;
    // Ritz vectors kept at a restart: 3/8 of the basis (12 of 32), at least want + 1 (R1-SPEC-026).
    cfg.keep = std::max<std::uint32_t>(want + 1, params.basis * 3 / 8);
    cfg.tolerance = params.tolerance;
    cfg.max_cycles = (params.max_restarts == 0 ? kDefaultMaxRestarts : params.max_restarts) + 1;
    cfg.seed = kSpectralSeed;
    auto lz = spectral::thick_restart_lanczos(op, ops, cfg, progress);
    pairs = std::move(lz.pairs);
    out.restarts = lz.cycles - 1;
    out.matvecs += lz.matvecs;
  }
  // Outputs (R1-SPEC-060..063): lambda_1 = 0 with the residual of the trivial vector, then the
  // pairs ascending, unit vectors u = x / ||x|| rounded once per entry; missing ones are zero.
  std::vector<Scalar> y(g.n), r(g.n);
  op.apply(op.trivial.data(), y.data(), options.parallel);
  ++out.matvecs;
  out.eigenvalues[0] = 0;
  out.residuals[0] = std::sqrt(ops.dot(y, y) / ops.dot(op.trivial, op.trivial));
  out.found = static_cast<std::uint32_t>(pairs.size());
  for (std::size_t c = 0; c < 5; ++c) {
    out.u[c].assign(g.n, Scalar{});
    if (c >= pairs.size()) continue;
    out.eigenvalues[c + 1] = pairs[c].lambda;
    out.residuals[c + 1] = pairs[c].residual;
    const double length = std::sqrt(std::ldexp(ops.dot(pairs[c].x, pairs[c].x), op.e));
    ops.scale(out.u[c], pairs[c].x, 1.0 / length);
  }
  return out;
}

Status check_params(const SpectralParams& p) {
  // basis >= 12 leaves room for the want + 1 kept Ritz vectors and as many new ones per cycle.
  if (p.basis < 12 || p.basis > 1024) return Status::input("spectral: basis must be 12..1024 (got " + std::to_string(p.basis) + ")");
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
