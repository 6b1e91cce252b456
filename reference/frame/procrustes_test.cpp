// The 3x3 Jacobi SVD and the similarity Procrustes solution: known rotations, scales, translations and reflections recovered, degenerate sets (R1-FRM-031..036).
#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstring>

#include "r1/fixedpoint/counter_rng.hpp"
#include "r1/reference/frame.hpp"

namespace {

using r1::Q32;
using M3 = std::array<double, 9>;
using P3 = std::array<Q32, 3>;

M3 mul(const M3& a, const M3& b) {
  M3 c{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) c[i * 3 + j] += a[i * 3 + k] * b[k * 3 + j];
  return c;
}
M3 transpose(const M3& a) {
  M3 t{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) t[j * 3 + i] = a[i * 3 + j];
  return t;
}
double det(const M3& a) {
  return a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6]) + a[2] * (a[3] * a[7] - a[4] * a[6]);
}
double max_abs_diff(const M3& a, const M3& b) {
  double m = 0;
  for (int k = 0; k < 9; ++k) m = std::max(m, std::fabs(a[k] - b[k]));
  return m;
}
const M3 kI{1, 0, 0, 0, 1, 0, 0, 0, 1};

double uniform(std::uint64_t seed, std::uint64_t item, std::uint64_t dim, double lo, double hi) {
  return lo + (hi - lo) * r1::rng::uniform_double(seed, item, dim);
}

// A rotation from a random unit quaternion (counter-based, so a pure function of the seed).
M3 random_rotation(std::uint64_t seed) {
  double q[4];
  double n2 = 0;
  for (int k = 0; k < 4; ++k) {
    q[k] = uniform(seed, 0, static_cast<std::uint64_t>(k), -1, 1);
    n2 += q[k] * q[k];
  }
  const double n = std::sqrt(n2);
  const double w = q[0] / n, x = q[1] / n, y = q[2] / n, z = q[3] / n;
  return {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
          2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
          2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
}

std::vector<P3> random_points(std::uint64_t seed, std::size_t m, double box) {
  std::vector<P3> p(m);
  for (std::size_t i = 0; i < m; ++i)
    for (std::uint64_t c = 0; c < 3; ++c) p[i][c] = Q32::from_double(uniform(seed, 100 + i, c, -box, box));
  return p;
}

std::vector<P3> transform(const std::vector<P3>& from, const M3& q, double s, const std::array<double, 3>& t) {
  std::vector<P3> to(from.size());
  for (std::size_t i = 0; i < from.size(); ++i)
    for (int r = 0; r < 3; ++r) {
      double acc = 0;
      for (int c = 0; c < 3; ++c) acc += q[r * 3 + c] * from[i][c].to_double();
      to[i][r] = Q32::from_double(s * acc + t[r]);
    }
  return to;
}

// RMS of apply(from) - to in scene units.
double rms(const r1::Similarity& sim, const std::vector<P3>& from, const std::vector<P3>& to) {
  double e = 0;
  for (std::size_t i = 0; i < from.size(); ++i) {
    const auto y = r1::apply_similarity(sim, from[i]);
    EXPECT_TRUE(y.has_value());
    for (int c = 0; c < 3; ++c) {
      const double d = (*y)[c].to_double() - to[i][c].to_double();
      e += d * d;
    }
  }
  return std::sqrt(e / static_cast<double>(from.size()));
}

void expect_svd(const M3& h) {
  const auto s = r1::svd3(h);
  EXPECT_LE(max_abs_diff(mul(transpose(s.v), s.v), kI), 1e-14);
  EXPECT_GE(s.sigma[0], s.sigma[1]);
  EXPECT_GE(s.sigma[1], s.sigma[2]);
  EXPECT_GE(s.sigma[2], 0);
  EXPECT_LE(s.sweeps, 12);
  // H = U diag(sigma) V^T; columns of U with sigma > 0 are orthonormal.
  M3 us = s.u;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) us[r * 3 + c] *= s.sigma[c];
  double scale = 0;
  for (double x : h) scale = std::max(scale, std::fabs(x));
  EXPECT_LE(max_abs_diff(mul(us, transpose(s.v)), h), 1e-14 * std::max(scale, 1e-300));
  for (int a = 0; a < 3; ++a)
    for (int b = a; b < 3; ++b) {
      if (s.sigma[a] <= 1e-12 * s.sigma[0] || s.sigma[b] <= 1e-12 * s.sigma[0]) continue;
      double d = 0;
      for (int r = 0; r < 3; ++r) d += s.u[r * 3 + a] * s.u[r * 3 + b];
      EXPECT_NEAR(d, a == b ? 1.0 : 0.0, 1e-13);
    }
}

TEST(Svd3, InvariantsOnRandomMatrices) {
  for (std::uint64_t seed = 1; seed <= 200; ++seed) {
    M3 h{};
    for (int k = 0; k < 9; ++k) h[k] = uniform(seed, 7, static_cast<std::uint64_t>(k), -1e6, 1e6);
    SCOPED_TRACE(seed);
    expect_svd(h);
  }
}

TEST(Svd3, RankDeficientZeroAndDiagonal) {
  expect_svd({0, 0, 0, 0, 0, 0, 0, 0, 0});
  expect_svd({3, 0, 0, 0, -5, 0, 0, 0, 1});
  expect_svd({1, 2, 3, 2, 4, 6, 3, 6, 9});    // rank 1
  expect_svd({1, 2, 3, 4, 5, 6, 5, 7, 9});    // rank 2 (row 3 = row 1 + row 2)
  expect_svd({1e120, 0, 0, 0, 1e-120, 0, 0, 0, 1});
  const auto d = r1::svd3({3, 0, 0, 0, -5, 0, 0, 0, 1});
  EXPECT_EQ(d.sigma, (std::array<double, 3>{5, 3, 1}));
  const auto z = r1::svd3({0, 0, 0, 0, 0, 0, 0, 0, 0});
  EXPECT_EQ(z.sigma, (std::array<double, 3>{0, 0, 0}));
}

TEST(Svd3, SingularValuesAgreeWithEigen) {
  // Eigen's JacobiSVD as an independent reference (tests only; R1-FRM-032).
  for (std::uint64_t seed = 1; seed <= 200; ++seed) {
    SCOPED_TRACE(seed);
    M3 h{};
    Eigen::Matrix3d e;
    for (int k = 0; k < 9; ++k) {
      h[k] = uniform(seed, 8, static_cast<std::uint64_t>(k), -1e3, 1e3);
      e(k / 3, k % 3) = h[k];
    }
    const auto ours = r1::svd3(h);
    const Eigen::JacobiSVD<Eigen::Matrix3d> ref(e, Eigen::ComputeFullU | Eigen::ComputeFullV);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(ours.sigma[c], ref.singularValues()(c), 1e-12 * ref.singularValues()(0));
    // Singular vectors agree up to sign where the singular values are well separated.
    for (int c = 0; c < 3; ++c) {
      double du = 0, dv = 0;
      for (int r = 0; r < 3; ++r) {
        du += ours.u[r * 3 + c] * ref.matrixU()(r, c);
        dv += ours.v[r * 3 + c] * ref.matrixV()(r, c);
      }
      EXPECT_NEAR(std::fabs(du), 1.0, 1e-9);
      EXPECT_NEAR(du * dv, 1.0, 1e-9);  // a sign flip of u_c comes with the same flip of v_c
    }
  }
}

// The least-squares optimum for noisy pairs (no exact answer exists) by Eigen's SVD: Q = V D U^T
// over O(3) with D = I, and the SC-R rotation R = Q F when det Q < 0 (R1-FRM-034).
TEST(Procrustes, NoisyOptimumAgreesWithEigen) {
  const M3 flip{1, 0, 0, 0, 1, 0, 0, 0, -1};
  for (std::uint64_t seed = 1; seed <= 60; ++seed) {
    SCOPED_TRACE(seed);
    const bool improper = seed % 2 == 0;
    const M3 q = improper ? mul(random_rotation(seed), flip) : random_rotation(seed);
    const auto from = random_points(seed + 500, 10 + seed, 700);
    auto to = transform(from, q, 1.3, {3, -4, 5});
    for (std::size_t i = 0; i < to.size(); ++i)
      for (std::uint64_t c = 0; c < 3; ++c)
        to[i][c] = Q32::from_double(to[i][c].to_double() + uniform(seed, 900 + i, c, -40, 40));
    Eigen::Vector3d cy = Eigen::Vector3d::Zero(), ca = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < from.size(); ++i)
      for (int c = 0; c < 3; ++c) {
        cy(c) += from[i][c].to_double();
        ca(c) += to[i][c].to_double();
      }
    cy /= static_cast<double>(from.size());
    ca /= static_cast<double>(from.size());
    Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
    double var = 0;
    for (std::size_t i = 0; i < from.size(); ++i) {
      Eigen::Vector3d y, a;
      for (int c = 0; c < 3; ++c) {
        y(c) = from[i][c].to_double() - cy(c);
        a(c) = to[i][c].to_double() - ca(c);
      }
      h += y * a.transpose();
      var += y.squaredNorm();
    }
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Eigen::Matrix3d qo = svd.matrixV() * svd.matrixU().transpose();
    const bool ref_reflected = qo.determinant() < 0;
    const double ref_scale = (qo * h).trace() / var;
    auto sim = r1::similarity_procrustes(from, to);
    ASSERT_TRUE(sim.is_ok());
    EXPECT_EQ(sim->reflected, ref_reflected);
    EXPECT_EQ(sim->reflected, improper);
    M3 want{};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) want[i * 3 + j] = (ref_reflected && j == 2) ? -qo(i, j) : qo(i, j);
    EXPECT_LE(max_abs_diff(sim->rotation, want), 1e-9);
    EXPECT_NEAR(sim->scale, ref_scale, 1e-9 * ref_scale);
  }
}

TEST(Procrustes, RecoversRotationScaleTranslation) {
  for (std::uint64_t seed = 1; seed <= 50; ++seed) {
    SCOPED_TRACE(seed);
    const M3 q = random_rotation(seed);
    const double s = uniform(seed, 1, 0, 0.2, 5);
    const std::array<double, 3> t{uniform(seed, 2, 0, -500, 500), uniform(seed, 2, 1, -500, 500), uniform(seed, 2, 2, -500, 500)};
    const auto from = random_points(seed, 4 + seed % 60, 1000);
    const auto to = transform(from, q, s, t);
    auto sim = r1::similarity_procrustes(from, to);
    ASSERT_TRUE(sim.is_ok()) << sim.status().message();
    EXPECT_FALSE(sim->reflected);
    EXPECT_FALSE(sim->planar);
    EXPECT_LE(max_abs_diff(sim->rotation, q), 1e-9);
    EXPECT_NEAR(sim->scale, s, 1e-9 * s);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(sim->translation[c], t[c], 1e-6);
    // Q32 rounding of the targets and of the applied transform only (R1-FRM-036).
    EXPECT_LE(rms(*sim, from, to), 1e-6);
  }
}

TEST(Procrustes, ReflectionComesOutRightHandedWithSCR) {
  const M3 flip{1, 0, 0, 0, 1, 0, 0, 0, -1};
  for (std::uint64_t seed = 1; seed <= 50; ++seed) {
    SCOPED_TRACE(seed);
    const M3 q = mul(random_rotation(seed), flip);  // improper: det -1
    ASSERT_LT(det(q), 0);
    const auto from = random_points(seed + 1000, 20, 800);
    const auto to = transform(from, q, 1.5, {10, -20, 30});
    auto sim = r1::similarity_procrustes(from, to);
    ASSERT_TRUE(sim.is_ok());
    EXPECT_TRUE(sim->reflected);
    EXPECT_NEAR(det(sim->rotation), 1.0, 1e-12);
    // R = Q F: the flip of the third input axis is absorbed (R1-FRM-034).
    EXPECT_LE(max_abs_diff(sim->rotation, mul(q, flip)), 1e-9);
    EXPECT_NEAR(sim->scale, 1.5, 1e-9);
    EXPECT_LE(rms(*sim, from, to), 1e-6);
  }
}

TEST(Procrustes, PlanarSetsTakeTheRotation) {
  const M3 flip{1, 0, 0, 0, 1, 0, 0, 0, -1};
  for (bool improper : {false, true}) {
    SCOPED_TRACE(improper);
    auto from = random_points(77, 30, 500);
    for (auto& p : from) p[2] = Q32::zero();  // every point in the plane z = 0
    const M3 q = improper ? mul(random_rotation(78), flip) : random_rotation(78);
    const auto to = transform(from, q, 2.0, {1, 2, 3});
    auto sim = r1::similarity_procrustes(from, to);
    ASSERT_TRUE(sim.is_ok());
    EXPECT_TRUE(sim->planar);
    EXPECT_FALSE(sim->collinear);
    // A planar anchor cannot tell a reflection from a rotation; r1 takes the rotation.
    EXPECT_FALSE(sim->reflected);
    EXPECT_NEAR(det(sim->rotation), 1.0, 1e-12);
    EXPECT_LE(rms(*sim, from, to), 1e-6);
    // The rotation agrees with q on the plane's two directions.
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 2; ++c) EXPECT_NEAR(sim->rotation[r * 3 + c], q[r * 3 + c], 1e-9);
  }
}

TEST(Procrustes, CollinearSetsMapTheLine) {
  std::vector<P3> from;
  for (int i = 0; i < 10; ++i) from.push_back({Q32::from_int(i), Q32::from_int(2 * i), Q32::from_int(-i)});
  const M3 q = random_rotation(5);
  const auto to = transform(from, q, 3.0, {0, 0, 100});
  auto sim = r1::similarity_procrustes(from, to);
  ASSERT_TRUE(sim.is_ok());
  EXPECT_TRUE(sim->collinear);
  EXPECT_TRUE(sim->planar);
  EXPECT_FALSE(sim->reflected);
  EXPECT_NEAR(det(sim->rotation), 1.0, 1e-12);
  EXPECT_LE(max_abs_diff(mul(transpose(sim->rotation), sim->rotation), kI), 1e-12);
  EXPECT_NEAR(sim->scale, 3.0, 1e-9);
  EXPECT_LE(rms(*sim, from, to), 1e-6);
}

TEST(Procrustes, CoincidentPointsTranslateOnly) {
  const std::vector<P3> same(5, P3{Q32::from_int(3), Q32::from_int(4), Q32::from_int(5)});
  const auto to = random_points(9, 5, 100);
  auto sim = r1::similarity_procrustes(same, to);
  ASSERT_TRUE(sim.is_ok());
  EXPECT_TRUE(sim->translation_only);
  EXPECT_EQ(sim->rotation, kI);
  EXPECT_EQ(sim->scale, 1.0);
  // The centroid of `same` lands on the centroid of `to`.
  for (int c = 0; c < 3; ++c) {
    double mean = 0;
    for (const auto& p : to) mean += p[c].to_double();
    EXPECT_NEAR(sim->translation[c] + 3 + c, mean / 5, 1e-9);
  }
  // A target with no spread (H = 0) moves the centroid too.
  auto sim2 = r1::similarity_procrustes(to, same);
  ASSERT_TRUE(sim2.is_ok());
  EXPECT_TRUE(sim2->translation_only);
}

TEST(Procrustes, RefusesBadInput) {
  const auto a = random_points(1, 4, 10);
  EXPECT_EQ(r1::similarity_procrustes(a, random_points(1, 5, 10)).status().kind(), r1::ErrorKind::kInternal);
  EXPECT_FALSE(r1::similarity_procrustes(std::vector<P3>{}, std::vector<P3>{}).is_ok());
  auto far = a;
  far[0][0] = Q32::from_int(1 << 21);
  EXPECT_EQ(r1::similarity_procrustes(far, a).status().kind(), r1::ErrorKind::kInput);
}

TEST(Procrustes, Deterministic) {
  const auto from = random_points(3, 50, 900);
  const auto to = transform(from, random_rotation(4), 0.7, {5, 6, 7});
  auto a = r1::similarity_procrustes(from, to);
  auto b = r1::similarity_procrustes(from, to);
  ASSERT_TRUE(a.is_ok() && b.is_ok());
  EXPECT_EQ(a->m, b->m);
  EXPECT_EQ(a->t, b->t);
  EXPECT_EQ(std::memcmp(a->rotation.data(), b->rotation.data(), sizeof(double) * 9), 0);
}

RC_GTEST_PROP(Procrustes, AnySimilarityIsRecovered, ()) {
  const auto seed = *rc::gen::inRange<std::uint64_t>(1, 1u << 30);
  const auto m = *rc::gen::inRange<std::size_t>(4, 80);
  const bool improper = *rc::gen::arbitrary<bool>();
  const M3 flip{1, 0, 0, 0, 1, 0, 0, 0, -1};
  const M3 q = improper ? mul(random_rotation(seed), flip) : random_rotation(seed);
  const double s = uniform(seed, 1, 0, 0.1, 10);
  const auto from = random_points(seed, m, 1000);
  const auto to = transform(from, q, s, {uniform(seed, 2, 0, -1000, 1000), 0, uniform(seed, 2, 2, -1000, 1000)});
  auto sim = r1::similarity_procrustes(from, to);
  RC_ASSERT(sim.is_ok());
  RC_ASSERT(sim->reflected == improper);
  RC_ASSERT(std::fabs(det(sim->rotation) - 1.0) < 1e-12);
  RC_ASSERT(std::fabs(sim->scale - s) <= 1e-8 * s);
  RC_ASSERT(rms(*sim, from, to) <= 1e-5);
}

}  // namespace
