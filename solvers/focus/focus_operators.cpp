// The tri-kernel operators: apportioned transition and walk matrices, prior, diffusion, springs and
// N x in Q32 and fp64 (R1-FOC-011, R1-FOC-020..041, R1-FOC-080..081, R1-FOC-090).
#include "focus_operators.hpp"

#include <string>

#include "apportion.hpp"
#include "r1/fixedpoint/pairwise.hpp"

namespace r1::focus {

namespace {

constexpr std::uint64_t kOne = std::uint64_t{1} << 32;
// Q32 raw -> double value: the raws here are below 2^53 or their rounding is documented, and the
// scaling by 2^-32 is exact.
constexpr double kRawScale = 0x1p-32;

Status bad(const std::string& what) { return Status::input("focus: inconsistent layout graph: " + what); }

Status check_csr(const std::vector<std::uint64_t>& ptr, std::size_t entries, std::uint32_t n, const char* name) {
  if (ptr.size() != static_cast<std::size_t>(n) + 1) return bad(std::string(name) + " pointer array has the wrong size");
  if (ptr[0] != 0 || ptr[n] != entries) return bad(std::string(name) + " pointers do not span the entries");
  for (std::uint32_t i = 0; i < n; ++i)
    if (ptr[i + 1] < ptr[i]) return bad(std::string(name) + " pointers decrease at row " + std::to_string(i));
  return Status::ok();
}

// The in-link pattern of directed A0 and the dangling sources; slot_of_out[e] is where out-link e
// lands among the in-links (targets' rows, sources ascending because sources are visited in order).
FocusPattern build_pattern(const Graph& g, std::vector<std::uint64_t>& slot_of_out) {
  FocusPattern p;
  p.n = g.n;
  p.in_ptr.assign(static_cast<std::size_t>(g.n) + 1, 0);
  for (const std::uint32_t q : g.out_col) ++p.in_ptr[q + 1];
  for (std::uint32_t i = 0; i < g.n; ++i) p.in_ptr[i + 1] += p.in_ptr[i];
  p.in_src.resize(g.out_col.size());
  slot_of_out.resize(g.out_col.size());
  std::vector<std::uint64_t> cursor(p.in_ptr.begin(), p.in_ptr.end() - 1);
  for (std::uint32_t s = 0; s < g.n; ++s) {
    if (g.out_ptr[s] == g.out_ptr[s + 1]) p.dangling.push_back(s);
    for (std::uint64_t e = g.out_ptr[s]; e < g.out_ptr[s + 1]; ++e) {
      const std::uint64_t slot = cursor[g.out_col[e]]++;
      p.in_src[slot] = s;
      slot_of_out[e] = slot;
    }
  }
  return p;
}

// For every A_sym entry k = (j, i) of row j, the index of its mirror (i, j) in row i. Row i's
// columns ascend and rows j are visited in ascending order, so the mirrors of row i are met in
// its own column order: a cursor per row finds them. Input error when the pattern or the
// weights are not symmetric.
Result<std::vector<std::uint64_t>> mirror_slots(const Graph& g) {
  std::vector<std::uint64_t> cursor(g.row_ptr.begin(), g.row_ptr.end() - 1);
  std::vector<std::uint64_t> mirror(g.col.size());
  for (std::uint32_t j = 0; j < g.n; ++j) {
    for (std::uint64_t k = g.row_ptr[j]; k < g.row_ptr[j + 1]; ++k) {
      const std::uint32_t i = g.col[k];
      const std::uint64_t slot = cursor[i]++;
      if (slot >= g.row_ptr[i + 1] || g.col[slot] != j || g.w[slot] != g.w[k])
        return bad("A_sym is not symmetric at (" + std::to_string(j) + ", " + std::to_string(i) + ")");
      mirror[k] = slot;
    }
  }
  return mirror;
}

// The row shares apportion(2^32, weights of row) for every row of a CSR (R1-FOC-020, R1-FOC-041),
// written to out[slot[k]] (or out[k] without slots). Empty rows write nothing.
void apportion_rows(const std::vector<std::uint64_t>& ptr, const std::vector<std::int64_t>& weight,
                    const std::vector<std::uint64_t>& slot, std::vector<std::int64_t>& out) {
  ApportionScratch scratch;
  std::vector<std::uint64_t> w;
  std::vector<std::int64_t> share;
  for (std::size_t r = 0; r + 1 < ptr.size(); ++r) {
    const std::uint64_t b = ptr[r], e = ptr[r + 1];
    if (b == e) continue;
    w.assign(weight.begin() + static_cast<std::ptrdiff_t>(b), weight.begin() + static_cast<std::ptrdiff_t>(e));
    share.resize(w.size());
    apportion_into(kOne, w, share, scratch);
    for (std::uint64_t k = b; k < e; ++k) out[slot[k]] = share[k - b];
  }
}

std::uint64_t row_sum(const std::vector<std::uint64_t>& ptr, const std::vector<std::int64_t>& w, std::uint32_t i) {
  std::uint64_t s = 0;
  for (std::uint64_t k = ptr[i]; k < ptr[i + 1]; ++k) s += static_cast<std::uint64_t>(w[k]);
  return s;
}

}  // namespace

Status check_graph(const Graph& g) {
  if (g.n == 0) return Status::input("focus: the graph has no particles");
  R1_TRY(check_csr(g.row_ptr, g.col.size(), g.n, "A_sym"));
  R1_TRY(check_csr(g.out_ptr, g.out_col.size(), g.n, "A0"));
  if (g.w.size() != g.col.size()) return bad("A_sym weights and columns differ in length");
  if (g.out_w.size() != g.out_col.size()) return bad("A0 weights and columns differ in length");
  if (g.degree.size() != g.n) return bad("degree array has the wrong size");
  // Weights are Q32 in (0, 1] (R1-IN-052): the exactness bounds of R1-FOC-090 rely on it.
  for (std::size_t k = 0; k < g.col.size(); ++k)
    if (g.col[k] >= g.n || g.w[k] < 1 || g.w[k] > static_cast<std::int64_t>(kOne)) return bad("A_sym entry " + std::to_string(k) + " out of range");
  for (std::size_t k = 0; k < g.out_col.size(); ++k)
    if (g.out_col[k] >= g.n || g.out_w[k] < 1 || g.out_w[k] > static_cast<std::int64_t>(kOne)) return bad("A0 entry " + std::to_string(k) + " out of range");
  u128 total = 0;
  for (std::uint32_t i = 0; i < g.n; ++i) {
    // Rows of at most 2^31 - 1 entries keep every exact row sum inside 128 bits (R1-FOC-090).
    if (g.row_ptr[i + 1] - g.row_ptr[i] >= (std::uint64_t{1} << 31)) return bad("a row of 2^31 or more entries");
    if (row_sum(g.row_ptr, g.w, i) != g.degree[i]) return bad("degree of particle " + std::to_string(i) + " is not its row sum");
    total += g.degree[i];
  }
  if (total == 0) return Status::input("focus: the graph has no links (total degree 0)");
  return Status::ok();
}

// ---- Q32 ------------------------------------------------------------------------------------------

Result<OperatorsQ32> OperatorsQ32::build(const Graph& g, const TriKernelParams& params, bool parallel) {
  R1_TRY(check_graph(g));
  OperatorsQ32 ops;
  ops.parallel_ = parallel;
  ops.row_ptr_ = g.row_ptr.data();
  ops.col_ = g.col.data();
  ops.w_ = g.w.data();
  ops.degree_ = g.degree.data();
  {
    std::vector<std::uint64_t> slot_of_out;
    ops.pattern_ = build_pattern(g, slot_of_out);
    ops.in_p_.resize(g.out_col.size());
    apportion_rows(g.out_ptr, g.out_w, slot_of_out, ops.in_p_);
  }
  {
    R1_ASSIGN(const auto mirror, mirror_slots(g));
    // Column j of N is row j's shares placed at the mirrored entries (i, j) (R1-FOC-041).
    ops.walk_.resize(g.col.size());
    apportion_rows(g.row_ptr, g.w, mirror, ops.walk_);
  }
  {
    std::vector<std::int64_t> share(g.n);
    ApportionScratch scratch;
    apportion_into(kOne, g.degree, share, scratch);  // R1-FOC-011
    ops.prior_.resize(g.n);
    for (std::uint32_t i = 0; i < g.n; ++i) ops.prior_[i] = Q32::from_raw(share[i]);
  }
  ops.teleport_ = params.teleport.raw;
  ops.one_minus_t_ = static_cast<std::int64_t>(kOne) - params.teleport.raw;  // exact
  ops.mu_ = params.mu.raw;
  // a = RNE(mu / n), the screening source mu x0 with x0 uniform (R1-FOC-030): the one rounding.
  ops.springs_a_ = static_cast<std::int64_t>(fx::detail::rne_div(params.mu.raw, g.n));
  return ops;
}

void OperatorsQ32::diffusion(std::span<const Q32> phi, std::vector<Q32>& out) const {
  out.resize(n());
  i128 dangling_mass = 0;  // exact: at most n raws below 2^63
  for (const std::uint32_t p : pattern_.dangling) dangling_mass += phi[p].raw;
  // c = RNE((1 - t) m + t): the dangling mass and the teleport both go to the prior.
  const std::int64_t c = round_q32(static_cast<i128>(one_minus_t_) * dangling_mass + (static_cast<i128>(teleport_) << 32));
  for_rows(parallel_, n(), [&](std::uint32_t b, std::uint32_t e) {
    for (std::uint32_t q = b; q < e; ++q) {
      i128 acc = 0;
      for (std::uint64_t s = pattern_.in_ptr[q]; s < pattern_.in_ptr[q + 1]; ++s)
        acc += static_cast<i128>(in_p_[s]) * phi[pattern_.in_src[s]].raw;
      const std::int64_t y = round_q32(acc);
      out[q] = Q32::from_raw(round_q32(static_cast<i128>(one_minus_t_) * y + static_cast<i128>(c) * prior_[q].raw));
    }
  });
}

void OperatorsQ32::springs(std::span<const Q32> phi, std::vector<Q32>& out) const {
  out.resize(n());
  for_rows(parallel_, n(), [&](std::uint32_t b, std::uint32_t e) {
    for (std::uint32_t i = b; i < e; ++i) {
      i128 num = static_cast<i128>(springs_a_) << 32;
      for (std::uint64_t k = row_ptr_[i]; k < row_ptr_[i + 1]; ++k) num += static_cast<i128>(w_[k]) * phi[col_[k]].raw;
      // num is on the 2^-64 scale and mu + d_i on 2^-32, so num / (mu + d_i) is the raw itself.
      const i128 r = fx::detail::rne_div(num, static_cast<i128>(mu_) + degree_[i]);
      if (!fx::detail::fits_i64(r)) fx::detail::throw_overflow("focus: springs");
      out[i] = Q32::from_raw(static_cast<std::int64_t>(r));
    }
  });
}

void OperatorsQ32::walk(std::span<const Q32> x, std::vector<Q32>& out) const {
  out.resize(n());
  for_rows(parallel_, n(), [&](std::uint32_t b, std::uint32_t e) {
    for (std::uint32_t i = b; i < e; ++i) out[i] = Q32::from_raw(round_q32(walk_row(i, x.data())));
  });
}

// ---- fp64 -----------------------------------------------------------------------------------------

Result<OperatorsF64> OperatorsF64::build(const Graph& g, const TriKernelParams& params, bool parallel) {
  R1_TRY(check_graph(g));
  OperatorsF64 ops;
  ops.parallel_ = parallel;
  ops.row_ptr_ = g.row_ptr.data();
  ops.col_ = g.col.data();
  ops.w_ = g.w.data();
  {
    std::vector<std::uint64_t> slot_of_out;
    ops.pattern_ = build_pattern(g, slot_of_out);
    ops.in_p_.resize(g.out_col.size());
    for (std::uint32_t p = 0; p < g.n; ++p) {
      // o_p exact, converted once; P(p, q) = a(p, q) / o_p (R1-FOC-081).
      const double out_strength = static_cast<double>(row_sum(g.out_ptr, g.out_w, p));
      for (std::uint64_t e = g.out_ptr[p]; e < g.out_ptr[p + 1]; ++e)
        ops.in_p_[slot_of_out[e]] = static_cast<double>(g.out_w[e]) / out_strength;
    }
  }
  {
    R1_ASSIGN(const auto mirror, mirror_slots(g));
    ops.walk_.resize(g.col.size());
    for (std::uint32_t j = 0; j < g.n; ++j) {
      const double dj = static_cast<double>(g.degree[j]);
      for (std::uint64_t k = g.row_ptr[j]; k < g.row_ptr[j + 1]; ++k) ops.walk_[mirror[k]] = static_cast<double>(g.w[k]) / dj;
    }
  }
  u128 total = 0;
  for (const std::uint64_t d : g.degree) total += d;
  const double total_d = static_cast<double>(total);  // exact sum, one rounding (R1-FOC-080)
  ops.prior_.resize(g.n);
  ops.degree_.resize(g.n);
  for (std::uint32_t i = 0; i < g.n; ++i) {
    ops.prior_[i] = static_cast<double>(g.degree[i]) / total_d;
    ops.degree_[i] = static_cast<double>(g.degree[i]) * kRawScale;
  }
  ops.teleport_ = params.teleport.to_double();
  ops.one_minus_t_ = 1.0 - ops.teleport_;  // exact: t is a multiple of 2^-32 in [0, 1]
  ops.mu_ = params.mu.to_double();
  ops.springs_a_ = ops.mu_ / static_cast<double>(g.n);
  return ops;
}

void OperatorsF64::diffusion(std::span<const double> phi, std::vector<double>& out) const {
  out.resize(n());
  std::vector<double> dangling(pattern_.dangling.size());
  for (std::size_t k = 0; k < dangling.size(); ++k) dangling[k] = phi[pattern_.dangling[k]];
  const double c = one_minus_t_ * fx::pairwise_sum(dangling) + teleport_;
  for_rows(parallel_, n(), [&](std::uint32_t b, std::uint32_t e) {
    std::vector<double> buf;
    for (std::uint32_t q = b; q < e; ++q) {
      buf.clear();
      for (std::uint64_t s = pattern_.in_ptr[q]; s < pattern_.in_ptr[q + 1]; ++s) buf.push_back(in_p_[s] * phi[pattern_.in_src[s]]);
      out[q] = one_minus_t_ * fx::pairwise_sum(buf) + c * prior_[q];
    }
  });
}

void OperatorsF64::springs(std::span<const double> phi, std::vector<double>& out) const {
  out.resize(n());
  for_rows(parallel_, n(), [&](std::uint32_t b, std::uint32_t e) {
    std::vector<double> buf;
    for (std::uint32_t i = b; i < e; ++i) {
      buf.clear();
      for (std::uint64_t k = row_ptr_[i]; k < row_ptr_[i + 1]; ++k)
        buf.push_back(static_cast<double>(w_[k]) * kRawScale * phi[col_[k]]);
      out[i] = (springs_a_ + fx::pairwise_sum(buf)) / (mu_ + degree_[i]);
    }
  });
}

double OperatorsF64::walk_row(std::uint32_t i, const double* x, std::vector<double>& buf) const {
  const std::uint64_t b = row_ptr_[i], e = row_ptr_[i + 1];
  if (b == e) return x[i];  // isolated: a fixed point of the walk (R1-FOC-041)
  buf.clear();
  for (std::uint64_t k = b; k < e; ++k) buf.push_back(walk_[k] * x[col_[k]]);
  return fx::pairwise_sum(buf);
}

void OperatorsF64::walk(std::span<const double> x, std::vector<double>& out) const {
  out.resize(n());
  for_rows(parallel_, n(), [&](std::uint32_t b, std::uint32_t e) {
    std::vector<double> buf;
    for (std::uint32_t i = b; i < e; ++i) out[i] = walk_row(i, x.data(), buf);
  });
}

}  // namespace r1::focus
