// Helpers the spectral tests share: graphs from generators and from named links, an independent
// fp64 normalised Laplacian (sparse and dense), the result invariants of R1-SPEC-060..063, and
// principal angles. Tests only; nothing here is shared with the solver.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "r1/reference/generate.hpp"
#include "r1/reference/graph_build.hpp"
#include "r1/reference/snapshot_builder.hpp"
#include "r1/solvers/spectral.hpp"

namespace r1::spectral_test {

using Link = std::tuple<std::string, std::string, std::uint64_t>;

inline Graph generated(GenKind kind, std::optional<std::int64_t> n, std::vector<std::int64_t> dims = {},
                       std::optional<std::int64_t> k = std::nullopt) {
  GenParams p;
  p.kind = kind;
  p.n = n;
  p.dims = std::move(dims);
  p.k = k;
  auto s = generate(p);
  EXPECT_TRUE(s.is_ok()) << s.status().message();
  auto g = build_graph(*s);
  EXPECT_TRUE(g.is_ok()) << g.status().message();
  return std::move(g).value();
}

// A graph from named weighted links (weights in whole units).
inline Graph from_links(const std::vector<Link>& links) {
  SnapshotBuilder b("test");
  b.snapshot().config = text_input_config();
  for (const auto& [from, to, w] : links) {
    r1::Link l;
    l.height = 1;
    l.amount = static_cast<u128>(w) << 32;
    l.valence = 1;
    l.from = b.particle_by_name(from);
    l.to = b.particle_by_name(to);
    b.add_link(l);
  }
  auto g = build_graph(std::move(b.finish()).value());
  EXPECT_TRUE(g.is_ok()) << g.status().message();
  return std::move(g).value();
}

inline double to_d(fx::Q32 v) { return v.to_double(); }
inline double to_d(double v) { return v; }

// Unit vectors u_2..u_(found+1) as an n x found Eigen matrix.
template <class Scalar>
Eigen::MatrixXd vectors(const Spectrum<Scalar>& s) {
  Eigen::MatrixXd u(s.n, s.found);
  for (std::uint32_t c = 0; c < s.found; ++c)
    for (std::uint32_t i = 0; i < s.n; ++i) u(i, c) = to_d(s.u[c][i]);
  return u;
}

// D = weighted degree + rho, straight from the graph (no code shared with the solver).
inline Eigen::VectorXd degrees(const Graph& g, double rho) {
  Eigen::VectorXd d(g.n);
  for (std::uint32_t i = 0; i < g.n; ++i) d(i) = static_cast<double>(g.degree[i]) * 0x1p-32 + rho;
  return d;
}

// The regularised normalised Laplacian applied in fp64: y = x - D^-1/2 A_rho D^-1/2 x.
inline Eigen::VectorXd apply_laplacian(const Graph& g, double rho, const Eigen::VectorXd& x) {
  const Eigen::VectorXd d = degrees(g, rho);
  const Eigen::VectorXd s = d.array().rsqrt();
  Eigen::VectorXd y = x;
  for (std::uint32_t i = 0; i < g.n; ++i)
    for (std::uint64_t k = g.row_ptr[i]; k < g.row_ptr[i + 1]; ++k)
      y(i) -= s(i) * static_cast<double>(g.w[k]) * 0x1p-32 * s(g.col[k]) * x(g.col[k]);
  if (rho > 0) y -= s * (rho / g.n) * s.dot(x);
  return y;
}

// The same operator as a dense matrix (small graphs).
inline Eigen::MatrixXd dense_laplacian(const Graph& g, double rho) {
  const Eigen::Index n = g.n;
  const Eigen::VectorXd d = degrees(g, rho);
  Eigen::MatrixXd a = Eigen::MatrixXd::Constant(n, n, rho / static_cast<double>(n));
  for (std::uint32_t i = 0; i < g.n; ++i)
    for (std::uint64_t k = g.row_ptr[i]; k < g.row_ptr[i + 1]; ++k) a(i, g.col[k]) += static_cast<double>(g.w[k]) * 0x1p-32;
  const Eigen::VectorXd s = d.array().rsqrt();
  return Eigen::MatrixXd::Identity(n, n) - s.asDiagonal() * a * s.asDiagonal();
}

// Largest principal angle (radians) between the column spaces of two orthonormal n x k bases:
// asin of the largest singular value of the part of b outside span(a) (well conditioned for
// the tiny angles the tests bound, where acos of the cosines is not).
inline double max_angle(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  const Eigen::MatrixXd rest = b - a * (a.transpose() * b);
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(rest);
  return std::asin(std::min(1.0, svd.singularValues().maxCoeff()));
}

// Invariants every result must satisfy (R1-SPEC-060..063): lambda_1 = 0, ascending eigenvalues,
// residuals within the tolerance, unit and mutually orthogonal vectors, orthogonal to D^(1/2) 1.
template <class Scalar>
void check_invariants(const Graph& g, const Spectrum<Scalar>& s, double tol, double ortho_tol) {
  EXPECT_EQ(s.eigenvalues[0], 0.0);
  for (std::uint32_t c = 0; c < s.found; ++c) {
    EXPECT_LE(s.eigenvalues[c], s.eigenvalues[c + 1] + 1e-12) << c;
    EXPECT_LE(s.residuals[c + 1], tol) << "pair " << c + 2;
  }
  const Eigen::MatrixXd u = vectors(s);
  const Eigen::MatrixXd gram = u.transpose() * u;
  EXPECT_LT((gram - Eigen::MatrixXd::Identity(s.found, s.found)).cwiseAbs().maxCoeff(), ortho_tol);
  Eigen::VectorXd t = degrees(g, s.rho).array().sqrt();
  t.normalize();
  EXPECT_LT((u.transpose() * t).cwiseAbs().maxCoeff(), ortho_tol);
  for (std::uint32_t c = s.found; c < 5; ++c)
    for (const Scalar& x : s.u[c]) EXPECT_EQ(to_d(x), 0.0);
}

// The five smallest non-trivial values of a spectrum (all n eigenvalues, any order).
inline std::array<double, 5> wanted(std::vector<double> all) {
  std::sort(all.begin(), all.end());
  std::array<double, 5> w{};
  for (int c = 0; c < 5; ++c) w[c] = all[static_cast<std::size_t>(c) + 1];
  return w;
}

}  // namespace r1::spectral_test
