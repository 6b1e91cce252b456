// The tri-kernel operators on the layout graph: prior, diffusion, springs and the walk matrix N of
// the heat kernel, in Q32 and fp64 (R1-FOC-011, R1-FOC-020..041, R1-FOC-080..081, R1-FOC-090).
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstdint>
#include <memory>
#include <span>
#include <stdexcept>
#include <vector>

#include "r1/fixedpoint/int128.hpp"
#include "r1/fixedpoint/prefetch.hpp"
#include "r1/fixedpoint/q32.hpp"
#include "r1/spec/epoch.hpp"
#include "r1/spec/graph.hpp"
#include "r1/solvers/focus.hpp"
#include "r1/spec/status.hpp"

namespace r1::focus {

// Runs body(begin, end) over [0, n): serially, or on TBB threads in blocks. Callers write only
// the rows of their block, each a pure function of read-only inputs, so both give the same bits.
template <class Body>
void for_rows(bool parallel, std::uint32_t n, const Body& body) {
  // 2048 rows per task: large enough that task overhead is noise for sparse rows of ~10 entries,
  // small enough that a hub row does not leave the other threads idle for long.
  constexpr std::uint32_t kGrain = 2048;
  if (!parallel || n <= kGrain) {
    body(std::uint32_t{0}, n);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, n, kGrain),
                    [&](const tbb::blocked_range<std::uint32_t>& r) { body(r.begin(), r.end()); });
}

// How far ahead, in stored entries, the Q32 row loops prefetch the vector entry they will gather.
// On graphs larger than the caches a sparse product's time goes to these gathers, whose columns
// no reordering makes local on a small-world graph; a prefetch hint changes no bit (R1-FOC-090).
// Measured on BA 10^6 (m = 10), one walk on two cores: 29-52 ms without, 20-21 ms at 64 (32:
// 21 ms, 16: 23-25 ms, 8: 27 ms); reordering the particles (breadth first, by degree) gained
// nothing over the canonical order. Since the hint fetches into the second-level cache
// (fx::gather_hint), 160 ahead: a BA 10^6 focus step 0.138-0.143 s -> 0.123 s (64: 0.125-0.130 s).
inline constexpr std::uint64_t kGatherAhead = 160;
template <class T>
inline void gather_ahead(const T* x, const std::uint32_t* col, std::uint64_t k, std::uint64_t end) {
  if (k + kGatherAhead < end) fx::gather_hint(x + col[k + kGatherAhead]);
}

// Apportioned shares of one (raws in [0, 2^32], R1-FOC-020, R1-FOC-041), stored in four bytes
// each when every raw is below 2^32 (a row of one entry, or one whose other weights are too small
// to get a unit, has a share of 2^32 and keeps the operator in eight-byte form): a product over
// the whole graph streams its shares and columns from memory, 12 bytes an entry in eight-byte form
// and 8 in four-byte form (speed only; the values are the same).
class Shares {
 public:
  Shares() = default;
  explicit Shares(std::vector<std::int64_t> raws);
  std::size_t size() const { return size_; }
  // One of the two is non-null.
  const std::uint32_t* narrow() const { return narrow_.empty() ? nullptr : narrow_.data(); }
  const std::int64_t* wide() const { return narrow_.empty() ? wide_.data() : nullptr; }
  std::vector<std::int64_t> raws() const;

 private:
  std::vector<std::int64_t> wide_;
  std::vector<std::uint32_t> narrow_;
  std::size_t size_ = 0;
};

// sum_k w[k] x[col[k]] over entries [b, e) exactly (raws; `end` bounds the prefetch).
template <class W>
inline i128 dot_row(const W* w, const std::uint32_t* col, const Q32* x, std::uint64_t b, std::uint64_t e,
                    std::uint64_t end) {
  i128 acc = 0;
  for (std::uint64_t k = b; k < e; ++k) {
    gather_ahead(x, col, k, end);
    acc += static_cast<i128>(static_cast<std::int64_t>(w[k])) * x[col[k]].raw;
  }
  return acc;
}
inline i128 dot_row(const Shares& w, const std::uint32_t* col, const Q32* x, std::uint64_t b, std::uint64_t e) {
  return w.narrow() != nullptr ? dot_row(w.narrow(), col, x, b, e, w.size()) : dot_row(w.wide(), col, x, b, e, w.size());
}

// The sums of the springs and the walk over entries [b, e) of A_sym's row, each gathered
// x[col[k]] serving both (R1-FOC-090): sum_k w[k] x and sum_k v[k] x, exactly (raws; `end` bounds
// the prefetch).
template <class V>
inline void dot_row2(const std::int64_t* w, const V* v, const std::uint32_t* col, const Q32* x, std::uint64_t b,
                     std::uint64_t e, std::uint64_t end, i128& sum_w, i128& sum_v) {
  i128 acc_w = 0, acc_v = 0;
  for (std::uint64_t k = b; k < e; ++k) {
    gather_ahead(x, col, k, end);
    const std::int64_t xk = x[col[k]].raw;
    acc_w += static_cast<i128>(w[k]) * xk;
    acc_v += static_cast<i128>(static_cast<std::int64_t>(v[k])) * xk;
  }
  sum_w = acc_w;
  sum_v = acc_v;
}

// A backend's product failed (R1-FOC-092): the stage reports it as an internal error.
struct ProductError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Round-to-nearest-even of v / 2^32 to a Q32 raw; OverflowError when it does not fit.
inline std::int64_t round_q32(i128 v) {
  const i128 r = fx::detail::rne_shift(v, Q32::kFracBits);
  if (!fx::detail::fits_i64(r)) fx::detail::throw_overflow("focus: rounding");
  return static_cast<std::int64_t>(r);
}

// The sparsity patterns both domains share: in-links of directed A0 (targets' rows, sources
// ascending) and, for every particle, whether it is isolated (no A_sym neighbour).
struct FocusPattern {
  std::uint32_t n = 0;
  std::vector<std::uint64_t> in_ptr;   // n + 1
  std::vector<std::uint32_t> in_src;   // source of each in-link
  std::vector<std::uint32_t> dangling; // sources without out-links, ascending
};

// Checks the graph's array sizes and index ranges and that A_sym's pattern is symmetric where the
// operators rely on it. Input error naming the first inconsistency.
Status check_graph(const Graph& g);

// ---- Q32 (canonical) -------------------------------------------------------------------------------

class OperatorsQ32 {
 public:
  // Precomputes the prior, the apportioned transition P (R1-FOC-020) and walk matrix N
  // (R1-FOC-041) and the springs constants. The graph must pass check_graph and have a positive
  // total degree; the parameters must be valid.
  static Result<OperatorsQ32> build(const Graph& g, const TriKernelParams& params, bool parallel);

  // The operators of a region R of the graph for a local update (R1-INC-050): local index a <
  // |R| is region[a] (ascending, distinct), the indices after it the ring of R's neighbours
  // outside R, ascending; `local_to_global` receives that map. Rows of R are the graph's rows
  // with the whole graph's shares (transition rows, walk columns, the prior, a = RNE(mu / n)), so
  // with R = every particle the operators are those of build(). Ring rows are empty: a ring
  // particle is a fixed point of the walk, as an isolated particle is (R1-FOC-041), and its
  // diffusion and springs values are never used. The dangling mass adds `phi` summed exactly over
  // the dangling particles outside R, which stay frozen. `phi` has one entry per particle.
  static Result<OperatorsQ32> build_local(const Graph& g, const TriKernelParams& params, bool parallel,
                                          std::span<const std::uint32_t> region, std::span<const Q32> phi,
                                          std::vector<std::uint32_t>& local_to_global);

  std::uint32_t n() const { return pattern_.n; }
  // The rows from this index on are build_local's ring: empty rows, fixed points of the walk
  // (n() for build()). Diffusion and springs leave their entries 0 (never used); the heat kernel
  // carries them in closed form.
  std::uint32_t fixed_from() const { return std::min(fixed_from_, n()); }
  const std::vector<Q32>& prior() const { return prior_; }

  // Makes the whole-graph products on `factory`'s (R1-FOC-092): N, the heat kernel's Chebyshev
  // step and the diffusion's in-link sums. Only for build()'s operators.
  Status use_products(const ExactProductFactory& factory);
  bool on_products() const { return dev_walk_ != nullptr; }

  // D(phi) (R1-FOC-021), S(phi) (R1-FOC-030), N x (R1-FOC-041); `out` is resized to n.
  void diffusion(std::span<const Q32> phi, std::vector<Q32>& out) const;
  void springs(std::span<const Q32> phi, std::vector<Q32>& out) const;
  void walk(std::span<const Q32> x, std::vector<Q32>& out) const;
  // The heat kernel's step on the products (on_products()): out_i = RNE(2 (N t)_i - prev_i), as
  // heat_q32's row loop computes it (R1-FOC-043).
  void chebyshev_step(std::span<const Q32> t, std::span<const Q32> prev, std::vector<Q32>& out) const;
  // S(phi) and N phi, the values of springs() and walk(), in one pass over A_sym's rows, each
  // gathered phi_j serving both sums: a step's cost on graphs past the caches is its gathers
  // (R1-FOC-090). Not on the products (on_products()).
  void springs_and_walk(std::span<const Q32> phi, std::vector<Q32>& s, std::vector<Q32>& nphi) const;

  // sum_j N(i, j) x_j exactly, on the 2^-64 scale (x_i * 2^32 for an isolated particle).
  i128 walk_row(std::uint32_t i, const Q32* x) const {
    const std::uint64_t b = row_ptr_[i], e = row_ptr_[i + 1];
    if (b == e) return static_cast<i128>(x[i].raw) << Q32::kFracBits;
    return dot_row(walk_, col_, x, b, e);
  }
  bool parallel() const { return parallel_; }

 private:
  void set_constants(const TriKernelParams& params, std::uint32_t particles);
  // S(phi)_i's raw from sum_j w(i, j) phi_j (exact, raws on the 2^-64 scale), R1-FOC-030.
  std::int64_t springs_value(std::uint32_t i, i128 weighted) const {
    const i128 num = (static_cast<i128>(springs_a_) << 32) + weighted;
    // num is on the 2^-64 scale and mu + d_i on 2^-32, so num / (mu + d_i) is the raw itself.
    const i128 r = fx::detail::rne_div(num, static_cast<i128>(mu_) + degree_[i]);
    if (!fx::detail::fits_i64(r)) fx::detail::throw_overflow("focus: springs");
    return static_cast<std::int64_t>(r);
  }

  FocusPattern pattern_;
  bool parallel_ = false;
  const std::uint64_t* row_ptr_ = nullptr;  // the graph's A_sym CSR, borrowed (outlives *this)
  const std::uint32_t* col_ = nullptr;
  const std::int64_t* w_ = nullptr;
  const std::uint64_t* degree_ = nullptr;
  std::vector<Q32> prior_;
  Shares in_p_;                      // P(p, q) per in-link, raw
  Shares walk_;                      // N(i, j) at A_sym entry (i, j), raw
  std::int64_t one_minus_t_ = 0, teleport_ = 0, mu_ = 0, springs_a_ = 0;
  i128 frozen_dangling_ = 0;         // build_local: the dangling phi outside the region, exact
  std::uint32_t fixed_from_ = UINT32_MAX;  // build_local: |R|
  // build_local's rows (the pointers above point into it; shared, so copies stay valid).
  struct LocalRows {
    std::vector<std::uint64_t> row_ptr, degree;
    std::vector<std::uint32_t> col;
    std::vector<std::int64_t> w;
  };
  std::shared_ptr<const LocalRows> local_;
  // use_products(): N with identity rows, [2N | -2^32 I] over (t, prev), the in-link sums.
  std::shared_ptr<ExactProduct> dev_walk_, dev_chebyshev_, dev_in_;
};

// ---- fp64 -----------------------------------------------------------------------------------------

class OperatorsF64 {
 public:
  static Result<OperatorsF64> build(const Graph& g, const TriKernelParams& params, bool parallel);

  std::uint32_t n() const { return pattern_.n; }
  const std::vector<double>& prior() const { return prior_; }

  void diffusion(std::span<const double> phi, std::vector<double>& out) const;
  void springs(std::span<const double> phi, std::vector<double>& out) const;
  void walk(std::span<const double> x, std::vector<double>& out) const;
  // (N x)_i: the pairwise sum of row i's products (x_i for an isolated particle); `buf` is
  // scratch of at least the row's length.
  double walk_row(std::uint32_t i, const double* x, std::vector<double>& buf) const;
  bool parallel() const { return parallel_; }

 private:
  FocusPattern pattern_;
  bool parallel_ = false;
  const std::uint64_t* row_ptr_ = nullptr;
  const std::uint32_t* col_ = nullptr;
  const std::int64_t* w_ = nullptr;
  std::vector<double> degree_;       // d_i as a double (one rounding of the exact raw sum), value scale
  std::vector<double> prior_;
  std::vector<double> in_p_;
  std::vector<double> walk_;
  double one_minus_t_ = 0, teleport_ = 0, mu_ = 0, springs_a_ = 0;
};

}  // namespace r1::focus
