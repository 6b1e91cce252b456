// Similarity Procrustes with a hand-written 3x3 one-sided Jacobi SVD and the SC-R flip (R1-FRM-031..037).
#include <cmath>

#include "r1/fixedpoint/exact_sum.hpp"
#include "r1/fixedpoint/int128.hpp"
#include "r1/reference/frame.hpp"
#include "frame_internal.hpp"

namespace r1 {

namespace {

using Vec3 = std::array<double, 3>;

// Relative degeneracy threshold tau = 2^-30 (R1-FRM-033): far above the ~2^-40 relative noise
// that Q32 rounding at scene scale leaves in H, far below any genuine spread.
constexpr double kTau = 0x1p-30;
// Jacobi skips a pair whose columns are orthogonal to within 2^-50 (a few ulps) of their norms.
constexpr double kOrthoTol = 0x1p-50;
// Above this |zeta|, zeta^2 would overflow; t = 1 / (2 zeta) is then the rotation's tangent.
constexpr double kZetaHuge = 0x1p500;
// 3x3 one-sided Jacobi converges quadratically in a handful of sweeps; the cap only bounds
// pathological inputs (NaN never arises: inputs are finite integers converted once).
constexpr int kMaxSweeps = 32;

using frame_detail::to_double_rne;

double dot3(const Vec3& a, const Vec3& b) { return (a[0] * b[0] + a[1] * b[1]) + a[2] * b[2]; }
Vec3 cross3(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

// Column c of a row-major 3x3 matrix.
Vec3 column(const std::array<double, 9>& m, int c) { return {m[c], m[3 + c], m[6 + c]}; }

// A canonical unit vector orthogonal to the unit vector a: e_j - (a . e_j) a normalised, for the
// axis j where |a_j| is smallest (ties: lowest j), so the vector is far from parallel to a.
Vec3 canonical_orthogonal(const Vec3& a) {
  int j = 0;
  for (int k = 1; k < 3; ++k)
    if (std::fabs(a[k]) < std::fabs(a[j])) j = k;
  Vec3 e{0, 0, 0};
  e[j] = 1;
  const double proj = a[j];
  const Vec3 q{e[0] - proj * a[0], e[1] - proj * a[1], e[2] - proj * a[2]};
  const double len = std::sqrt(dot3(q, q));
  return {q[0] / len, q[1] / len, q[2] / len};
}

}  // namespace

Svd3 svd3(const std::array<double, 9>& h) {
  // w[c] is column c of the working matrix, v[c] column c of the accumulated rotation.
  std::array<Vec3, 3> w{column(h, 0), column(h, 1), column(h, 2)};
  std::array<Vec3, 3> v{Vec3{1, 0, 0}, Vec3{0, 1, 0}, Vec3{0, 0, 1}};
  constexpr int kPairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
  Svd3 out;
  while (out.sweeps < kMaxSweeps) {
    bool rotated = false;
    for (const auto& pr : kPairs) {
      const int i = pr[0], j = pr[1];
      const double alpha = dot3(w[i], w[i]);
      const double beta = dot3(w[j], w[j]);
      const double gamma = dot3(w[i], w[j]);
      if (std::fabs(gamma) <= kOrthoTol * (std::sqrt(alpha) * std::sqrt(beta))) continue;
      const double zeta = (beta - alpha) / (2.0 * gamma);
      double t = 0;
      if (std::fabs(zeta) > kZetaHuge) {
        t = 1.0 / (2.0 * zeta);
      } else {
        const double sign = zeta >= 0 ? 1.0 : -1.0;  // sign(0) = +1: a 45-degree rotation
        t = sign / (std::fabs(zeta) + std::sqrt(1.0 + zeta * zeta));
      }
      const double c = 1.0 / std::sqrt(1.0 + t * t);
      const double s = c * t;
      for (int r = 0; r < 3; ++r) {
        const double wi = w[i][r], wj = w[j][r];
        w[i][r] = c * wi - s * wj;
        w[j][r] = s * wi + c * wj;
        const double vi = v[i][r], vj = v[j][r];
        v[i][r] = c * vi - s * vj;
        v[j][r] = s * vi + c * vj;
      }
      rotated = true;
    }
    ++out.sweeps;
    if (!rotated) break;
  }
  std::array<double, 3> sigma{};
  std::array<Vec3, 3> u{};
  for (int c = 0; c < 3; ++c) {
    sigma[c] = std::sqrt(dot3(w[c], w[c]));
    if (sigma[c] > 0)
      for (int r = 0; r < 3; ++r) u[c][r] = w[c][r] / sigma[c];
  }
  // Stable sort by sigma descending: three compare-and-swaps, strict so ties keep index order.
  std::array<int, 3> idx{0, 1, 2};
  auto order = [&](int a, int b) {
    if (sigma[idx[b]] > sigma[idx[a]]) std::swap(idx[a], idx[b]);
  };
  order(0, 1);
  order(1, 2);
  order(0, 1);
  for (int c = 0; c < 3; ++c) {
    out.sigma[c] = sigma[idx[c]];
    for (int r = 0; r < 3; ++r) {
      out.u[r * 3 + c] = u[idx[c]][r];
      out.v[r * 3 + c] = v[idx[c]][r];
    }
  }
  return out;
}

Result<Similarity> similarity_procrustes(std::span<const std::array<Q32, 3>> from, std::span<const std::array<Q32, 3>> to) {
  if (from.size() != to.size() || from.empty() || from.size() > kAnchorMax)
    return Status::internal("procrustes: needs 1 to 1024 pairs of equal count");
  for (std::size_t p = 0; p < from.size(); ++p)
    for (int c = 0; c < 3; ++c)
      if (from[p][c].raw < -kAnchorCoordMax || from[p][c].raw > kAnchorCoordMax || to[p][c].raw < -kAnchorCoordMax ||
          to[p][c].raw > kAnchorCoordMax)
        return Status::input("procrustes: a coordinate lies beyond 2^20 scene units");

  // Exact moments (R1-FRM-031). With |raw| <= 2^52 and m <= 1024 every value below stays under
  // 2^126 in magnitude, so i128 never wraps.
  const auto m = static_cast<i128>(from.size());
  std::array<i128, 3> sy{}, sa{};
  std::array<i128, 9> p{};
  i128 syy = 0;
  for (std::size_t k = 0; k < from.size(); ++k) {
    for (int i = 0; i < 3; ++i) {
      const i128 y = from[k][i].raw;
      sy[i] += y;
      sa[i] += to[k][i].raw;
      syy += y * y;
      for (int j = 0; j < 3; ++j) p[i * 3 + j] += y * to[k][j].raw;
    }
  }
  std::array<i128, 9> hi{};
  bool h_zero = true;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      hi[i * 3 + j] = m * p[i * 3 + j] - sy[i] * sa[j];
      h_zero = h_zero && hi[i * 3 + j] == 0;
    }
  const i128 vi = m * syy - (sy[0] * sy[0] + sy[1] * sy[1] + sy[2] * sy[2]);

  // Centroids in scene units: the exact sum rounded once, divided by m, scaled by 2^-32 (exact).
  const double md = static_cast<double>(from.size());
  Vec3 cy{}, ca{};
  for (int i = 0; i < 3; ++i) {
    cy[i] = to_double_rne(sy[i]) / md * 0x1p-32;
    ca[i] = to_double_rne(sa[i]) / md * 0x1p-32;
  }

  Similarity sim;
  if (h_zero || vi == 0) {
    // No rotation or scale information (R1-FRM-033): move the centroid only.
    sim.translation_only = true;
    sim.translation = {ca[0] - cy[0], ca[1] - cy[1], ca[2] - cy[2]};
  } else {
    std::array<double, 9> h{};
    for (int k = 0; k < 9; ++k) h[k] = to_double_rne(hi[k]);
    const Svd3 svd = svd3(h);
    Vec3 u0 = column(svd.u, 0), u1 = column(svd.u, 1);
    Vec3 v0 = column(svd.v, 0), v1 = column(svd.v, 1);
    const Vec3 u2 = column(svd.u, 2), v2 = column(svd.v, 2);
    sim.collinear = svd.sigma[1] <= kTau * svd.sigma[0];
    sim.planar = svd.sigma[2] <= kTau * svd.sigma[0];
    if (sim.collinear) {
      // The second singular pair is noise: both partners become canonical (R1-FRM-033).
      u1 = canonical_orthogonal(u0);
      v1 = canonical_orthogonal(v0);
    }
    const Vec3 u2p = cross3(u0, u1), v2p = cross3(v0, v1);
    // The O(3) optimum V_J U^T is improper exactly when det U det V_J < 0; the sort of R1-FRM-032
    // may permute the columns of both, so both determinants are read off (R1-FRM-034).
    sim.reflected = !sim.planar && (dot3(u2, u2p) < 0) != (dot3(v2, v2p) < 0);
    // Q = V' diag(1, 1, d) U'^T with right-handed U' = [u0, u1, u0 x u1], V' = [v0, v1, v0 x v1]:
    // d = -1 reproduces the reflection optimum (R1-FRM-034).
    const double d = sim.reflected ? -1.0 : 1.0;
    const std::array<Vec3, 3> uc{u0, u1, Vec3{d * u2p[0], d * u2p[1], d * u2p[2]}};
    const std::array<Vec3, 3> vc{v0, v1, v2p};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        // Q_ij = sum_k V'_ik U'_jk; SC-R then negates column 2 (R = Q F).
        const double q = (vc[0][i] * uc[0][j] + vc[1][i] * uc[1][j]) + vc[2][i] * uc[2][j];
        sim.rotation[i * 3 + j] = (sim.reflected && j == 2) ? -q : q;
      }
    // s = trace(R F H) / V, the nine products row by row (R1-FRM-035). F H negates row 2 of H.
    double tr = 0;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        const double g = (sim.reflected && j == 2) ? -h[j * 3 + i] : h[j * 3 + i];
        tr += sim.rotation[i * 3 + j] * g;
      }
    sim.scale = tr / to_double_rne(vi);
    if (sim.reflected) cy[2] = -cy[2];
    for (int i = 0; i < 3; ++i) {
      const Vec3 row{sim.rotation[i * 3], sim.rotation[i * 3 + 1], sim.rotation[i * 3 + 2]};
      sim.translation[i] = ca[i] - sim.scale * dot3(row, cy);
    }
  }
  R1_TRY(set_applied_transform(sim).with_prefix("procrustes: "));
  return sim;
}

Status set_applied_transform(Similarity& sim) {
  // The applied transform (R1-FRM-036): RNE(s R) and RNE(t) from their doubles.
  for (int k = 0; k < 9; ++k) {
    const auto q = Q32::checked_from_double(sim.scale * sim.rotation[k]);
    if (!q) return Status::input("the alignment scale does not fit Q32");
    sim.m[k] = *q;
  }
  for (int i = 0; i < 3; ++i) {
    const auto q = Q32::checked_from_double(sim.translation[i]);
    if (!q) return Status::input("the alignment translation does not fit Q32");
    sim.t[i] = *q;
  }
  return Status::ok();
}

Result<Similarity> similarity_of(const Alignment& a) {
  Similarity sim;
  sim.rotation = a.rotation;
  sim.scale = a.scale;
  sim.translation = a.translation;
  sim.reflected = a.reflected;
  R1_TRY(set_applied_transform(sim));
  return sim;
}

std::optional<std::array<Q32, 3>> apply_similarity(const Similarity& sim, const std::array<Q32, 3>& y) {
  // SC-R: the third axis is inverted before the rotation (exact for every raw but -2^63).
  if (sim.reflected && y[2].raw == INT64_MIN) return std::nullopt;
  const std::array<Q32, 3> yf{y[0], y[1], sim.reflected ? Q32::from_raw(-y[2].raw) : y[2]};
  std::array<Q32, 3> out{};
  for (int i = 0; i < 3; ++i) {
    fx::ExactSum acc;
    for (int j = 0; j < 3; ++j) acc.add_product(sim.m[i * 3 + j], yf[j]);
    acc.add(sim.t[i]);
    const auto r = acc.checked_round();
    if (!r) return std::nullopt;
    out[i] = *r;
  }
  return out;
}

}  // namespace r1
