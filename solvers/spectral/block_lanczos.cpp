// Block thick-restart Lanczos (a symmetric block Krylov-Schur method) with full
// re-orthogonalisation and locking (R1-SPEC-020..035, R1-SPEC-061). Why a block: a Krylov space
// grown from one vector holds one direction of each eigenspace, so it can never see a second copy
// of a repeated eigenvalue; one grown from b random vectors holds min(b, multiplicity) of them
// (proofs/spectral_multiplicity.md).
#include "block_lanczos.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

#include "jacobi.hpp"

namespace r1::spectral {

// The compact copies a block application reads and writes, kept across applications: a fresh
// pair per application is n x b entries each (112 MB at 10^6 particles), whose pages the
// kernel would map and clear again every time. A block of fewer than 8 columns has rows of
// compact_ld(count) entries, whole divisions of a 64-byte line, and its first row starts a line
// (R1-SPEC-074): a row's gather then reads one line, and a backend's rows read the block in place
// instead of copying it to such rows first (at 10^6 a 64 MB copy per application). The entries
// of a row past its columns are zero, which the filter's recurrence keeps.
static std::size_t compact_ld(std::size_t count) { return count < 8 ? std::bit_ceil(count) : count; }

template <class Scalar>
class LineBlock {
 public:
  // `entries` entries, zero when first made, the first on a 64-byte boundary; kept as they are
  // while the size stays the same.
  Scalar* get(std::size_t entries) {
    constexpr std::size_t kLine = 64 / sizeof(Scalar);
    if (entries != size_) {
      std::vector<Scalar>().swap(buf_);  // the old block goes before the new one comes
      buf_.assign(entries + kLine, Scalar{});
      size_ = entries;
    }
    const auto misalign = reinterpret_cast<std::uintptr_t>(buf_.data()) % 64;
    return buf_.data() + (misalign == 0 ? 0 : (64 - misalign) / sizeof(Scalar));
  }

 private:
  std::vector<Scalar> buf_;
  std::size_t size_ = 0;
};

template <class Scalar>
struct CompactBlocks {
  LineBlock<Scalar> x, y, z;
};

// x <- panel columns src .. src + count - 1 as a block with rows ld apart (the entries past count
// zero), and back.
template <class Scalar>
void to_compact(const PanelOps<Scalar>& ops, const Panel<Scalar>& p, std::uint32_t src, std::size_t count,
                std::size_t ld, Scalar* x) {
  for_row_blocks(p.rows(), ops.parallel(), [&](std::size_t lo, std::size_t hi) {
    for (std::size_t i = lo; i < hi; ++i) {
      for (std::size_t c = 0; c < count; ++c) x[i * ld + c] = p.at(i, src + c);
      for (std::size_t c = count; c < ld; ++c) x[i * ld + c] = Scalar{};
    }
  });
}
template <class Scalar>
void from_compact(const PanelOps<Scalar>& ops, const Scalar* y, std::size_t count, std::size_t ld, Panel<Scalar>& p,
                  std::uint32_t dst) {
  for_row_blocks(p.rows(), ops.parallel(), [&](std::size_t lo, std::size_t hi) {
    for (std::size_t i = lo; i < hi; ++i)
      for (std::size_t c = 0; c < count; ++c) p.at(i, dst + c) = y[i * ld + c];
  });
}

// Columns dst.. <- L~ columns src.. (count of each, dst and src runs disjoint). The operator
// gathers a row of the source block per stored entry: from a compact copy those rows are a line
// or less apart instead of a whole panel row, which keeps large graphs in cache. The values are
// those of apply_block on the panel itself (which writes every entry of y).
template <class Scalar>
void apply_compact(const SpectralOperator<Scalar>& op, const PanelOps<Scalar>& ops, Panel<Scalar>& p, std::uint32_t src,
                   std::uint32_t dst, std::size_t count, CompactBlocks<Scalar>& buf) {
  const std::size_t n = p.rows(), ld = compact_ld(count);
  Scalar* x = buf.x.get(n * ld);
  Scalar* y = buf.z.get(n * ld);  // not y: a solve whose filter steps are fused never makes y
  to_compact(ops, p, src, count, ld, x);
  op.apply_block(x, ld, y, ld, count, ops.parallel());
  from_compact(ops, y, count, ld, p, dst);
}

template <class Scalar>
void rayleigh_block(const SpectralOperator<Scalar>& op, const PanelOps<Scalar>& ops, Panel<Scalar>& p, Cols xs, Cols ys,
                    std::uint32_t trivial, std::span<double> lambda, std::span<double> residual, CompactBlocks<Scalar>& buf) {
  const std::size_t k = xs.size();
  for (std::size_t c = 0; c < k; ++c)
    if (xs[c] != xs[0] + c || ys[c] != ys[0] + c) throw std::invalid_argument("rayleigh_block: columns must be runs");
  apply_compact(op, ops, p, xs[0], ys[0], k, buf);
  for (std::size_t c = 0; c < k; ++c) {
    const double xx = ops.dot(p, xs[c], xs[c]), xy = ops.dot(p, xs[c], ys[c]);
    lambda[c] = xy / xx;
    // r = L x - lambda x with one rounding per entry, then r - t <t, r> / <t, t> the same way,
    // then ||r|| / ||x|| (R1-SPEC-061).
    const std::uint32_t out[1] = {ys[c]}, term[1] = {xs[c]}, t_col[1] = {trivial};
    const double coef[1] = {-lambda[c]};
    ops.combine(p, out, out, term, coef);
    const double t_coef[1] = {-(ops.dot(p, trivial, ys[c]) / ops.dot(p, trivial, trivial))};
    ops.combine(p, out, out, t_col, t_coef);
    residual[c] = std::sqrt(ops.dot(p, ys[c], ys[c]) / xx);
  }
}

template <class Scalar>
void rayleigh_block(const SpectralOperator<Scalar>& op, const PanelOps<Scalar>& ops, Panel<Scalar>& p, Cols xs, Cols ys,
                    std::uint32_t trivial, std::span<double> lambda, std::span<double> residual) {
  CompactBlocks<Scalar> buf;
  rayleigh_block(op, ops, p, xs, ys, trivial, lambda, residual, buf);
}

namespace {

using Col = std::uint32_t;

std::vector<Col> col_run(Col first, std::size_t count) {
  std::vector<Col> v(count);
  std::iota(v.begin(), v.end(), first);
  return v;
}

// Two passes W = list c1 + V1 r1 and V1 = list c2 + V r2 compose to W = list c + V r with
// c = c1 + c2 r1 and r = r2 r1 (c: rows per list column, r: b x b, row-major; sums in ascending
// index order).
void compose_passes(std::size_t b, const std::vector<double>& c1, const std::vector<double>& r1,
                    const std::vector<double>& c2, const std::vector<double>& r2, std::vector<double>& c,
                    std::vector<double>& r) {
  const std::size_t nl = c1.size() / b;
  c.assign(nl * b, 0.0);
  for (std::size_t q = 0; q < nl; ++q)
    for (std::size_t j = 0; j < b; ++j) {
      double s = c1[q * b + j];
      for (std::size_t i = 0; i < b; ++i) s = s + c2[q * b + i] * r1[i * b + j];
      c[q * b + j] = s;
    }
  r.assign(b * b, 0.0);
  for (std::size_t i = 0; i < b; ++i)
    for (std::size_t j = 0; j < b; ++j) {
      double s = 0.0;
      for (std::size_t k = 0; k < b; ++k) s = s + r2[i * b + k] * r1[k * b + j];
      r[i * b + j] = s;
    }
}

template <class Scalar>
class Solver {
 public:
  Solver(const SpectralOperator<Scalar>& op, const PanelOps<Scalar>& ops, std::span<const Scalar> trivial,
         const BlockLanczosConfig& cfg, const ProgressFn& progress)
      : op_(op), ops_(ops), cfg_(cfg), progress_(progress), b_(cfg.block), m_(cfg.basis), keep_(cfg.keep),
        base_(1 + cfg.want), next_(base_ + cfg.basis), scratch_(next_ + cfg.block),
        p_(op.n, scratch_ + cfg.block) {
    // b >= want is the canonical choice (R1-SPEC-021); narrower blocks are accepted for the test
    // that shows why.
    if (b_ == 0 || m_ % b_ != 0 || keep_ < cfg.want + b_ || keep_ + 2 * b_ > m_)
      throw std::invalid_argument("block Lanczos: inconsistent configuration");
    p_.set_column(0, trivial);
    for (Col s = 1; s <= cfg.want; ++s) free_slots_.push_back(s);
  }

  LanczosOutcome<Scalar> run();

  // The start block: b fresh vectors, counter dimensions 0, 1, ... (R1-SPEC-030), in the first
  // basis columns.
  void start() {
    for (std::size_t j = 0; j < b_; ++j) fresh(base_ + static_cast<Col>(j), against(j));
  }
  std::vector<Scalar> basis_column(std::size_t j) const { return p_.copy_column(base_ + j); }

 private:
  struct Locked {
    Col slot;
    double lambda, residual;
  };

  // The columns every new basis vector is kept orthogonal to: the trivial vector, the locked
  // ones in ascending order of their eigenvalue, and the first `upto` basis columns, in that
  // order (R1-SPEC-022).
  std::vector<Col> against(std::size_t upto) const {
    std::vector<Col> list;
    list.reserve(1 + locked_.size() + upto);
    list.push_back(0);
    for (const Locked& l : locked_) list.push_back(l.slot);
    for (std::size_t j = 0; j < upto; ++j) list.push_back(base_ + static_cast<Col>(j));
    return list;
  }

  // One classical Gram-Schmidt pass on the columns ws against `list`: w <- w - sum_q <q, w> q, one
  // rounding per entry; coef receives the inner products (list.size() x ws.size(), row-major).
  void project(Cols ws, const std::vector<Col>& list, std::vector<double>& coef) {
    coef.assign(list.size() * ws.size(), 0.0);
    ops_.dots(p_, list, ws, coef);
    std::vector<double> neg(coef);
    for (double& x : neg) x = -x;
    ops_.combine(p_, ws, ws, list, neg);
  }
  void project(Col c, const std::vector<Col>& list) {
    const Col cc[1] = {c};
    std::vector<double> unused;
    project(cc, list, unused);
  }

  // Column c <- a fresh random unit vector orthogonal to `list` (R1-SPEC-030): counter dimension
  // next_dim_, two projection passes; a draw that loses all but 2^-20 of its squared length to
  // the projection is replaced by the next dimension. The basis never fills more than half the
  // space (R1-SPEC-021), so a draw keeps most of its length; 64 failures in a row mean a bug.
  void fresh(Col c, const std::vector<Col>& list) {
    for (int attempt = 0; attempt < 64; ++attempt) {
      ops_.random(p_, c, cfg_.seed, next_dim_++);
      const double before = ops_.dot(p_, c, c);
      project(c, list);
      project(c, list);
      const double after = ops_.dot(p_, c, c);
      if (after > 0x1p-20 * before) {
        ops_.scale(p_, c, 1.0 / std::sqrt(after));
        return;
      }
    }
    throw std::runtime_error("spectral: no fresh vector outside the basis after 64 draws");
  }

  void apply(Col src, Col dst, std::size_t count) {
    if (filter_.on()) return apply_filtered(src, dst, count);
    apply_compact(op_, ops_, p_, src, dst, count, compact_);
    matvecs_ += static_cast<std::uint32_t>(count);
    ++passes_;
  }
  // Columns dst.. <- K columns src.. (R1-SPEC-081): the filter's recurrence on compact blocks, one
  // block application per degree.
  void apply_filtered(Col src, Col dst, std::size_t count) {
    const ChebyshevFilter& f = filter_;
    const double e = f.e(), c = f.c(), s1 = f.s1(), tau = 2 / s1;
    const std::size_t n = p_.rows(), b = count, ld = compact_ld(b), len = n * ld;
    Scalar* cur = compact_.x.get(len);
    Scalar* prev = compact_.z.get(len);
    Scalar* img = nullptr;  // L cur, where the backend's rows do not fuse the step (R1-SPEC-075)
    to_compact(ops_, p_, src, b, ld, cur);
    // One step: prev <- alpha L cur + beta cur + gamma prev (gamma = 0: prev is not read), then
    // the two swap roles. The entries of a row past b are zero in cur (to_compact) and in L cur,
    // so they are zero in every block the recurrence makes.
    auto step = [&](double alpha, double beta, double gamma) {
      matvecs_ += static_cast<std::uint32_t>(b);
      ++passes_;
      if (img == nullptr && op_.apply_three_term(cur, ld, prev, b, alpha, beta, gamma, ops_.parallel())) {
        std::swap(cur, prev);
        return;
      }
      if (img == nullptr) {
        img = compact_.y.get(len);
        if (ld > b) {
          for_row_blocks(n, ops_.parallel(), [&](std::size_t lo, std::size_t hi) {
            for (std::size_t i = lo; i < hi; ++i)
              for (std::size_t k = b; k < ld; ++k) img[i * ld + k] = Scalar{};
          });
        }
      }
      op_.apply_block(cur, ld, img, ld, b, ops_.parallel());
      ops_.three_term(len, img, cur, prev, alpha, beta, gamma);
      std::swap(cur, prev);
    };
    // Y1 = -(s1/e) (L X - c X) (Y0 = -X), into prev's buffer; then cur = Y1, prev = X.
    step(-s1 / e, c * s1 / e, 0.0);
    double sg = s1;
    for (std::uint32_t i = 2; i <= f.degree; ++i) {
      const double sn = 1 / (tau - sg);
      // Y_new = 2 sn/e (L Y - c Y) - sg sn Y_prev, over Y_prev.
      step(2 * sn / e, -2 * c * sn / e, i == 2 ? sg * sn : -sg * sn);
      sg = sn;
    }
    from_compact(ops_, cur, b, ld, p_, dst);
  }

  void orthonormalize_block(Col w0, const std::vector<Col>& list, std::size_t gap_begin, std::size_t gap_end,
                           std::vector<double>& c, std::vector<double>& r);
  bool fused_pass(Col w0, const std::vector<Col>& list, std::vector<double>& c, std::vector<double>& r, bool second);
  void robust_block(Col w0, const std::vector<Col>& list, std::vector<double>& c, std::vector<double>& r);

  // The want-th smallest locked eigenvalue (locked_ is kept sorted).
  double lambda_want() const { return locked_[cfg_.want - 1].lambda; }

  // Adds column `col` to the locked pairs: into a free slot, or, when all `want` are taken, over
  // the largest (the last in the stable ascending order), which it must beat. The list stays
  // sorted ascending by a stable sort, so equal eigenvalues keep their locking order.
  void offer(Col col, double lambda, double residual) {
    Col slot = 0;
    if (!free_slots_.empty()) {
      slot = free_slots_.front();
      free_slots_.erase(free_slots_.begin());
    } else {
      if (!(lambda < locked_.back().lambda)) return;
      slot = locked_.back().slot;
      locked_.pop_back();
    }
    ops_.copy(p_, slot, col);
    locked_.push_back(Locked{slot, lambda, residual});
    std::stable_sort(locked_.begin(), locked_.end(), [](const Locked& a, const Locked& b) { return a.lambda < b.lambda; });
  }

  const SpectralOperator<Scalar>& op_;
  const PanelOps<Scalar>& ops_;
  const BlockLanczosConfig& cfg_;
  const ProgressFn& progress_;
  const std::size_t b_, m_, keep_;
  // Panel columns: 0 the trivial vector, 1..want the locked slots, [base_, base_ + m) the basis,
  // [next_, next_ + b) the block that continues the basis after its last column, then b scratch.
  const Col base_, next_, scratch_;
  ChebyshevFilter filter_;
  Panel<Scalar> p_;
  std::vector<Locked> locked_;
  std::vector<Col> free_slots_;
  std::uint64_t next_dim_ = 0;
  std::uint32_t matvecs_ = 0, passes_ = 0, robust_blocks_ = 0;
  CompactBlocks<Scalar> compact_;
};

// The new block W = L V_s in columns w0.. (b of them) <- an orthonormal block V_(s+1), with
// L V_s = list C + V_(s+1) R up to rounding (R1-SPEC-023..024). c is list.size() x b, r is b x b
// upper triangular, both row-major. Two fused passes serve every step they can: the first against
// the near list, which is `list` less its entries [gap_begin, gap_end) (their rows of the first
// pass's C are 0), the second against the whole list. The robust path takes over from whatever a
// declined pass left (nothing is written by a declined pass).
template <class Scalar>
void Solver<Scalar>::orthonormalize_block(Col w0, const std::vector<Col>& list, std::size_t gap_begin,
                                          std::size_t gap_end, std::vector<double>& c, std::vector<double>& r) {
  const auto at = [&list](std::size_t i) { return list.begin() + static_cast<std::ptrdiff_t>(i); };
  std::vector<Col> near(list.begin(), at(gap_begin));
  near.insert(near.end(), at(gap_end), list.end());
  std::vector<double> c1, r1, c2, r2;
  if (!fused_pass(w0, near, c1, r1, false)) {
    ++robust_blocks_;
    robust_block(w0, list, c, r);
    return;
  }
  if (gap_end > gap_begin) {
    // The first pass's C on the whole list's rows.
    std::vector<double> whole(list.size() * b_, 0.0);
    const auto row = [this](std::vector<double>& v, std::size_t i) { return v.begin() + static_cast<std::ptrdiff_t>(i * b_); };
    std::copy(row(c1, 0), row(c1, gap_begin), whole.begin());
    std::copy(row(c1, gap_begin), c1.end(), row(whole, gap_end));
    c1.swap(whole);
  }
  if (!fused_pass(w0, list, c2, r2, true)) {
    ++robust_blocks_;
    robust_block(w0, list, c2, r2);
  }
  compose_passes(b_, c1, r1, c2, r2, c, r);
}

// One fused block Gram-Schmidt pass (R1-SPEC-023): one sweep computes C = list^T W and
// G = W^T W; the Gram matrix of W's part outside the list, G - C^T C, factors as R^T R (Cholesky,
// fp64, fixed order); one combination forms V = W R^-1 - list (C R^-1), each entry one exact sum
// rounded once, so V is normalised by the same rounding that projects it. Terms of the list whose
// coefficients in C R^-1 are all at most kApplyFloor are left out (V is orthogonal to them within
// that bound already). Coefficients of 8 or more are scaled by 2^-k into range and the result by
// 2^k (exact). Declined, with nothing written, when a pivot is not clearly positive
// (kPivotFloor: the Gram matrix's rounding could then dominate it), when a second pass finds a
// column that lost over half its length (rounding noise, not a direction), or when k would
// exceed kMaxScaleBits.
template <class Scalar>
bool Solver<Scalar>::fused_pass(Col w0, const std::vector<Col>& list, std::vector<double>& c, std::vector<double>& r,
                                bool second) {
  const std::size_t nl = list.size(), b = b_;
  const std::vector<Col> w = col_run(w0, b);
  std::vector<Col> qs = list;
  qs.insert(qs.end(), w.begin(), w.end());
  std::vector<double> g((nl + b) * b);
  ops_.dots(p_, qs, w, g);
  // gp = G - C^T C: the Gram matrix of W after the projection, sums over q ascending.
  std::vector<double> gp(b * b);
  for (std::size_t i = 0; i < b; ++i)
    for (std::size_t j = 0; j < b; ++j) {
      double s = g[(nl + i) * b + j];
      for (std::size_t q = 0; q < nl; ++q) s = s - g[q * b + i] * g[q * b + j];
      gp[i * b + j] = s;
    }
  // Cholesky gp = R^T R, R upper triangular, row by row.
  std::vector<double> rr(b * b, 0.0);
  for (std::size_t i = 0; i < b; ++i) {
    double d = gp[i * b + i];
    for (std::size_t k = 0; k < i; ++k) d = d - rr[k * b + i] * rr[k * b + i];
    if (!(d > kPivotFloor * g[(nl + i) * b + i]) || !(d > 0)) return false;
    if (second && 2 * d < 1) return false;
    const double rii = std::sqrt(d);
    rr[i * b + i] = rii;
    for (std::size_t j = i + 1; j < b; ++j) {
      double s = gp[i * b + j];
      for (std::size_t k = 0; k < i; ++k) s = s - rr[k * b + i] * rr[k * b + j];
      rr[i * b + j] = s / rii;
    }
  }
  // R^-1 (upper triangular) by back substitution, column by column.
  std::vector<double> ri(b * b, 0.0);
  for (std::size_t j = 0; j < b; ++j) {
    ri[j * b + j] = 1.0 / rr[j * b + j];
    for (std::size_t i = j; i-- > 0;) {
      double s = 0.0;
      for (std::size_t k = i + 1; k <= j; ++k) s = s + rr[i * b + k] * ri[k * b + j];
      ri[i * b + j] = -s / rr[i * b + i];
    }
  }
  // Terms: W with R^-1, then the list columns that matter with -(C R^-1).
  std::vector<Col> terms = w;
  std::vector<double> coef(ri);
  for (std::size_t q = 0; q < nl; ++q) {
    std::vector<double> row(b);
    bool apply = false;
    for (std::size_t j = 0; j < b; ++j) {
      double s = 0.0;
      for (std::size_t k = 0; k <= j; ++k) s = s + g[q * b + k] * ri[k * b + j];
      row[j] = -s;
      apply = apply || std::fabs(s) > kApplyFloor;
    }
    if (!apply) continue;
    terms.push_back(list[q]);
    coef.insert(coef.end(), row.begin(), row.end());
  }
  // The smallest k with every |coefficient| 2^-k below 8.
  double biggest = 0;
  for (const double x : coef) biggest = std::max(biggest, std::fabs(x));
  int k = 0;
  while (!(std::ldexp(biggest, -k) < 8.0)) {
    if (++k > kMaxScaleBits) return false;
  }
  for (double& x : coef) x = std::ldexp(x, -k);
  ops_.combine(p_, w, {}, terms, coef);
  if (k > 0)
    for (const Col col : w) ops_.scale(p_, col, std::ldexp(1.0, k));
  c.assign(g.begin(), g.begin() + static_cast<std::ptrdiff_t>(nl * b));
  r = std::move(rr);
  return true;
}

// The robust path (R1-SPEC-024): classical Gram-Schmidt against the list, Gram-Schmidt inside the
// block with normalisation, both twice, the second pass at unit scale. A column left shorter than
// the pass's floor (pass 1: kBreakdown; pass 2: 2^-1/2) was rounding noise, not a new direction:
// it becomes a fresh random vector orthogonal to the list and the columns before it, and its
// coupling is 0.
template <class Scalar>
void Solver<Scalar>::robust_block(Col w0, const std::vector<Col>& list, std::vector<double>& c, std::vector<double>& r) {
  const std::size_t b = b_;
  const std::vector<Col> w = col_run(w0, b);
  auto inside = [&](std::vector<double>& tri, bool second) {
    tri.assign(b * b, 0.0);
    for (std::size_t j = 0; j < b; ++j) {
      const Col cj[1] = {w[j]};
      std::vector<double> h(j);
      if (j > 0) {
        const std::span<const Col> before(w.data(), j);
        ops_.dots(p_, before, cj, h);
        std::vector<double> neg(h);
        for (double& x : neg) x = -x;
        ops_.combine(p_, cj, cj, before, neg);
      }
      const double nn = ops_.dot(p_, w[j], w[j]);
      const bool noise = second ? 2 * nn < 1 : !(std::sqrt(nn) >= kBreakdown);
      if (noise) {
        std::vector<Col> l2 = list;
        l2.insert(l2.end(), w.begin(), w.begin() + static_cast<std::ptrdiff_t>(j));
        fresh(w[j], l2);
        // Pass 1 keeps the coefficients against the columns before (w_j was their combination
        // plus noise); pass 2 drops the whole column, whose first-pass part was the noise.
        if (!second)
          for (std::size_t i = 0; i < j; ++i) tri[i * b + j] = h[i];
        continue;
      }
      const double len = std::sqrt(nn);
      ops_.scale(p_, w[j], 1.0 / len);
      for (std::size_t i = 0; i < j; ++i) tri[i * b + j] = h[i];
      tri[j * b + j] = len;
    }
  };
  std::vector<double> c1, c2, r1, r2;
  project(w, list, c1);
  inside(r1, false);
  project(w, list, c2);
  inside(r2, true);
  compose_passes(b_, c1, r1, c2, r2, c, r);
}

template <class Scalar>
LanczosOutcome<Scalar> Solver<Scalar>::run() {
  LanczosOutcome<Scalar> out;
  const double tol = cfg_.tolerance;
  std::size_t k = 0;          // thick-restart Ritz vectors at the front of the basis
  std::vector<double> theta;  // their Ritz values
  start();
  std::vector<double> c, r, r_last;
  for (std::uint32_t cycle = 1;; ++cycle) {
    out.cycles = cycle;
    // ---- extend the basis block by block (R1-SPEC-022..024) ----
    std::vector<double> h(m_ * m_, 0.0);  // upper triangle of the projected matrix
    for (std::size_t i = 0; i < k; ++i) h[i * m_ + i] = theta[i];
    std::size_t s = k, mm = 0;
    for (;;) {
      const bool last = s + 2 * b_ > m_;
      const Col dst = last ? next_ : base_ + static_cast<Col>(s + b_);
      apply(base_ + static_cast<Col>(s), dst, b_);
      const std::vector<Col> list = against(s + b_);
      // The near list of the first pass (R1-SPEC-022): the trivial and locked vectors and the
      // basis from the block before V_s on; at a cycle's first step the whole basis, since W then
      // couples with every kept Ritz vector (the Krylov-Schur arrow).
      const std::size_t head = 1 + locked_.size();
      orthonormalize_block(dst, list, head, head + (s == k ? 0 : s - b_), c, r);
      // Column block s of H: the coefficients against the basis (the trivial and locked
      // coefficients are rounding noise and leave).
      const std::size_t off = 1 + locked_.size();
      for (std::size_t j = 0; j < s + b_; ++j)
        for (std::size_t col = 0; col < b_; ++col) h[j * m_ + s + col] = c[(off + j) * b_ + col];
      if (last) {
        mm = s + b_;
        r_last = r;
        break;
      }
      s += b_;
    }
    // ---- Rayleigh-Ritz (R1-SPEC-025) ----
    std::vector<double> hm(mm * mm);
    for (std::size_t i = 0; i < mm; ++i)
      for (std::size_t j = 0; j < mm; ++j) hm[i * mm + j] = h[i * m_ + j];
    const JacobiResult eig = jacobi_eigen(mm, std::move(hm));
    const std::size_t kk = std::min(keep_, mm);
    {
      std::vector<double> y(mm * kk);
      for (std::size_t j = 0; j < mm; ++j)
        for (std::size_t col = 0; col < kk; ++col) y[j * kk + col] = eig.vectors[j * mm + col];
      const std::vector<Col> basis = col_run(base_, mm), ritz = col_run(base_, kk);
      ops_.combine(p_, ritz, {}, basis, y);
    }
    // Residual estimates ||R_last s_last|| (R1-SPEC-027): the Ritz vector's residual lies in the
    // continuation block, with coefficients R_last times its last b coordinates.
    std::vector<double> estimate(kk);
    for (std::size_t col = 0; col < kk; ++col) {
      double ss = 0.0;
      for (std::size_t i = 0; i < b_; ++i) {
        double e = 0.0;
        for (std::size_t j = 0; j < b_; ++j) e = e + r_last[i * b_ + j] * eig.vectors[(mm - b_ + j) * mm + col];
        ss = ss + e * e;
      }
      estimate[col] = filter_.on() ? filter_.residual_estimate(eig.values[col], std::sqrt(ss)) : std::sqrt(ss);
    }
    // ---- locking (R1-SPEC-027..028) ----
    std::size_t nl = 0;
    bool filter_floor = false;
    for (bool stop = false; !stop && nl < kk;) {
      std::size_t len = 0;
      while (len < b_ && nl + len < kk && estimate[nl + len] <= tol) ++len;
      if (len == 0) break;
      std::vector<double> lam(len), res(len);
      rayleigh_block(op_, ops_, p_, col_run(base_ + static_cast<Col>(nl), len), col_run(scratch_, len), 0, lam, res, compact_);
      matvecs_ += static_cast<std::uint32_t>(len);
      ++passes_;
      for (std::size_t i = 0; i < len; ++i) {
        if (!(res[i] <= tol) || (locked_.size() >= cfg_.want && !(lam[i] < lambda_want() - tol))) {
          // Under the filter, a pair whose estimate passed but whose residual does not is at the
          // floor of K's rounding (R1-SPEC-083).
          filter_floor = filter_floor || (filter_.on() && !(res[i] <= tol));
          stop = true;
          break;
        }
        offer(base_ + static_cast<Col>(nl), lam[i], res[i]);
        ++nl;
      }
    }
    report(progress_, filter_.on() ? "spectral embedding (filtered): converged pairs" : "spectral embedding: converged pairs", std::min<std::size_t>(locked_.size(), cfg_.want), cfg_.want);
    // ---- acceptance (R1-SPEC-031) ----
    // Every wanted pair is locked and the smallest Ritz value left in the basis is not below the
    // want-th: this block Krylov space holds nothing better.
    if (locked_.size() >= cfg_.want &&
        !(eig.values[nl] < (filter_.on() ? filter_.value(lambda_want() - tol) : lambda_want() - tol))) {
      out.converged = true;
      break;
    }
    if (cycle >= cfg_.max_cycles) {
      // Out of cycles (R1-SPEC-034): the best Ritz vectors fill the missing pairs, with their
      // honest residuals.
      for (std::size_t i = nl; i < kk; i += b_) {
        const std::size_t len = std::min(b_, kk - i);
        std::vector<double> lam(len), res(len);
        rayleigh_block(op_, ops_, p_, col_run(base_ + static_cast<Col>(i), len), col_run(scratch_, len), 0, lam, res, compact_);
        matvecs_ += static_cast<std::uint32_t>(len);
        ++passes_;
        for (std::size_t j = 0; j < len; ++j) offer(base_ + static_cast<Col>(i + j), lam[j], res[j]);
      }
      break;
    }
    // ---- the Chebyshev filter (R1-SPEC-080, R1-SPEC-083) ----
    bool fresh_start = false;
    if (!filter_.on() && cfg_.filter_degree > 1 && cycle == cfg_.filter_after && mm > cfg_.want) {
      // a: the first Ritz value from index `filter_index` on that lies above the want-th by 2^-16 of
      // it; as Ritz values bound the eigenvalues from above, a >= (1 + 2^-16) lambda_w, so no copy
      // of a wanted eigenvalue sits on the damped interval's edge.
      const double edge = eig.values[cfg_.want - 1] * (1 + 0x1p-16);
      std::size_t j = std::max<std::size_t>(cfg_.filter_index, cfg_.want);
      while (j < mm && !(eig.values[j] >= edge)) ++j;
      // al: the smallest Ritz value not locked (the locked ones are deflated). The degree: the
      // highest up to filter_degree whose gain at the smallest Ritz value over the want-th stays
      // within tol 2^42, so that K's rounding (2^-48 of its largest part) stays below tol
      // (R1-SPEC-080).
      const double al = eig.values[nl];
      if (j < mm && eig.values[j] < 1 && al < eig.values[j]) {
        const ChebyshevFilter probe{1, eig.values[j], al};
        const double x0 = (probe.c() - eig.values[0]) / probe.e(), xw = (probe.c() - eig.values[cfg_.want - 1]) / probe.e();
        std::uint32_t d = 1;
        double t0 = 1, t1 = x0, w0 = 1, w1 = xw;  // T_d(x0), T_d(xw) by the three-term recurrence
        while (d < cfg_.filter_degree) {
          const double t2 = 2 * x0 * t1 - t0, w2 = 2 * xw * w1 - w0;
          if (!(t2 <= cfg_.tolerance * 0x1p42 * w2)) break;
          t0 = t1;
          t1 = t2;
          w0 = w1;
          w1 = w2;
          ++d;
        }
        if (d > 1) {
          filter_ = ChebyshevFilter{d, eig.values[j], al};
          fresh_start = true;
        }
      }
    } else if (filter_.on() && (filter_floor || cycle >= cfg_.filter_after + cfg_.filter_cycles)) {
      filter_ = ChebyshevFilter{};  // at K's floor, or the filter's cycles spent: plain cycles from here
      fresh_start = true;
    }
    if (fresh_start) {
      // A fresh Krylov space from the first b Ritz vectors not locked.
      ops_.move(p_, col_run(base_, b_), col_run(base_ + static_cast<Col>(nl), b_));
      // Orthonormal against the trivial and locked vectors again: a start block is never
      // projected later, and what it keeps along a locked vector K would amplify.
      std::vector<double> c0, r0;
      orthonormalize_block(base_, against(0), 0, 0, c0, r0);
      k = 0;
      theta.clear();
      continue;
    }
    // ---- thick restart (R1-SPEC-026) ----
    k = kk - nl;
    {
      // The kept Ritz vectors to the front, the continuation block after them: one sweep.
      std::vector<Col> src = col_run(base_ + static_cast<Col>(nl), k), dst = col_run(base_, k + b_);
      const std::vector<Col> next = col_run(next_, b_);
      src.insert(src.end(), next.begin(), next.end());
      ops_.move(p_, dst, src);
    }
    theta.assign(eig.values.begin() + static_cast<std::ptrdiff_t>(nl), eig.values.begin() + static_cast<std::ptrdiff_t>(kk));
  }
  out.matvecs = matvecs_;
  out.passes = passes_;
  out.robust_blocks = robust_blocks_;
  for (const Locked& l : locked_) out.pairs.push_back(Eigenpair<Scalar>{p_.copy_column(l.slot), l.lambda, l.residual});
  return out;
}

}  // namespace

std::pair<double, double> ChebyshevFilter::value_slope(double lam) const {
  const double ee = e(), cc = c(), s = s1(), tau = 2 / s;
  double y0 = -1, d0 = 0, y1 = -(lam - cc) * s / ee, d1 = -s / ee, sg = s;
  for (std::uint32_t i = 2; i <= degree; ++i) {
    const double sn = 1 / (tau - sg);
    const double y2 = 2 * sn / ee * (lam - cc) * y1 - sg * sn * y0;
    const double d2 = 2 * sn / ee * ((lam - cc) * d1 + y1) - sg * sn * d0;
    y0 = y1;
    d0 = d1;
    y1 = y2;
    d1 = d2;
    sg = sn;
  }
  return {y1, d1};
}

double ChebyshevFilter::preimage(double theta) const {
  double lo = 0, hi = a;
  for (int it = 0; it < 64; ++it) {
    const double mid = (lo + hi) / 2;
    if (value(mid) < theta) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  return (lo + hi) / 2;
}

double ChebyshevFilter::residual_estimate(double theta, double est_k) const {
  const double band = std::fabs(value(a));
  if (!(theta < -band)) return std::numeric_limits<double>::infinity();
  const double slope = std::fabs(value_slope(preimage(theta)).second);
  return est_k * std::max(1 / slope, 2 / (std::fabs(theta) - band));
}

BlockLanczosConfig canonical_config(std::uint32_t n, std::uint32_t want, const SpectralParams& params, std::uint64_t seed) {
  // Default cap on restarts when SpectralParams::max_restarts is 0 (R1-SPEC-034): far above the
  // cycles any measured graph needed (spec/spectral.md, performance), so it only stops a solve
  // that cannot reach the tolerance.
  constexpr std::uint32_t kDefaultMaxRestarts = 1000;
  BlockLanczosConfig cfg;
  cfg.want = want;
  // Blocks two wider than the wanted pairs (R1-SPEC-021): at least `want` wide puts every copy of
  // an eigenvalue among them in reach (proofs/spectral_multiplicity.md); the two extra columns
  // move the gap that governs block convergence from lambda_(want+1) out to lambda_(want+3), which
  // on the clustered low end of large scale-free graphs saves 15% of the passes over the operator
  // (BA 10^5: 357 passes with b = 5, 338 with 6, 303 with 7 at the same ~160-190 basis columns;
  // wider blocks gain little more per pass and cost more vectors).
  cfg.block = want + 2;
  // m = basis block steps of b columns, at most half the deflated space (so fresh vectors always
  // find room), and room for the kept Ritz vectors plus two blocks.
  const std::uint32_t room = (n - 1 - want) / (2 * cfg.block);
  cfg.basis = cfg.block * std::min(params.basis, room);
  // Ritz vectors kept at a restart: 3/8 of the basis, at least want + b (R1-SPEC-026).
  cfg.keep = std::max<std::uint32_t>(want + cfg.block, cfg.basis * 3 / 8);
  cfg.tolerance = params.tolerance;
  cfg.max_cycles = (params.max_restarts == 0 ? kDefaultMaxRestarts : params.max_restarts) + 1;
  cfg.seed = seed;
  cfg.filter_degree = params.filter_degree;
  return cfg;
}

template <class Scalar>
LanczosOutcome<Scalar> block_lanczos(const SpectralOperator<Scalar>& op, const PanelOps<Scalar>& ops,
                                     std::span<const Scalar> trivial, const BlockLanczosConfig& config,
                                     const ProgressFn& progress) {
  Solver<Scalar> s(op, ops, trivial, config, progress);
  return s.run();
}

template <class Scalar>
std::vector<std::vector<Scalar>> start_block(const SpectralOperator<Scalar>& op, const PanelOps<Scalar>& ops,
                                             std::span<const Scalar> trivial, const BlockLanczosConfig& config) {
  const ProgressFn none;
  Solver<Scalar> s(op, ops, trivial, config, none);
  s.start();
  std::vector<std::vector<Scalar>> out;
  for (std::size_t j = 0; j < config.block; ++j) out.push_back(s.basis_column(j));
  return out;
}

template std::vector<std::vector<fx::Q32>> start_block(const SpectralOperator<fx::Q32>&, const PanelOps<fx::Q32>&,
                                                       std::span<const fx::Q32>, const BlockLanczosConfig&);
template std::vector<std::vector<double>> start_block(const SpectralOperator<double>&, const PanelOps<double>&,
                                                      std::span<const double>, const BlockLanczosConfig&);
template void rayleigh_block(const SpectralOperator<fx::Q32>&, const PanelOps<fx::Q32>&, Panel<fx::Q32>&, Cols, Cols,
                             std::uint32_t, std::span<double>, std::span<double>);
template void rayleigh_block(const SpectralOperator<double>&, const PanelOps<double>&, Panel<double>&, Cols, Cols,
                             std::uint32_t, std::span<double>, std::span<double>);
template LanczosOutcome<fx::Q32> block_lanczos(const SpectralOperator<fx::Q32>&, const PanelOps<fx::Q32>&,
                                               std::span<const fx::Q32>, const BlockLanczosConfig&, const ProgressFn&);
template LanczosOutcome<double> block_lanczos(const SpectralOperator<double>&, const PanelOps<double>&,
                                              std::span<const double>, const BlockLanczosConfig&, const ProgressFn&);

}  // namespace r1::spectral
