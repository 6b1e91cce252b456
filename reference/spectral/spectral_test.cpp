// The spectral embedding against known spectra (ring, path, complete, grid, torus with
// multiplicities), Eigen's dense solver, residual and orthogonality bounds, Q32 vs fp64,
// determinism and the TBB switch (R1-SPEC-001..072).
#include "r1/reference/spectral.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <boost/multiprecision/cpp_int.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "r1/reference/generate.hpp"
#include "r1/reference/graph_build.hpp"
#include "r1/reference/snapshot_builder.hpp"
#include "r1/fixedpoint/counter_rng.hpp"
#include "r1/fixedpoint/hemera.hpp"
#include "test_support.hpp"

namespace {

using r1::fx::Q32;

r1::Graph generated(r1::GenKind kind, std::optional<std::int64_t> n, std::vector<std::int64_t> dims = {},
                    std::optional<std::int64_t> k = std::nullopt) {
  r1::GenParams p;
  p.kind = kind;
  p.n = n;
  p.dims = std::move(dims);
  p.k = k;
  auto s = r1::generate(p);
  EXPECT_TRUE(s.is_ok()) << s.status().message();
  auto g = r1::build_graph(*s);
  EXPECT_TRUE(g.is_ok()) << g.status().message();
  return std::move(g).value();
}

// A graph from named weighted links (weights in whole units).
r1::Graph from_links(const std::vector<std::tuple<std::string, std::string, std::uint64_t>>& links) {
  r1::SnapshotBuilder b("test");
  b.snapshot().config = r1::text_input_config();
  for (const auto& [from, to, w] : links) {
    r1::Link l;
    l.height = 1;
    l.amount = static_cast<r1::u128>(w) << 32;
    l.valence = 1;
    l.from = b.particle_by_name(from);
    l.to = b.particle_by_name(to);
    b.add_link(l);
  }
  auto g = r1::build_graph(std::move(b.finish()).value());
  EXPECT_TRUE(g.is_ok()) << g.status().message();
  return std::move(g).value();
}

double to_d(Q32 v) { return v.to_double(); }
double to_d(double v) { return v; }

// Unit vectors u_2..u_(found+1) as an n x found Eigen matrix.
template <class Scalar>
Eigen::MatrixXd vectors(const r1::Spectrum<Scalar>& s) {
  Eigen::MatrixXd u(s.n, s.found);
  for (std::uint32_t c = 0; c < s.found; ++c)
    for (std::uint32_t i = 0; i < s.n; ++i) u(i, c) = to_d(s.u[c][i]);
  return u;
}

// The independent reference: the dense regularised normalised Laplacian straight from the
// graph's weights and degrees in double (no code shared with the solver).
Eigen::MatrixXd dense_laplacian(const r1::Graph& g, double rho) {
  const Eigen::Index n = g.n;
  Eigen::VectorXd d(n);
  for (Eigen::Index i = 0; i < n; ++i) d(i) = static_cast<double>(g.degree[static_cast<std::size_t>(i)]) * 0x1p-32 + rho;
  Eigen::MatrixXd a = Eigen::MatrixXd::Constant(n, n, rho / static_cast<double>(n));
  for (std::uint32_t i = 0; i < g.n; ++i)
    for (std::uint64_t k = g.row_ptr[i]; k < g.row_ptr[i + 1]; ++k) a(i, g.col[k]) += static_cast<double>(g.w[k]) * 0x1p-32;
  const Eigen::VectorXd s = d.array().rsqrt();
  return Eigen::MatrixXd::Identity(n, n) - s.asDiagonal() * a * s.asDiagonal();
}

// Largest principal angle (radians) between the column spaces of two orthonormal n x k bases:
// asin of the largest singular value of the part of b outside span(a) (well conditioned for
// the tiny angles the tests bound, where acos of the cosines is not).
double max_angle(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  const Eigen::MatrixXd rest = b - a * (a.transpose() * b);
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(rest);
  return std::asin(std::min(1.0, svd.singularValues().maxCoeff()));
}

// A Hemera digest of everything a spectrum holds: the bit-identity check of reruns.
template <class Scalar>
std::string spectrum_digest(const r1::Spectrum<Scalar>& s) {
  std::vector<std::uint8_t> bytes;
  auto put = [&](const void* p, std::size_t len) {
    const auto* b = static_cast<const std::uint8_t*>(p);
    bytes.insert(bytes.end(), b, b + len);
  };
  put(s.eigenvalues.data(), sizeof s.eigenvalues);
  put(s.residuals.data(), sizeof s.residuals);
  for (const auto& u : s.u) put(u.data(), u.size() * sizeof(Scalar));
  put(&s.found, sizeof s.found);
  put(&s.restarts, sizeof s.restarts);
  put(&s.matvecs, sizeof s.matvecs);
  return r1::hemera::to_hex(r1::hemera::hash(bytes));
}

// Invariants every result must satisfy (R1-SPEC-060..063): lambda_1 = 0, ascending eigenvalues,
// residuals within the tolerance, unit and mutually orthogonal vectors, orthogonal to D^(1/2) 1.
template <class Scalar>
void check_invariants(const r1::Graph& g, const r1::Spectrum<Scalar>& s, double tol, double ortho_tol) {
  EXPECT_EQ(s.eigenvalues[0], 0.0);
  for (std::uint32_t c = 0; c < s.found; ++c) {
    EXPECT_LE(s.eigenvalues[c], s.eigenvalues[c + 1] + 1e-12) << c;
    EXPECT_LE(s.residuals[c + 1], tol) << "pair " << c + 2;
  }
  const Eigen::MatrixXd u = vectors(s);
  const Eigen::MatrixXd gram = u.transpose() * u;
  EXPECT_LT((gram - Eigen::MatrixXd::Identity(s.found, s.found)).cwiseAbs().maxCoeff(), ortho_tol);
  Eigen::VectorXd t(g.n);
  for (std::uint32_t i = 0; i < g.n; ++i) t(i) = std::sqrt(static_cast<double>(g.degree[i]) * 0x1p-32 + s.rho);
  t.normalize();
  EXPECT_LT((u.transpose() * t).cwiseAbs().maxCoeff(), ortho_tol);
  for (std::uint32_t c = s.found; c < 5; ++c)
    for (const Scalar& x : s.u[c]) EXPECT_EQ(to_d(x), 0.0);
}

r1::SpectralParams defaults() { return r1::SpectralParams{}; }

// The five smallest non-trivial values of a sorted spectrum.
std::array<double, 5> wanted(std::vector<double> all) {
  std::sort(all.begin(), all.end());
  std::array<double, 5> w{};
  for (int c = 0; c < 5; ++c) w[c] = all[static_cast<std::size_t>(c) + 1];
  return w;
}

TEST(Spectral, RingHasDoubleEigenvalues) {
  // lambda_k = 1 - cos(2 pi k / n), each k = 1..n/2-1 twice: the verification restart must find
  // the second copy of each (R1-SPEC-031..033).
  const std::uint32_t n = 200;
  const r1::Graph g = generated(r1::GenKind::kRing, n);
  std::vector<double> all;
  for (std::uint32_t k = 0; k < n; ++k) all.push_back(1 - std::cos(2 * std::numbers::pi * k / n));
  const auto want = wanted(all);
  for (const bool q32 : {true, false}) {
    const auto check = [&](const auto& s) {
      check_invariants(g, s, 1e-9, 1e-8);
      EXPECT_EQ(s.found, 5u);
      EXPECT_EQ(s.rho, 0.0);
      for (int c = 0; c < 5; ++c) EXPECT_NEAR(s.eigenvalues[c + 1], want[c], 1e-9) << c;
    };
    if (q32) {
      auto s = r1::spectral_embedding_q32(g, defaults());
      ASSERT_TRUE(s.is_ok()) << s.status().message();
      check(*s);
    } else {
      auto s = r1::spectral_embedding_f64(g, defaults());
      ASSERT_TRUE(s.is_ok()) << s.status().message();
      check(*s);
    }
  }
}

TEST(Spectral, PathEigenvalues) {
  // Path of n nodes, normalised Laplacian: lambda_k = 1 - cos(pi k / (n - 1)), k = 0..n-1.
  const std::uint32_t n = 150;
  const r1::Graph g = generated(r1::GenKind::kPath, n);
  auto s = r1::spectral_embedding_q32(g, defaults());
  ASSERT_TRUE(s.is_ok()) << s.status().message();
  check_invariants(g, *s, 1e-9, 1e-8);
  for (int k = 1; k <= 5; ++k) EXPECT_NEAR(s->eigenvalues[k], 1 - std::cos(std::numbers::pi * k / (n - 1)), 1e-9) << k;
}

TEST(Spectral, CompleteGraphBreaksDownAndRecovers) {
  // Every vector orthogonal to 1 is an eigenvector with n / (n - 1): each Lanczos step breaks
  // down at once and fresh vectors take over (R1-SPEC-024). n = 100 runs Lanczos, n = 20 dense.
  for (const std::uint32_t n : {100u, 20u}) {
    const r1::Graph g = generated(r1::GenKind::kComplete, n);
    auto s = r1::spectral_embedding_q32(g, defaults());
    ASSERT_TRUE(s.is_ok()) << s.status().message();
    check_invariants(g, *s, 1e-9, 1e-8);
    for (int k = 1; k <= 5; ++k) EXPECT_NEAR(s->eigenvalues[k], n / (n - 1.0), 1e-9) << n << " " << k;
    EXPECT_EQ(s->restarts == 0, n == 20u);
  }
}

TEST(Spectral, TorusRepeatedEigenvalues) {
  // 1 - (cos 2 pi a / A + cos 2 pi b / B + cos 2 pi c / C) / 3; on the cube 6x6x6 the lowest
  // non-zero value 1/6 has multiplicity 6, so u_2..u_6 are five vectors of one eigenspace.
  for (const auto& dims : {std::vector<std::int64_t>{6, 6, 6}, std::vector<std::int64_t>{5, 6, 8}}) {
    const r1::Graph g = generated(r1::GenKind::kTorus, std::nullopt, dims);
    std::vector<double> all;
    for (std::int64_t a = 0; a < dims[0]; ++a)
      for (std::int64_t b = 0; b < dims[1]; ++b)
        for (std::int64_t c = 0; c < dims[2]; ++c)
          all.push_back(1 - (std::cos(2 * std::numbers::pi * a / dims[0]) + std::cos(2 * std::numbers::pi * b / dims[1]) +
                             std::cos(2 * std::numbers::pi * c / dims[2])) / 3);
    const auto want = wanted(all);
    auto s = r1::spectral_embedding_q32(g, defaults());
    ASSERT_TRUE(s.is_ok()) << s.status().message();
    check_invariants(g, *s, 1e-9, 1e-8);
    for (int c = 0; c < 5; ++c) EXPECT_NEAR(s->eigenvalues[c + 1], want[c], 1e-9) << dims[0] << " " << c;
    // Each vector lies in its eigenvalue's eigenspace: the dense reference's projector keeps it,
    // up to the Davis-Kahan sin-theta bound ||u - P u|| <= ||L u - lambda u|| / gap, where gap is
    // the distance from lambda to the rest of the spectrum and the residual against the dense
    // double operator is the solver's (<= tol) plus ||L_Q32 - L|| <= degree * 2^-33 (each entry
    // of M rounded once); the unit vector's own Q32 rounding adds sqrt(n / 12) 2^-32.
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(dense_laplacian(g, 0));
    const Eigen::MatrixXd u = vectors(*s);
    const double rounding = std::sqrt(g.n / 12.0) * 0x1p-32;
    for (int c = 0; c < 5; ++c) {
      Eigen::VectorXd proj = Eigen::VectorXd::Zero(g.n);
      double gap = 2;
      for (Eigen::Index k = 0; k < es.eigenvalues().size(); ++k) {
        const double d = std::fabs(es.eigenvalues()(k) - want[c]);
        if (d < 1e-8) {
          proj += es.eigenvectors().col(k) * es.eigenvectors().col(k).dot(u.col(c));
        } else {
          gap = std::min(gap, d);
        }
      }
      const double bound = (s->residuals[c + 1] + 6 * 0x1p-33) / gap + rounding;
      EXPECT_LT((proj - u.col(c)).norm(), bound) << dims[0] << " " << c;
      // The bound is tight enough to mean something: well below the 1e-6 a stalled solve gave.
      EXPECT_LT(bound, 5e-8);
    }
  }
}

TEST(Spectral, GridMatchesEigenDense) {
  const r1::Graph g = generated(r1::GenKind::kGrid, std::nullopt, {17, 12});
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(dense_laplacian(g, 0));
  auto q = r1::spectral_embedding_q32(g, defaults());
  auto f = r1::spectral_embedding_f64(g, defaults());
  ASSERT_TRUE(q.is_ok() && f.is_ok());
  check_invariants(g, *q, 1e-9, 1e-8);
  check_invariants(g, *f, 1e-9, 1e-10);
  for (int c = 1; c <= 5; ++c) {
    EXPECT_NEAR(q->eigenvalues[c], es.eigenvalues()(c), 1e-9);
    EXPECT_NEAR(f->eigenvalues[c], es.eigenvalues()(c), 1e-11);
  }
  // The 17x12 grid's low spectrum is simple: compare the subspaces.
  EXPECT_LT(max_angle(es.eigenvectors().middleCols(1, 5), vectors(*q)), 1e-7);
  EXPECT_LT(max_angle(es.eigenvectors().middleCols(1, 5), vectors(*f)), 1e-7);
}

TEST(Spectral, SbmSubspaceMatchesEigenDense) {
  // Four communities: u_2..u_4 span the community indicators (a clear gap to the bulk).
  r1::GenParams p;
  p.kind = r1::GenKind::kSbm;
  p.n = 400;
  p.k = 4;
  p.p_in = 0.2;
  p.p_out = 0.01;
  const r1::Graph g = std::move(r1::build_graph(std::move(r1::generate(p)).value())).value();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(dense_laplacian(g, 0));
  for (const bool parallel : {false, true}) {
    r1::SpectralOptions o;
    o.parallel = parallel;
    auto q = r1::spectral_embedding_q32(g, defaults(), {}, o);
    ASSERT_TRUE(q.is_ok());
    check_invariants(g, *q, 1e-9, 1e-8);
    for (int c = 1; c <= 5; ++c) EXPECT_NEAR(q->eigenvalues[c], es.eigenvalues()(c), 1e-8);
    EXPECT_LT(max_angle(es.eigenvectors().middleCols(1, 3), vectors(*q).leftCols(3)), 1e-7);
  }
}

TEST(Spectral, SmallGraphsSolveDensely) {
  // n = 2..6: found = n - 1, the rest zero; eigenvalues against Eigen (R1-SPEC-050..051).
  const std::vector<std::vector<std::tuple<std::string, std::string, std::uint64_t>>> graphs = {
      {{"a", "b", 1}},
      {{"a", "b", 1}, {"b", "c", 2}},
      {{"a", "b", 1}, {"b", "c", 1}, {"c", "a", 1}},
      {{"a", "b", 1}, {"a", "c", 1}, {"a", "d", 3}},
      {{"a", "b", 1}, {"b", "c", 1}, {"c", "d", 1}, {"d", "e", 1}, {"e", "a", 5}},
      {{"a", "b", 1}, {"a", "c", 1}, {"a", "d", 1}, {"a", "e", 1}, {"a", "f", 1}, {"e", "f", 2}},
  };
  for (const auto& links : graphs) {
    const r1::Graph g = from_links(links);
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(dense_laplacian(g, 0));
    auto s = r1::spectral_embedding_q32(g, defaults());
    ASSERT_TRUE(s.is_ok()) << s.status().message();
    EXPECT_EQ(s->found, g.n - 1);
    EXPECT_EQ(s->restarts, 0u);
    check_invariants(g, *s, 1e-9, 1e-8);
    for (std::uint32_t c = 1; c < g.n; ++c) EXPECT_NEAR(s->eigenvalues[c], es.eigenvalues()(c), 1e-9) << g.n;
    for (std::uint32_t c = g.n; c < 6; ++c) EXPECT_EQ(s->eigenvalues[c], 0.0);
  }
}

TEST(Spectral, DisconnectedGraphUsesAutoRho) {
  // Two rings of 60 and 80: rho = mean weighted degree = 2 (decision 4), and u_2 separates them.
  std::vector<std::tuple<std::string, std::string, std::uint64_t>> links;
  for (int i = 0; i < 60; ++i) links.emplace_back("a" + std::to_string(i), "a" + std::to_string((i + 1) % 60), 1);
  for (int i = 0; i < 80; ++i) links.emplace_back("b" + std::to_string(i), "b" + std::to_string((i + 1) % 80), 1);
  const r1::Graph g = from_links(links);
  ASSERT_EQ(g.component_size.size(), 2u);
  auto s = r1::spectral_embedding_q32(g, defaults());
  ASSERT_TRUE(s.is_ok()) << s.status().message();
  EXPECT_EQ(s->rho, 2.0);
  check_invariants(g, *s, 1e-9, 1e-8);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(dense_laplacian(g, 2.0));
  for (int c = 1; c <= 5; ++c) EXPECT_NEAR(s->eigenvalues[c], es.eigenvalues()(c), 1e-9);
  // u_2 is constant in sign on each component, opposite between them.
  double lo_a = 1, hi_a = -1, lo_b = 1, hi_b = -1;
  for (std::uint32_t i = 0; i < g.n; ++i) {
    const double x = s->u[0][i].to_double();
    (g.component[i] == 0 ? lo_a : lo_b) = std::min(g.component[i] == 0 ? lo_a : lo_b, x);
    (g.component[i] == 0 ? hi_a : hi_b) = std::max(g.component[i] == 0 ? hi_a : hi_b, x);
  }
  EXPECT_TRUE((hi_a < 0 && lo_b > 0) || (lo_a > 0 && hi_b < 0)) << lo_a << " " << hi_a << " " << lo_b << " " << hi_b;
  // A forced rho is used as given.
  r1::SpectralParams p;
  p.rho = 0.5;
  auto f = r1::spectral_embedding_f64(g, p);
  ASSERT_TRUE(f.is_ok());
  EXPECT_EQ(f->rho, 0.5);
  check_invariants(g, *f, 1e-9, 1e-10);
}

TEST(Spectral, InputErrors) {
  // An isolated particle (only a self-loop) with rho forced to 0.
  const r1::Graph iso = from_links({{"a", "b", 1}, {"b", "c", 1}, {"d", "d", 1}, {"c", "a", 1}});
  r1::SpectralParams p;
  p.rho = 0.0;
  auto s = r1::spectral_embedding_q32(iso, p);
  ASSERT_FALSE(s.is_ok());
  EXPECT_EQ(s.status().kind(), r1::ErrorKind::kInput);
  EXPECT_NE(s.status().message().find("particle 3 has no links"), std::string::npos) << s.status().message();
  // Automatic rho handles it (the graph is disconnected).
  auto a = r1::spectral_embedding_q32(iso, defaults());
  ASSERT_TRUE(a.is_ok()) << a.status().message();
  EXPECT_GT(a->rho, 0.0);
  r1::SpectralParams bad;
  bad.rho = -1;
  EXPECT_EQ(r1::spectral_embedding_q32(iso, bad).status().kind(), r1::ErrorKind::kInput);
  bad = {};
  bad.basis = 8;
  EXPECT_EQ(r1::spectral_embedding_q32(iso, bad).status().kind(), r1::ErrorKind::kInput);
  bad = {};
  bad.tolerance = 0;
  EXPECT_EQ(r1::spectral_embedding_f64(iso, bad).status().kind(), r1::ErrorKind::kInput);
  const r1::Graph empty;
  EXPECT_EQ(r1::spectral_embedding_q32(empty, defaults()).status().kind(), r1::ErrorKind::kInput);
}

TEST(Spectral, Q32AndFp64Agree) {
  const r1::Graph g = generated(r1::GenKind::kTorus, std::nullopt, {5, 7, 9});
  auto q = r1::spectral_embedding_q32(g, defaults());
  auto f = r1::spectral_embedding_f64(g, defaults());
  ASSERT_TRUE(q.is_ok() && f.is_ok());
  for (int c = 1; c <= 5; ++c) EXPECT_NEAR(q->eigenvalues[c], f->eigenvalues[c], 1e-9);
  // Pairs 2-3 and 4-5 are double eigenvalues, 6 is simple (cycle of 9 then 7): compare spaces.
  const Eigen::MatrixXd uq = vectors(*q), uf = vectors(*f);
  EXPECT_LT(max_angle(uq.leftCols(2), uf.leftCols(2)), 1e-7);
  EXPECT_LT(max_angle(uq.middleCols(2, 2), uf.middleCols(2, 2)), 1e-7);
}

TEST(Spectral, RerunsAndTbbAreBitIdentical) {
  // A star of 40000: above the kernels' parallel threshold, eigenvalue 1 with multiplicity n - 2.
  // Every Lanczos step breaks down there, so a 12-vector basis (the smallest allowed) keeps the
  // fresh random vectors, and the test's time, down; bit-identity does not depend on the size.
  const r1::Graph g = generated(r1::GenKind::kStar, 40000);
  r1::SpectralOptions par;
  par.parallel = true;
  r1::SpectralParams small = defaults();
  small.basis = 12;
  auto a = r1::spectral_embedding_q32(g, small);
  auto b = r1::spectral_embedding_q32(g, small);
  auto c = r1::spectral_embedding_q32(g, small, {}, par);
  ASSERT_TRUE(a.is_ok() && b.is_ok() && c.is_ok());
  for (int k = 1; k <= 5; ++k) EXPECT_NEAR(a->eigenvalues[k], 1.0, 1e-9);
  check_invariants(g, *a, 1e-9, 1e-8);
  EXPECT_EQ(spectrum_digest(*a), spectrum_digest(*b));
  EXPECT_EQ(spectrum_digest(*a), spectrum_digest(*c));
  EXPECT_EQ(a->matvecs, c->matvecs);
  auto fa = r1::spectral_embedding_f64(g, small);
  auto fc = r1::spectral_embedding_f64(g, small, {}, par);
  ASSERT_TRUE(fa.is_ok() && fc.is_ok());
  EXPECT_EQ(spectrum_digest(*fa), spectrum_digest(*fc));
}

TEST(Spectral, MatrixMarketExportIsTheOperator) {
  const r1::Graph g = from_links({{"a", "b", 1}, {"b", "c", 3}, {"c", "a", 2}, {"c", "d", 1}, {"e", "f", 1}});
  auto op = r1::spectral_operator_q32(g, defaults());  // disconnected: rho > 0, rank-one lines
  ASSERT_TRUE(op.is_ok());
  r1::test::TempDir dir;
  const std::string path = (dir / "l.mtx").string();
  ASSERT_TRUE(r1::write_operator_matrix_market(*op, path).is_ok());
  std::istringstream in(r1::test::read_file(path));
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "%%MatrixMarket matrix coordinate real symmetric");
  Eigen::MatrixXd l = Eigen::MatrixXd::Zero(g.n, g.n);
  Eigen::VectorXd gv = Eigen::VectorXd::Zero(g.n);
  bool size_seen = false;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    if (line.rfind("%r1-rank-one ", 0) == 0) {
      std::string tag;
      int i = 0;
      double v = 0;
      ls >> tag >> i >> v;
      gv(i - 1) = v;
    } else if (line[0] != '%' && !size_seen) {
      size_seen = true;
    } else if (line[0] != '%') {
      int i = 0, j = 0;
      double v = 0;
      ls >> i >> j >> v;
      l(i - 1, j - 1) = l(j - 1, i - 1) = v;
    }
  }
  for (std::uint32_t i = 0; i < g.n; ++i) EXPECT_EQ(gv(i), op->g[i].to_double());
  // The exported matrix applied to a vector is the solver's operator, up to its roundings.
  std::vector<Q32> x(g.n), y(g.n);
  for (std::uint32_t i = 0; i < g.n; ++i) x[i] = Q32::from_decimal(std::to_string(i + 1));
  op->apply(x.data(), y.data());
  Eigen::VectorXd xv(g.n);
  for (std::uint32_t i = 0; i < g.n; ++i) xv(i) = x[i].to_double();
  const Eigen::VectorXd ref = l * xv - gv * gv.dot(xv);
  for (std::uint32_t i = 0; i < g.n; ++i) EXPECT_NEAR(y[i].to_double(), ref(i), 1e-9);
  // And it matches the independent dense Laplacian to the Q32 entry rounding.
  const Eigen::MatrixXd dense = dense_laplacian(g, op->rho.to_double());
  EXPECT_LT((l - gv * gv.transpose() - dense).cwiseAbs().maxCoeff(), 1e-9);
}

// R1-SPEC-005: y = L~ x with one rounding per row, whichever path the row takes (the unchecked
// i128 sum for x raws below 2^57, the checked exact sum above), against cpp_int.
TEST(Spectral, OperatorApplicationIsExactOnBothPaths) {
  using boost::multiprecision::cpp_int;
  const r1::Graph g = from_links({{"a", "b", 1}, {"b", "c", 3}, {"c", "a", 2}, {"c", "d", 1}, {"e", "f", 5}, {"f", "a", 1}});
  for (const double rho : {0.0, 0.75}) {
    r1::SpectralParams params = defaults();
    params.rho = rho;
    auto op = r1::spectral_operator_q32(g, params);
    ASSERT_TRUE(op.is_ok()) << op.status().message();
    for (const int bits : {40, 60}) {
      SCOPED_TRACE(bits);
      std::vector<r1::fx::Q32> x(g.n), y(g.n);
      for (std::size_t i = 0; i < g.n; ++i) {
        const auto r = r1::rng::bits(5, i, static_cast<std::uint64_t>(bits));
        x[i] = r1::fx::Q32::from_raw(static_cast<std::int64_t>(r >> (64 - bits)) * ((r & 1) ? -1 : 1));
      }
      op->apply(x.data(), y.data());
      auto rne32 = [](const cpp_int& v) {  // RNE(v / 2^32)
        const cpp_int den = cpp_int(1) << 32;
        cpp_int q = v / den;
        if (q * den > v) --q;
        const cpp_int rem = v - q * den;
        if (2 * rem > den || (2 * rem == den && (q & 1) != 0)) ++q;
        return q;
      };
      cpp_int c = 0;
      for (std::size_t j = 0; j < op->g.size(); ++j) c += cpp_int(op->g[j].raw) * x[j].raw;
      c = rne32(c);
      for (std::size_t i = 0; i < g.n; ++i) {
        cpp_int v = cpp_int(x[i].raw) << 32;
        for (std::uint64_t k = g.row_ptr[i]; k < g.row_ptr[i + 1]; ++k) v -= cpp_int(op->m[k].raw) * x[g.col[k]].raw;
        if (!op->g.empty()) v -= cpp_int(op->g[i].raw) * c;
        EXPECT_EQ(cpp_int(y[i].raw), rne32(v)) << "row " << i << " rho " << rho;
      }
    }
  }
}

}  // namespace
