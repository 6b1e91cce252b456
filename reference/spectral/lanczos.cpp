// Thick-restart Lanczos (Wu and Simon 2000) with full re-orthogonalisation, locking and a
// fresh-start verification (R1-SPEC-020..035, R1-SPEC-061).
#include "lanczos.hpp"

#include <algorithm>
#include <cmath>

#include "jacobi.hpp"

namespace r1::spectral {

template <class Scalar>
void rayleigh(const SpectralOperator<Scalar>& op, const VectorOps<Scalar>& ops, std::span<const Scalar> x,
              std::vector<Scalar>& y, std::vector<Scalar>& r, double& lambda, double& residual) {
  op.apply(x.data(), y.data(), ops.parallel());
  const double xx = ops.dot(x, x), xy = ops.dot(x, y);
  lambda = xy / xx;
  // r = L x - lambda x with one rounding per entry, then ||r|| / ||x|| (R1-SPEC-061).
  const double c[1] = {-lambda};
  const Scalar* xs[1] = {x.data()};
  ops.combine(r, y.data(), c, xs);
  residual = std::sqrt(ops.dot(r, r) / xx);
}

namespace {

template <class Scalar>
class Solver {
 public:
  using Vec = std::vector<Scalar>;

  Solver(const SpectralOperator<Scalar>& op, const VectorOps<Scalar>& ops, const LanczosConfig& cfg,
         const ProgressFn& progress)
      : op_(op), ops_(ops), cfg_(cfg), progress_(progress), n_(op.n), m_(cfg.basis),
        kk_(std::min<std::size_t>(cfg.keep, cfg.basis - 1)) {
    v_.assign(m_, Vec(n_));
    w_.resize(n_);
    next_.resize(n_);
    y_.resize(n_);
    r_.resize(n_);
  }

  LanczosOutcome<Scalar> run();

 private:
  // The vectors every new basis vector is kept orthogonal to: the trivial one, the locked ones
  // and the basis vectors V[0..upto), in that order (R1-SPEC-022).
  std::vector<const Scalar*> against(std::size_t upto) const {
    std::vector<const Scalar*> list;
    list.reserve(1 + locked_.size() + upto);
    list.push_back(op_.trivial.data());
    for (const auto& p : locked_) list.push_back(p.x.data());
    for (std::size_t j = 0; j < upto; ++j) list.push_back(v_[j].data());
    return list;
  }

  // One classical Gram-Schmidt pass: v <- v - sum_q <q, v> q, one rounding per entry.
  void project(Vec& v, const std::vector<const Scalar*>& list) {
    std::vector<double> h(list.size());
    ops_.dots(list, v, h);
    for (double& c : h) c = -c;
    ops_.combine(v, v.data(), h, list);
  }

  // V[slot] <- a fresh random unit vector orthogonal to against(upto) (R1-SPEC-030): counter
  // dimension next_dim_, two projection passes; a draw that loses all but 2^-20 of its squared
  // length to the projection (the space is nearly exhausted) is replaced by the next dimension.
  void fresh(std::size_t slot, std::size_t upto) { fresh_into(v_[slot], against(upto)); }
  void fresh_into(Vec& v, const std::vector<const Scalar*>& list) {
    for (;;) {
      ops_.random(v, cfg_.seed, next_dim_++);
      const double before = ops_.dot(v, v);
      project(v, list);
      project(v, list);
      const double after = ops_.dot(v, v);
      if (after > 0x1p-20 * before) {
        ops_.scale(v, v, 1.0 / std::sqrt(after));
        return;
      }
    }
  }

  // The want-th smallest locked eigenvalue (locked_ is kept sorted).
  double lambda_want() const { return locked_[cfg_.want - 1].lambda; }

  void sort_and_trim_locked() {
    std::stable_sort(locked_.begin(), locked_.end(),
                     [](const Eigenpair<Scalar>& a, const Eigenpair<Scalar>& b) { return a.lambda < b.lambda; });
    if (locked_.size() > cfg_.want) locked_.resize(cfg_.want);
  }

  const SpectralOperator<Scalar>& op_;
  const VectorOps<Scalar>& ops_;
  const LanczosConfig& cfg_;
  const ProgressFn& progress_;
  std::size_t n_, m_, kk_;
  std::vector<Vec> v_;
  Vec w_, y_, r_;
  Vec next_;  // the unit vector that continues the basis after its last column (R1-SPEC-026)
  std::vector<Eigenpair<Scalar>> locked_;
  std::uint64_t next_dim_ = 0;
  std::uint32_t matvecs_ = 0;
};

template <class Scalar>
LanczosOutcome<Scalar> Solver<Scalar>::run() {
  LanczosOutcome<Scalar> out;
  const double tol = cfg_.tolerance;
  std::size_t k = 0;              // thick-restart Ritz vectors at the front of V
  std::vector<double> theta(0), b(0);
  bool verifying = false;          // the current basis grew from a fresh start after acceptance was possible
  fresh(0, 0);                     // the start vector: counter dimension 0 (R1-SPEC-030)
  for (std::uint32_t cycle = 1;; ++cycle) {
    out.cycles = cycle;
    // ---- extend the basis to m vectors (R1-SPEC-022..024) ----
    std::vector<double> h(m_ * m_, 0.0);
    for (std::size_t i = 0; i < k; ++i) {
      h[i * m_ + i] = theta[i];
      h[i * m_ + k] = h[k * m_ + i] = b[i];
    }
    double beta_prev = 0, beta_last = 0;
    for (std::size_t j = k; j < m_; ++j) {
      op_.apply(v_[j].data(), w_.data(), ops_.parallel());
      ++matvecs_;
      const double alpha = ops_.dot(v_[j], w_);
      // Local three-term step: w -= alpha v_j + (beta_{j-1} v_{j-1} | sum_i b_i v_i after a restart).
      std::vector<double> c{-alpha};
      std::vector<const Scalar*> xs{v_[j].data()};
      if (j == k) {
        for (std::size_t i = 0; i < k; ++i) {
          c.push_back(-b[i]);
          xs.push_back(v_[i].data());
        }
      } else {
        c.push_back(-beta_prev);
        xs.push_back(v_[j - 1].data());
      }
      ops_.combine(w_, w_.data(), c, xs);
      // Full re-orthogonalisation, classical Gram-Schmidt twice (R1-SPEC-023): the first pass on
      // w, the second on the normalised vector. Q32 rounds absolutely (2^-33 per entry), so the
      // rounding left by the first pass is about 2^-33 / sqrt(n) against every basis vector in
      // absolute terms and that divided by beta after normalisation; near an invariant subspace
      // (beta ~ 1e-6 on the 3D torus) that is 1e-6 of non-orthogonality, which the projected
      // matrix never sees and which then caps every Ritz residual. The second pass at unit scale
      // brings it back to the rounding level whatever beta is.
      const auto list = against(j + 1);
      project(w_, list);
      const double beta1 = std::sqrt(ops_.dot(w_, w_));
      h[j * m_ + j] = alpha;
      Vec& next = j + 1 < m_ ? v_[j + 1] : next_;
      double coupling = 0;
      bool breakdown = beta1 < kBreakdown;
      if (!breakdown) {
        ops_.scale(next, w_, 1.0 / beta1);
        project(next, list);
        const double n2 = ops_.dot(next, next);
        // Over half of the normalised vector lay in the basis: w was rounding noise, not a new
        // direction (only possible for beta1 within a few units of 2^-33 / sqrt(n)).
        breakdown = 2 * n2 < 1;
        if (!breakdown) {
          ops_.scale(next, next, 1.0 / std::sqrt(n2));
          // L v_j = ... + beta1 v' and v' = sqrt(n2) v_(j+1) + (the removed part, ~2^-33
          // absolute after multiplication by beta1), so the coupling is beta1 sqrt(n2).
          coupling = beta1 * std::sqrt(n2);
        }
      }
      // A breakdown (R1-SPEC-024) drops w, below the rounding level; after the last column the
      // restart draws the fresh vector.
      if (breakdown && j + 1 < m_) fresh_into(next, list);
      if (j + 1 < m_) {
        h[j * m_ + j + 1] = h[(j + 1) * m_ + j] = coupling;
        beta_prev = coupling;
      } else {
        beta_last = coupling;
      }
    }
    // ---- Rayleigh-Ritz (R1-SPEC-025) ----
    const JacobiResult eig = jacobi_eigen(m_, std::move(h));
    std::vector<double> y(m_ * kk_);
    for (std::size_t j = 0; j < m_; ++j)
      for (std::size_t c = 0; c < kk_; ++c) y[j * kk_ + c] = eig.vectors[j * m_ + c];
    std::vector<Scalar*> vp(m_);
    for (std::size_t j = 0; j < m_; ++j) vp[j] = v_[j].data();
    ops_.rotate(vp, m_, kk_, y);
    // ---- locking (R1-SPEC-027..028) ----
    std::size_t nl = 0;
    const double beta_eff = beta_last;  // 0 after a breakdown in the last column
    for (; nl < kk_; ++nl) {
      const double estimate = std::fabs(beta_eff * eig.vectors[(m_ - 1) * m_ + nl]);
      if (!(estimate <= tol)) break;
      double lambda = 0, residual = 0;
      rayleigh<Scalar>(op_, ops_, v_[nl], y_, r_, lambda, residual);
      ++matvecs_;
      if (!(residual <= tol)) break;
      if (locked_.size() >= cfg_.want && !(lambda < lambda_want() - tol)) break;
      locked_.push_back(Eigenpair<Scalar>{std::move(v_[nl]), lambda, residual});
      v_[nl] = Vec(n_);
      sort_and_trim_locked();
    }
    report(progress_, "spectral embedding: converged pairs", std::min<std::size_t>(locked_.size(), cfg_.want), cfg_.want);
    // ---- acceptance and verification (R1-SPEC-031..033) ----
    // The smallest Ritz value left in the basis. When it is not below lambda_want - tol, this
    // basis holds nothing better; a single-vector Krylov space cannot see a second copy of an
    // eigenvalue it already holds, so acceptance needs one full cycle grown from a fresh random
    // vector that finds and locks nothing below lambda_want - tol.
    bool restart_fresh = false;
    if (locked_.size() >= cfg_.want) {
      if (eig.values[nl] >= lambda_want() - tol) {
        if (verifying && nl == 0) {
          out.converged = true;
          break;
        }
        verifying = true;
        restart_fresh = true;
      } else {
        verifying = false;
      }
    }
    if (cycle >= cfg_.max_cycles) {
      // Out of cycles: the best available pairs, locked or not, with honest residuals.
      for (std::size_t i = nl; i < kk_; ++i) {
        double lambda = 0, residual = 0;
        rayleigh<Scalar>(op_, ops_, v_[i], y_, r_, lambda, residual);
        ++matvecs_;
        locked_.push_back(Eigenpair<Scalar>{std::move(v_[i]), lambda, residual});
        v_[i] = Vec(n_);
      }
      sort_and_trim_locked();
      break;
    }
    if (restart_fresh) {
      k = 0;
      fresh(0, 0);
      continue;
    }
    // ---- thick restart (R1-SPEC-026) ----
    k = kk_ - nl;
    std::rotate(v_.begin(), v_.begin() + static_cast<std::ptrdiff_t>(nl), v_.begin() + static_cast<std::ptrdiff_t>(kk_));
    theta.assign(eig.values.begin() + static_cast<std::ptrdiff_t>(nl), eig.values.begin() + static_cast<std::ptrdiff_t>(kk_));
    b.resize(k);
    for (std::size_t i = 0; i < k; ++i) b[i] = beta_eff * eig.vectors[(m_ - 1) * m_ + nl + i];
    if (beta_eff == 0.0) {
      fresh(k, k);
    } else {
      std::swap(v_[k], next_);
    }
  }
  out.matvecs = matvecs_;
  out.pairs = std::move(locked_);
  return out;
}

}  // namespace

template <class Scalar>
LanczosOutcome<Scalar> thick_restart_lanczos(const SpectralOperator<Scalar>& op, const VectorOps<Scalar>& ops,
                                             const LanczosConfig& config, const ProgressFn& progress) {
  Solver<Scalar> s(op, ops, config, progress);
  return s.run();
}

template void rayleigh(const SpectralOperator<fx::Q32>&, const VectorOps<fx::Q32>&, std::span<const fx::Q32>,
                       std::vector<fx::Q32>&, std::vector<fx::Q32>&, double&, double&);
template void rayleigh(const SpectralOperator<double>&, const VectorOps<double>&, std::span<const double>,
                       std::vector<double>&, std::vector<double>&, double&, double&);
template LanczosOutcome<fx::Q32> thick_restart_lanczos(const SpectralOperator<fx::Q32>&, const VectorOps<fx::Q32>&,
                                                       const LanczosConfig&, const ProgressFn&);
template LanczosOutcome<double> thick_restart_lanczos(const SpectralOperator<double>&, const VectorOps<double>&,
                                                      const LanczosConfig&, const ProgressFn&);

}  // namespace r1::spectral
