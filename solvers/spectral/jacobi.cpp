// Cyclic Jacobi eigensolver in fp64 with Rutishauser's rotation (R1-SPEC-040..042).
#include "jacobi.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace r1::spectral {

JacobiResult jacobi_eigen(std::size_t m, std::vector<double> a) {
  auto at = [&](std::size_t i, std::size_t j) -> double& { return a[i * m + j]; };
  // Symmetrise from the upper triangle so the lower one never matters.
  for (std::size_t i = 0; i < m; ++i)
    for (std::size_t j = 0; j < i; ++j) at(i, j) = at(j, i);
  std::vector<double> z(m * m, 0.0);
  for (std::size_t i = 0; i < m; ++i) z[i * m + i] = 1.0;

  JacobiResult r;
  for (int sweep = 0; sweep < kJacobiMaxSweeps; ++sweep) {
    // Stopping rule (R1-SPEC-041): off = sum_{p<q} a_pq^2 and diag = sum a_ii^2, both summed in
    // index order; stop when off <= 2^-106 (diag + 2 off), i.e. the off-diagonal part is below
    // the double rounding level of the matrix (2^-53 in Frobenius norm).
    double off = 0, diag = 0;
    for (std::size_t p = 0; p < m; ++p) {
      diag = diag + at(p, p) * at(p, p);
      for (std::size_t q = p + 1; q < m; ++q) off = off + at(p, q) * at(p, q);
    }
    if (off <= 0x1p-106 * (diag + 2 * off)) break;
    ++r.sweeps;
    for (std::size_t p = 0; p + 1 < m; ++p)
      for (std::size_t q = p + 1; q < m; ++q) {
        const double apq = at(p, q);
        if (apq == 0.0) continue;
        // Rutishauser: theta = (a_qq - a_pp) / (2 a_pq), t = sign(theta) / (|theta| + sqrt(theta^2 + 1)),
        // the smaller rotation angle; for |theta| > 2^500 theta^2 would overflow and t = 1 / (2 theta).
        const double theta = (at(q, q) - at(p, p)) / (2.0 * apq);
        double t = 0;
        if (std::fabs(theta) > 0x1p500) {
          t = 0.5 / theta;
        } else {
          t = 1.0 / (std::fabs(theta) + std::sqrt(theta * theta + 1.0));
          if (theta < 0) t = -t;
        }
        const double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c, tau = s / (1.0 + c);
        at(p, p) = at(p, p) - t * apq;
        at(q, q) = at(q, q) + t * apq;
        at(p, q) = 0.0;
        at(q, p) = 0.0;
        for (std::size_t k = 0; k < m; ++k) {
          if (k != p && k != q) {
            const double akp = at(k, p), akq = at(k, q);
            at(k, p) = akp - s * (akq + tau * akp);
            at(k, q) = akq + s * (akp - tau * akq);
            at(p, k) = at(k, p);
            at(q, k) = at(k, q);
          }
          const double zkp = z[k * m + p], zkq = z[k * m + q];
          z[k * m + p] = zkp - s * (zkq + tau * zkp);
          z[k * m + q] = zkq + s * (zkp - tau * zkq);
        }
      }
  }
  // Ascending eigenvalues; ties keep diagonal order (a stable sort on the index).
  std::vector<std::size_t> order(m);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t x, std::size_t y) { return at(x, x) < at(y, y); });
  r.values.resize(m);
  r.vectors.resize(m * m);
  for (std::size_t c = 0; c < m; ++c) {
    r.values[c] = at(order[c], order[c]);
    for (std::size_t k = 0; k < m; ++k) r.vectors[k * m + c] = z[k * m + order[c]];
  }
  return r;
}

}  // namespace r1::spectral
