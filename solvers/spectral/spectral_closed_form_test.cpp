// The spectral solver against graphs whose normalised Laplacian spectrum is known in closed form
// (R1-SPEC-020..035, proofs/spectral_multiplicity.md): rings, paths, 2D and 3D tori, stars,
// complete and complete bipartite graphs, hypercubes and spiders (symmetric twins). Every wanted
// eigenvalue must come out with its multiplicity, and every returned vector must lie in its
// eigenspace: an independent fp64 residual and the closed-form gap bound the distance
// (Davis-Kahan). Built twice: the fast sizes for every run, R1_SPECTRAL_LARGE adds the large ones
// (the 1000- and 3000-rings, Q_10, the 20^3 torus; label slow).
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <bit>
#include <numbers>
#include <string>
#include <type_traits>
#include <vector>

#include "block_lanczos.hpp"
#include "r1/solvers/panel.hpp"
#include "r1/solvers/spectral.hpp"
#include "spectral_test_support.hpp"
#include "trivial_vector.hpp"

namespace {

using namespace r1::spectral_test;
using r1::GenKind;
using r1::Graph;
constexpr double kPi = std::numbers::pi;

struct Family {
  std::string name;
  Graph graph;
  std::vector<double> spectrum;  // all n eigenvalues, closed form, any order
};

Family ring(std::uint32_t n) {
  std::vector<double> s;
  for (std::uint32_t k = 0; k < n; ++k) s.push_back(1 - std::cos(2 * kPi * k / n));
  return {"ring " + std::to_string(n), generated(GenKind::kRing, n), s};
}

Family path(std::uint32_t n) {
  std::vector<double> s;
  for (std::uint32_t k = 0; k < n; ++k) s.push_back(1 - std::cos(kPi * k / (n - 1)));
  return {"path " + std::to_string(n), generated(GenKind::kPath, n), s};
}

// A periodic 2D grid (degree 4 everywhere): 1 - (cos 2 pi a / A + cos 2 pi b / B) / 2. The open
// grid's normalised Laplacian has no closed form (degrees 2, 3 and 4); spectral_test.cpp checks
// it against Eigen's dense solver.
Family torus2(std::uint32_t a, std::uint32_t b) {
  std::vector<Link> links;
  auto name = [](std::uint32_t x, std::uint32_t y) { return std::to_string(x) + "," + std::to_string(y); };
  for (std::uint32_t x = 0; x < a; ++x)
    for (std::uint32_t y = 0; y < b; ++y) {
      links.emplace_back(name(x, y), name((x + 1) % a, y), 1);
      links.emplace_back(name(x, y), name(x, (y + 1) % b), 1);
    }
  std::vector<double> s;
  for (std::uint32_t x = 0; x < a; ++x)
    for (std::uint32_t y = 0; y < b; ++y) s.push_back(1 - (std::cos(2 * kPi * x / a) + std::cos(2 * kPi * y / b)) / 2);
  return {"2D torus " + std::to_string(a) + "x" + std::to_string(b), from_links(links), s};
}

Family torus3(std::int64_t a, std::int64_t b, std::int64_t c) {
  std::vector<double> s;
  for (std::int64_t x = 0; x < a; ++x)
    for (std::int64_t y = 0; y < b; ++y)
      for (std::int64_t z = 0; z < c; ++z)
        s.push_back(1 - (std::cos(2 * kPi * x / a) + std::cos(2 * kPi * y / b) + std::cos(2 * kPi * z / c)) / 3);
  return {"3D torus " + std::to_string(a) + "x" + std::to_string(b) + "x" + std::to_string(c),
          generated(GenKind::kTorus, std::nullopt, {a, b, c}), s};
}

// Star on n particles: 0, 1 (n - 2 times), 2.
Family star(std::uint32_t n) {
  std::vector<double> s(n, 1.0);
  s[0] = 0;
  s[1] = 2;
  return {"star " + std::to_string(n), generated(GenKind::kStar, n), s};
}

// Complete graph: 0, n / (n - 1) (n - 1 times).
Family complete(std::uint32_t n) {
  std::vector<double> s(n, n / (n - 1.0));
  s[0] = 0;
  return {"complete " + std::to_string(n), generated(GenKind::kComplete, n), s};
}

// Complete bipartite K_(a,b): 0, 1 (a + b - 2 times), 2.
Family bipartite(std::uint32_t a, std::uint32_t b) {
  std::vector<Link> links;
  for (std::uint32_t i = 0; i < a; ++i)
    for (std::uint32_t j = 0; j < b; ++j) links.emplace_back("l" + std::to_string(i), "r" + std::to_string(j), 1);
  std::vector<double> s(a + b, 1.0);
  s[0] = 0;
  s[1] = 2;
  return {"K_" + std::to_string(a) + "," + std::to_string(b), from_links(links), s};
}

// Hypercube Q_d (regular of degree d): 2k / d with multiplicity C(d, k).
Family hypercube(std::uint32_t d) {
  std::vector<Link> links;
  const std::uint32_t n = 1u << d;
  for (std::uint32_t v = 0; v < n; ++v)
    for (std::uint32_t bit = 0; bit < d; ++bit)
      if ((v & (1u << bit)) == 0) links.emplace_back("q" + std::to_string(v), "q" + std::to_string(v | (1u << bit)), 1);
  std::vector<double> s;
  for (std::uint32_t v = 0; v < n; ++v) s.push_back(2.0 * std::popcount(v) / d);
  return {"Q_" + std::to_string(d), from_links(links), s};
}

// A spider: k identical arms of `len` particles joined at a centre, symmetric twins of one
// another. Antisymmetric arm combinations (centre 0) give 1 - cos((2m + 1) pi / (2 len)),
// m < len, each k - 1 times; symmetric ones 1 - cos(m pi / len), m = 0..len (derivation:
// proofs/spectral_multiplicity.md). The lowest non-zero eigenvalue has multiplicity k - 1.
Family spider(std::uint32_t k, std::uint32_t len) {
  std::vector<Link> links;
  for (std::uint32_t a = 0; a < k; ++a) {
    std::string prev = "centre";
    for (std::uint32_t i = 1; i <= len; ++i) {
      const std::string cur = "a" + std::to_string(a) + "/" + std::to_string(i);
      links.emplace_back(prev, cur, 1);
      prev = cur;
    }
  }
  std::vector<double> s;
  for (std::uint32_t m = 0; m < len; ++m)
    for (std::uint32_t c = 0; c + 1 < k; ++c) s.push_back(1 - std::cos((2 * m + 1) * kPi / (2 * len)));
  for (std::uint32_t m = 0; m <= len; ++m) s.push_back(1 - std::cos(m * kPi / len));
  return {"spider " + std::to_string(k) + "x" + std::to_string(len), from_links(links), s};
}

// The distance from the eigenspace of want[c], bounded through an independent fp64 residual: a
// unit vector u with ||L u - lambda u|| = r lies within r / gap of the eigenspace of the
// eigenvalues equal to want[c], gap the distance from lambda to the rest of the spectrum
// (Davis-Kahan sin theta). Returns the bound; the residual goes to `residual`.
double eigenspace_bound(const Family& f, double rho, const Eigen::VectorXd& u, double lambda, double want,
                        double& residual) {
  residual = (apply_laplacian(f.graph, rho, u) - lambda * u).norm();
  double gap = 2;
  for (const double mu : f.spectrum)
    if (std::fabs(mu - want) > 1e-12) gap = std::min(gap, std::fabs(mu - lambda));
  return residual / gap;
}

// Every wanted eigenvalue with its multiplicity, every vector in its eigenspace: the public
// result (eigenvalues, invariants, independent residuals of the Q32 unit vectors, whose entries
// carry 2^-33 of rounding each), then the solver's own vectors before that rounding (2^-48), for
// the eigenspace bound.
template <class Scalar>
void expect_closed_form(const Family& f, const r1::Spectrum<Scalar>& s, double tol) {
  SCOPED_TRACE(f.name);
  ASSERT_EQ(f.spectrum.size(), f.graph.n);
  check_invariants(f.graph, s, tol, 1e-8);
  ASSERT_EQ(s.found, 5u);
  const auto want = wanted(f.spectrum);
  const Eigen::MatrixXd u = vectors(s);
  // ||L du|| <= 2 ||du|| for the output rounding du (0 in fp64).
  const double rounding = std::is_same_v<Scalar, double> ? 0.0 : 2 * std::sqrt(f.graph.n / 4.0) * 0x1p-33;
  for (int c = 0; c < 5; ++c) {
    // |lambda - exact| <= residual (a Rayleigh quotient is within its residual of an
    // eigenvalue) plus the Q32 operator's entry rounding (degree x 2^-33 per row).
    EXPECT_NEAR(s.eigenvalues[c + 1], want[c], 2 * tol) << "pair " << c + 2;
    double residual = 0;
    eigenspace_bound(f, s.rho, u.col(c), s.eigenvalues[c + 1], want[c], residual);
    EXPECT_LE(residual, 2 * tol + rounding) << "pair " << c + 2;
  }
}

// The canonical solve's unrounded vectors (the Q32 domain at 2^-48): each within 10^-3 of its
// eigenspace by the independent bound.
void expect_in_eigenspaces(const Family& f) {
  SCOPED_TRACE(f.name);
  const r1::SpectralParams params;
  auto op = r1::spectral_operator_q32(f.graph, params);
  ASSERT_TRUE(op.is_ok());
  const int frac = r1::spectral::basis_frac(op->e);
  const r1::spectral::PanelOps<r1::fx::Q32> ops(f.graph.n, op->e, false, frac);
  const auto trivial = r1::spectral::scaled_trivial(f.graph, op->rho, op->e, frac);
  const auto cfg = r1::spectral::canonical_config(f.graph.n, 5, params, r1::spectral::kSpectralSeed);
  const auto out = r1::spectral::block_lanczos<r1::fx::Q32>(*op, ops, trivial, cfg, {});
  ASSERT_EQ(out.pairs.size(), 5u);
  const auto want = wanted(f.spectrum);
  for (int c = 0; c < 5; ++c) {
    Eigen::VectorXd x(f.graph.n);
    for (std::uint32_t i = 0; i < f.graph.n; ++i) x(i) = std::ldexp(static_cast<double>(out.pairs[c].x[i].raw), -frac);
    x.normalize();
    double residual = 0;
    const double bound = eigenspace_bound(f, op->rho.to_double(), x, out.pairs[c].lambda, want[c], residual);
    EXPECT_LE(residual, 2 * params.tolerance) << "pair " << c + 2;
    EXPECT_LT(bound, 1e-3) << "pair " << c + 2 << ": residual " << residual;
  }
}

void check_family(const Family& f, bool fp64 = true) {
  const r1::SpectralParams params;
  auto q = r1::spectral_embedding_q32(f.graph, params);
  ASSERT_TRUE(q.is_ok()) << q.status().message();
  expect_closed_form(f, *q, params.tolerance);
  EXPECT_LT(q->restarts, 1000u) << f.name << ": the solve reached the restart cap";
  expect_in_eigenspaces(f);
  if (!fp64) return;
  auto d = r1::spectral_embedding_f64(f.graph, params);
  ASSERT_TRUE(d.is_ok()) << d.status().message();
  expect_closed_form(f, *d, params.tolerance);
}

#ifndef R1_SPECTRAL_LARGE

TEST(SpectralClosedForm, Rings) {
  // Every non-zero eigenvalue of a cycle is double: u_2, u_3 span the first frequency.
  for (const std::uint32_t n : {100u, 300u}) check_family(ring(n));
}

TEST(SpectralClosedForm, Paths) {
  for (const std::uint32_t n : {150u, 400u}) check_family(path(n));
}

TEST(SpectralClosedForm, TwoDimensionalTori) {
  check_family(torus2(12, 12));  // lowest non-zero value 4 times
  check_family(torus2(10, 16));
}

TEST(SpectralClosedForm, ThreeDimensionalTori) {
  check_family(torus3(6, 6, 6));  // lowest non-zero value 6 times: u_2..u_6 all in it
  check_family(torus3(5, 6, 8));
}

TEST(SpectralClosedForm, StarsCompleteAndBipartite) {
  // One eigenvalue fills the whole wanted window: every step breaks down (R1-SPEC-024).
  check_family(star(200));
  check_family(complete(100));
  check_family(bipartite(40, 57));
}

TEST(SpectralClosedForm, Hypercubes) {
  check_family(hypercube(7));  // 2/7 seven times
  check_family(hypercube(8));
}

TEST(SpectralClosedForm, SpidersWithTwinArms) {
  check_family(spider(4, 30));  // 3 copies, one simple, then 3 copies again
  check_family(spider(6, 20));  // 5 copies: the whole window
}

// The hypothesis the multiplicity argument rests on (proofs/spectral_multiplicity.md): the
// canonical start block's projection onto each wanted eigenspace has full rank, well away from
// singular. Checked on the 1000-ring's first two frequencies (cos/sin pairs, closed form), and on
// the wanted eigenspaces of the 6x6x6 torus (six-dimensional), Q_7 (seven), the 4-arm spider
// (three) and K_40,57 (95), taken from Eigen's dense solver at the closed-form eigenvalue. The
// smallest singular value of Z^T X0 (Z an orthonormal eigenspace basis, X0 the unit start block,
// its b = 7 columns; at most 5 directions needed) is compared with sqrt(dim / n), its typical size for a random block.
TEST(SpectralMultiplicity, StartBlockSeesEveryWantedEigenspace) {
  struct Space {
    std::string name;
    Graph graph;
    Eigen::MatrixXd basis;  // n x r orthonormal basis of the eigenspace
  };
  std::vector<Space> spaces;
  const std::uint32_t n = 1000;
  for (const int k : {1, 2}) {
    // The ring generator links i to i + 1, so particle i is node i.
    Eigen::MatrixXd z(n, 2);
    for (std::uint32_t i = 0; i < n; ++i) {
      z(i, 0) = std::cos(2 * kPi * k * i / n);
      z(i, 1) = std::sin(2 * kPi * k * i / n);
    }
    z.col(0).normalize();
    z.col(1).normalize();
    spaces.push_back({"ring 1000, k = " + std::to_string(k), generated(GenKind::kRing, n), z});
  }
  for (Family f : {torus3(6, 6, 6), hypercube(7), spider(4, 30), bipartite(40, 57)}) {
    const double mu = wanted(f.spectrum)[0];
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(dense_laplacian(f.graph, 0));
    std::vector<Eigen::Index> cols;
    for (Eigen::Index i = 0; i < es.eigenvalues().size(); ++i)
      if (std::fabs(es.eigenvalues()(i) - mu) < 1e-9) cols.push_back(i);
    Eigen::MatrixXd z(f.graph.n, static_cast<Eigen::Index>(cols.size()));
    for (std::size_t j = 0; j < cols.size(); ++j) z.col(static_cast<Eigen::Index>(j)) = es.eigenvectors().col(cols[j]);
    const std::size_t copies = std::count(f.spectrum.begin(), f.spectrum.end(), mu);
    ASSERT_EQ(cols.size(), copies) << f.name << ": dense and closed-form multiplicities differ";
    spaces.push_back({f.name, std::move(f.graph), z});
  }
  for (const Space& sp : spaces) {
    SCOPED_TRACE(sp.name);
    ASSERT_LT((sp.basis.transpose() * sp.basis - Eigen::MatrixXd::Identity(sp.basis.cols(), sp.basis.cols())).cwiseAbs().maxCoeff(), 1e-10);
    const Eigen::MatrixXd lz = dense_laplacian(sp.graph, 0) * sp.basis;
    const double mu = (sp.basis.transpose() * lz).trace() / static_cast<double>(sp.basis.cols());
    ASSERT_LT((lz - mu * sp.basis).norm(), 1e-9) << "not an eigenspace";
    auto op = r1::spectral_operator_q32(sp.graph, r1::SpectralParams{});
    ASSERT_TRUE(op.is_ok());
    const r1::spectral::PanelOps<r1::fx::Q32> ops(sp.graph.n, op->e, false, 48);
    const auto trivial = r1::spectral::scaled_trivial(sp.graph, op->rho, op->e, 48);
    const r1::spectral::BlockLanczosConfig cfg;
    const auto x0 = r1::spectral::start_block<r1::fx::Q32>(*op, ops, trivial, cfg);
    const Eigen::Index b = cfg.block;
    ASSERT_EQ(x0.size(), cfg.block);
    Eigen::MatrixXd x(sp.graph.n, b);
    for (Eigen::Index c = 0; c < b; ++c) {
      for (std::uint32_t i = 0; i < sp.graph.n; ++i) x(i, c) = std::ldexp(static_cast<double>(x0[c][i].raw), -48);
      x.col(c).normalize();
    }
    EXPECT_LT((x.transpose() * x - Eigen::MatrixXd::Identity(b, b)).cwiseAbs().maxCoeff(), 1e-12);
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(sp.basis.transpose() * x);
    const double smallest = svd.singularValues()(std::min<Eigen::Index>(sp.basis.cols(), 5) - 1);
    const double typical = std::sqrt(static_cast<double>(sp.basis.cols()) / sp.graph.n);
    EXPECT_GT(smallest, 0.05 * typical) << "singular values " << svd.singularValues().transpose();
  }
}

// The argument's other half: a block narrower than the multiplicity cannot see every copy. With
// one vector per block, the ring's second copies stay out of reach and the solve returns the
// first five distinct frequencies instead of each of them twice; with the canonical width of 7
// (any width of at least 5) every copy is found. Proves the closed-form tests above can fail.
TEST(SpectralMultiplicity, OneVectorPerBlockMissesTheSecondCopies) {
  const Family f = ring(300);
  auto op = r1::spectral_operator_q32(f.graph, r1::SpectralParams{});
  ASSERT_TRUE(op.is_ok());
  const r1::spectral::PanelOps<r1::fx::Q32> ops(f.graph.n, op->e, false, 48);
  const auto trivial = r1::spectral::scaled_trivial(f.graph, op->rho, op->e, 48);
  const auto want = wanted(f.spectrum);
  for (const std::uint32_t b : {1u, 7u}) {
    SCOPED_TRACE(b);
    r1::spectral::BlockLanczosConfig cfg;
    cfg.block = b;
    cfg.basis = 40 * b;
    cfg.keep = 15 * b;
    cfg.max_cycles = 200;
    cfg.seed = 0x72312d7370656374u;
    const auto out = r1::spectral::block_lanczos<r1::fx::Q32>(*op, ops, trivial, cfg, {});
    ASSERT_EQ(out.pairs.size(), 5u);
    int matches = 0;
    for (int c = 0; c < 5; ++c) matches += std::fabs(out.pairs[c].lambda - want[c]) < 1e-9;
    if (b == 1) {
      // The distinct values 1 - cos(2 pi k / n), k = 1..5, one copy each.
      for (int c = 0; c < 5; ++c) EXPECT_NEAR(out.pairs[c].lambda, 1 - std::cos(2 * kPi * (c + 1) / 300), 1e-9) << c;
      EXPECT_LT(matches, 5);
    } else {
      EXPECT_EQ(matches, 5);
    }
  }
}

#else  // R1_SPECTRAL_LARGE: the sizes the issue names, in the slow label

TEST(SpectralClosedFormLarge, RingsOf1000And3000) {
  check_family(ring(1000));
  check_family(ring(3000), false);
}

TEST(SpectralClosedFormLarge, Path1000) { check_family(path(1000), false); }

TEST(SpectralClosedFormLarge, Grid2DAndTorus3D) {
  check_family(torus2(40, 40), false);
  check_family(torus3(10, 10, 10), false);
  check_family(torus3(20, 20, 20), false);
}

TEST(SpectralClosedFormLarge, LargeSymmetricFamilies) {
  check_family(hypercube(10), false);
  check_family(star(5000), false);
  check_family(complete(600), false);
  check_family(bipartite(300, 700), false);
  check_family(spider(5, 200), false);
}

#endif

// The filter's scalar K (R1-SPEC-081): -1 at al, the damped interval inside the band
// 1 / T_d((c - al) / e) (T_d(x) = cosh(d acosh x) for x >= 1), increasing on [0, a], its slope the
// derivative of the closed form; no L~ estimate inside the band (R1-SPEC-082).
TEST(SpectralFilter, ScalarRecurrenceIsTheScaledChebyshevPolynomial) {
  for (const std::uint32_t d : {2u, 5u, 12u, 40u}) {
    const r1::spectral::ChebyshevFilter f{d, 0.58, 0.5695};
    const double x_al = (f.c() - f.al) / f.e(), t_al = std::cosh(d * std::acosh(x_al));
    const auto closed = [&](double lam) {
      const double x = (f.c() - lam) / f.e();
      const double t = x >= 1 ? std::cosh(d * std::acosh(x)) : std::cos(d * std::acos(std::max(-1.0, x)));
      return -t / t_al;
    };
    EXPECT_NEAR(f.value(f.al), -1.0, 1e-13) << d;
    for (double lam = 0; lam <= 2; lam += 0.01)
      EXPECT_NEAR(f.value(lam), closed(lam), 1e-10 * std::max(1.0, std::fabs(closed(lam)))) << d << " " << lam;
    const double band = std::fabs(f.value(f.a));
    EXPECT_NEAR(band, 1 / t_al, 1e-13);
    for (double lam = f.a; lam <= 2; lam += 0.003) EXPECT_LE(std::fabs(f.value(lam)), band * (1 + 1e-12)) << lam;
    double prev = f.value(0);
    for (double lam = 0.001; lam <= f.a; lam += 0.001) {
      const auto [v, slope] = f.value_slope(lam);
      EXPECT_GT(v, prev) << lam;
      EXPECT_GT(slope, 0) << lam;
      const double h = 1e-6;
      EXPECT_NEAR(slope, (f.value(lam + h) - f.value(lam - h)) / (2 * h), 1e-5 * std::max(1.0, slope)) << lam;
      prev = v;
    }
    EXPECT_TRUE(std::isinf(f.residual_estimate(-band / 2, 1e-12)));
    // A Ritz value of an eigenvector at mu with a K-residual est: est / K'(mu) at least.
    const double mu = 0.57, theta = f.value(mu);
    EXPECT_GE(f.residual_estimate(theta, 1e-6), 1e-6 / f.value_slope(mu).second * (1 - 1e-9));
  }
}

}  // namespace
