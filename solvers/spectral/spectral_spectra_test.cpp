// The spectral solver against an independent one on random graphs (RapidCheck): Spectra's
// shift-invert Lanczos on the same operator, built here in fp64 from the graph (no code shared
// with the solver). Per case: the five eigenvalues with multiplicity, each cluster's eigenspace
// by principal angles (Davis-Kahan: within sqrt(c) residual / gap), the residuals and
// orthogonality of R1-SPEC-060..063, and the Q32 and fp64 domains against each other
// (proofs/spectral_multiplicity.md). The random graphs carry twin arms, so repeated eigenvalues
// are common, not an accident.
#include <gtest/gtest.h>
#include <rapidcheck.h>

#include <Spectra/MatOp/DenseSymShiftSolve.h>
#include <Spectra/SymEigsShiftSolver.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "rc_cases.hpp"
#include "r1/solvers/spectral.hpp"
#include "spectral_test_support.hpp"

namespace {

using namespace r1::spectral_test;

// A random graph: a random tree of `core` particles with extra random links (weights 1..4), k
// identical arms of `len` particles hung from one core particle (twins: the antisymmetric arm
// modes repeat k - 1 times, low in the spectrum when the arms are long), and optionally a
// separate path, which makes the graph disconnected (then rho > 0, R1-SPEC-002).
struct Case {
  std::vector<Link> links;
  std::string summary;
};

Case random_case() {
  Case c;
  const auto core = *rc::gen::inRange<std::uint32_t>(66, 160);
  const auto extra = *rc::gen::inRange<std::uint32_t>(0, 2 * core);
  const auto arms = *rc::gen::inRange<std::uint32_t>(0, 6);
  const auto len = *rc::gen::inRange<std::uint32_t>(4, 30);
  const auto arm_w = *rc::gen::inRange<std::uint64_t>(1, 4);
  const auto split = *rc::gen::inRange(0, 4) == 0;
  auto node = [](std::uint32_t i) { return "c" + std::to_string(i); };
  for (std::uint32_t i = 1; i < core; ++i)
    c.links.emplace_back(node(*rc::gen::inRange<std::uint32_t>(0, i)), node(i), *rc::gen::inRange<std::uint64_t>(1, 5));
  for (std::uint32_t e = 0; e < extra; ++e) {
    const auto a = *rc::gen::inRange<std::uint32_t>(0, core), b = *rc::gen::inRange<std::uint32_t>(0, core);
    if (a != b) c.links.emplace_back(node(a), node(b), *rc::gen::inRange<std::uint64_t>(1, 5));
  }
  const std::string hub = node(*rc::gen::inRange<std::uint32_t>(0, core));
  for (std::uint32_t a = 0; a < arms; ++a) {
    std::string prev = hub;
    for (std::uint32_t i = 0; i < len; ++i) {
      const std::string cur = "a" + std::to_string(a) + "/" + std::to_string(i);
      c.links.emplace_back(prev, cur, arm_w);
      prev = cur;
    }
  }
  if (split)
    for (std::uint32_t i = 0; i + 1 < 6; ++i) c.links.emplace_back("p" + std::to_string(i), "p" + std::to_string(i + 1), 1);
  c.summary = "core " + std::to_string(core) + " + " + std::to_string(extra) + " links, " + std::to_string(arms) +
              " arms of " + std::to_string(len) + (split ? ", split" : "");
  return c;
}

std::string sci(double x) {
  std::ostringstream o;
  o.precision(3);
  o << std::scientific << x;
  return o.str();
}

struct Independent {
  Eigen::VectorXd values;   // ascending, the trivial 0 first
  Eigen::MatrixXd vectors;  // matching unit columns
  double residual = 0;      // the largest ||L x - lambda x|| among them
};

// Spectra's shift-invert solver on the dense fp64 operator (rho included), sigma just below 0
// (L~ is positive semi-definite, so L~ - sigma I is positive definite), the smallest `nev`
// eigenpairs, ascending. Spectra's Lanczos is itself a single-vector method: with a short basis
// it misses copies of repeated eigenvalues (it did on these graphs, returning a 3-fold twin-arm
// eigenvalue twice), so its basis spans the whole space here (ncv = n, at most ~350), and then
// every copy is in it.
Independent spectra_smallest(const r1::Graph& g, double rho, int nev) {
  const Eigen::MatrixXd l = dense_laplacian(g, rho);
  Spectra::DenseSymShiftSolve<double> op(l);
  const Eigen::Index ncv = l.rows();
  Spectra::SymEigsShiftSolver<Spectra::DenseSymShiftSolve<double>> eigs(op, nev, ncv, -1e-3);
  eigs.init();
  eigs.compute(Spectra::SortRule::LargestMagn, 10000, 1e-13);
  RC_ASSERT(eigs.info() == Spectra::CompInfo::Successful);
  const Eigen::VectorXd v = eigs.eigenvalues();
  const Eigen::MatrixXd x = eigs.eigenvectors();
  std::vector<Eigen::Index> order(static_cast<std::size_t>(v.size()));
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<Eigen::Index>(i);
  std::sort(order.begin(), order.end(), [&](Eigen::Index a, Eigen::Index b) { return v(a) < v(b); });
  Independent out{Eigen::VectorXd(v.size()), Eigen::MatrixXd(x.rows(), x.cols())};
  for (std::size_t i = 0; i < order.size(); ++i) {
    out.values(static_cast<Eigen::Index>(i)) = v(order[i]);
    out.vectors.col(static_cast<Eigen::Index>(i)) = x.col(order[i]);
  }
  // Spectra's own answer must be sound before it judges anything: residuals at its tolerance.
  for (Eigen::Index c = 0; c < out.values.size(); ++c)
    out.residual = std::max(out.residual, (l * out.vectors.col(c) - out.values(c) * out.vectors.col(c)).norm());
  RC_ASSERT(out.residual < 1e-10);
  return out;
}

// Eigenvalues closer than this are one cluster: their eigenvectors are compared as one space.
constexpr double kClusterGap = 1e-6;

// r1's result against Spectra's: eigenvalues one by one (with multiplicity), then each cluster
// of r1's eigenvalues as a space: a cluster wholly inside the window spans Spectra's eigenspace
// of that cluster; one cut by the window's end lies inside it. Davis-Kahan bounds each side's
// distance from the true eigenspace by sqrt(c) residual / gap (gap: from the cluster to the rest
// of the spectrum). Q32 iterates on the operator with entries rounded to 2^-33 (R1-SPEC-003),
// an eigenvector of which is within ||dL|| / gap of the exact one (||dL|| at most 2^-33 times
// the longest row, Gershgorin, plus 2^-32 sqrt(n) for the rank-one term), and rounds its outputs
// to 2^-33 per entry.
template <class Scalar>
void compare(const r1::Spectrum<Scalar>& s, const Independent& ind, double rho, const r1::Graph& g) {
  RC_ASSERT(s.found == 5u);
  RC_ASSERT(s.eigenvalues[0] == 0.0);
  RC_LOG() << (std::is_same_v<Scalar, double> ? "fp64" : "q32") << " lambda_2..6";
  for (int c = 1; c <= 5; ++c) RC_LOG() << ' ' << sci(s.eigenvalues[c]);
  RC_LOG() << "; Spectra";
  for (Eigen::Index c = 1; c < std::min<Eigen::Index>(8, ind.values.size()); ++c) RC_LOG() << ' ' << sci(ind.values(c));
  RC_LOG() << '\n';
  double max_residual = 0;
  for (int c = 1; c <= 5; ++c) {
    RC_ASSERT(s.residuals[c] <= 1e-9);
    max_residual = std::max(max_residual, s.residuals[c]);
    if (!(std::fabs(s.eigenvalues[c] - ind.values(c)) < 1e-9))
      RC_FAIL("lambda_" + std::to_string(c + 1) + " " + sci(s.eigenvalues[c]) + " vs Spectra " +
              sci(ind.values(c)));
  }
  double rounding = 0, operator_error = 0;
  if (std::is_same_v<Scalar, r1::fx::Q32>) {
    std::uint64_t longest = 0;
    for (std::uint32_t i = 0; i < g.n; ++i) longest = std::max(longest, g.row_ptr[i + 1] - g.row_ptr[i]);
    rounding = 0x1p-33 * std::sqrt(static_cast<double>(g.n));
    operator_error = 0x1p-33 * static_cast<double>(longest) + (rho > 0 ? 0x1p-32 * std::sqrt(static_cast<double>(g.n)) : 0.0);
  }
  const Eigen::MatrixXd u = vectors(s);
  Eigen::VectorXd t = degrees(g, rho).array().sqrt();
  t.normalize();
  // The residuals r1 reports are those of R1-SPEC-061: of L u - lambda u in the complement of the
  // trivial vector t (the exact operator's null vector here), not the full residual, which also
  // holds lambda times u's tiny trivial component. They hold against the exact fp64 operator, up
  // to the operator's and the output's rounding (|L~| <= 2, so a rounding of u moves L u - lambda u
  // by at most 3 |du|; the projection only shortens), and up to the floating-point error of the
  // two residuals themselves: each entry of L u - lambda u summed in fp64 over at most n + 2 terms
  // is within gamma_(n+2) (|L| |u| + |lambda| |u|) of the exact one (Higham, Accuracy and
  // Stability, 3.1), this dense product's and r1's row sums alike, so the two norms may differ by
  // twice that bound's norm (near 10^-13 at a few hundred rows).
  const Eigen::MatrixXd l = dense_laplacian(g, rho);
  const Eigen::MatrixXd lu = l * u;
  const Eigen::MatrixXd abs_lu = l.cwiseAbs() * u.cwiseAbs();
  const double terms = static_cast<double>(g.n) + 2, unit = 0x1p-53;
  const double gamma = terms * unit / (1 - terms * unit);
  for (int c = 0; c < 5; ++c) {
    const Eigen::VectorXd r = lu.col(c) - s.eigenvalues[c + 1] * u.col(c);
    const double independent = (r - t * t.dot(r)).norm();
    const double float_error =
        2 * gamma * (abs_lu.col(c) + std::fabs(s.eigenvalues[c + 1]) * u.col(c).cwiseAbs()).norm();
    if (!(independent <= s.residuals[c + 1] + operator_error + 3 * rounding + float_error))
      RC_FAIL("pair " + std::to_string(c + 2) + ": independent residual " + sci(independent) + ", reported " +
              sci(s.residuals[c + 1]) + ", floating-point allowance " + sci(float_error));
  }
  // Unit, orthogonal, and orthogonal to D^(1/2) 1 (R1-SPEC-062).
  RC_ASSERT((u.transpose() * u - Eigen::MatrixXd::Identity(5, 5)).cwiseAbs().maxCoeff() < 1e-8);
  RC_ASSERT((u.transpose() * t).cwiseAbs().maxCoeff() < 1e-8);
  const Eigen::Index have = ind.values.size();
  for (int lo = 1; lo <= 5;) {
    int hi = lo;
    while (hi + 1 <= 5 && ind.values(hi + 1) - ind.values(hi) < kClusterGap) ++hi;
    // Spectra's copies of the cluster, which may run past the window.
    Eigen::Index end = hi;
    while (end + 1 < have && ind.values(end + 1) - ind.values(end) < kClusterGap) ++end;
    RC_ASSERT(end + 1 < have);  // Spectra saw past the cluster, so its gap is known
    const double gap = std::min(ind.values(lo) - ind.values(lo - 1), ind.values(end + 1) - ind.values(end));
    const Eigen::MatrixXd mine = u.middleCols(lo - 1, hi - lo + 1);
    const Eigen::MatrixXd theirs = ind.vectors.middleCols(lo, end - lo + 1);
    const double bound =
        std::sqrt(static_cast<double>(hi - lo + 1)) * ((max_residual + ind.residual + operator_error) / gap + rounding) +
        1e-12;
    // Every returned vector of the cluster lies in Spectra's eigenspace...
    const double outside = (mine - theirs * (theirs.transpose() * mine)).norm();
    if (!(outside <= bound))
      RC_FAIL("cluster " + std::to_string(lo + 1) + ".." + std::to_string(hi + 1) + ": " + sci(outside) +
              " outside Spectra's eigenspace (bound " + sci(bound) + ", gap " + sci(gap) + ", residual " + sci(max_residual) + ")");
    // ...and, when the window holds the whole cluster, spans it (the largest principal angle).
    if (end == hi) {
      const double angle = max_angle(mine, theirs);
      if (!(angle <= bound))
        RC_FAIL("cluster " + std::to_string(lo + 1) + ".." + std::to_string(hi + 1) + ": angle " + sci(angle) +
                " (bound " + sci(bound) + ")");
    }
    lo = hi + 1;
  }
}

using r1::test::check_cases;

TEST(SpectralSpectra, RandomGraphsAgreeWithSpectraAndAcrossDomains) {
  EXPECT_TRUE(check_cases("spectral vs Spectra", 100, [] {
    const Case c = random_case();
    RC_LOG() << c.summary << "\n";
    const r1::Graph g = from_links(c.links);
    const auto q = r1::spectral_embedding_q32(g, r1::SpectralParams{});
    RC_ASSERT(q.is_ok());
    const auto f = r1::spectral_embedding_f64(g, r1::SpectralParams{});
    RC_ASSERT(f.is_ok());
    RC_ASSERT(q->rho == f->rho);
    // Enough of Spectra's spectrum to see past the cluster at the window's end (a star-like hub
    // can repeat an eigenvalue dozens of times).
    int nev = std::min<int>(12, static_cast<int>(g.n) - 2);
    Independent ind = spectra_smallest(g, q->rho, nev);
    while (nev < static_cast<int>(g.n) - 2 && ind.values(nev - 1) - ind.values(5) < kClusterGap) {
      nev = std::min<int>(2 * nev, static_cast<int>(g.n) - 2);
      ind = spectra_smallest(g, q->rho, nev);
    }
    bool repeated = false;
    for (int c2 = 1; c2 < 5; ++c2) repeated = repeated || ind.values(c2 + 1) - ind.values(c2) < kClusterGap;
    RC_CLASSIFY(repeated, "a repeated eigenvalue in the window");
    compare(*q, ind, q->rho, g);
    compare(*f, ind, f->rho, g);
    // The two domains agree with each other as closely as each agrees with Spectra.
    for (int c2 = 1; c2 <= 5; ++c2) RC_ASSERT(std::fabs(q->eigenvalues[c2] - f->eigenvalues[c2]) < 1e-9);
  }));
}

}  // namespace
