// The tri-kernel operators: apportioned transition and walk matrices, prior, diffusion, springs and
// N x in Q32 and fp64 (R1-FOC-011, R1-FOC-020..041, R1-FOC-080..081, R1-FOC-090).
#include "focus_operators.hpp"

#include <algorithm>
#include <iterator>
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

// The prior u = apportion(2^32, d) (R1-FOC-011), raws.
std::vector<std::int64_t> prior_raws(const Graph& g) {
  std::vector<std::int64_t> share(g.n);
  ApportionScratch scratch;
  apportion_into(kOne, g.degree, share, scratch);
  return share;
}

// The prior's raws: the graph's own (R1-IN-059), else computed into `own`.
const std::vector<std::int64_t>& prior_of(const Graph& g, std::vector<std::int64_t>& own) {
  if (g.summarised()) return g.prior;
  own = prior_raws(g);
  return own;
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

Shares::Shares(std::vector<std::int64_t> raws) : size_(raws.size()) {
  const bool fits = std::all_of(raws.begin(), raws.end(), [](std::int64_t v) { return v >= 0 && v <= 0xffffffffLL; });
  if (fits && !raws.empty()) {
    narrow_.assign(raws.begin(), raws.end());
  } else {
    wide_ = std::move(raws);
  }
}

std::vector<std::int64_t> Shares::raws() const {
  if (narrow_.empty()) return wide_;
  return std::vector<std::int64_t>(narrow_.begin(), narrow_.end());
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
    std::vector<std::int64_t> in_p(g.out_col.size());
    apportion_rows(g.out_ptr, g.out_w, slot_of_out, in_p);
    ops.in_p_ = Shares(std::move(in_p));
  }
  {
    R1_ASSIGN(const auto mirror, mirror_slots(g));
    // Column j of N is row j's shares placed at the mirrored entries (i, j) (R1-FOC-041).
    std::vector<std::int64_t> walk(g.col.size());
    apportion_rows(g.row_ptr, g.w, mirror, walk);
    ops.walk_ = Shares(std::move(walk));
  }
  std::vector<std::int64_t> own;
  const std::vector<std::int64_t>& prior = prior_of(g, own);
  ops.prior_.resize(g.n);
  for (std::uint32_t i = 0; i < g.n; ++i) ops.prior_[i] = Q32::from_raw(prior[i]);
  ops.set_constants(params, g.n);
  return ops;
}

void OperatorsQ32::set_constants(const TriKernelParams& params, std::uint32_t particles) {
  teleport_ = params.teleport.raw;
  one_minus_t_ = static_cast<std::int64_t>(kOne) - params.teleport.raw;  // exact
  mu_ = params.mu.raw;
  // a = RNE(mu / n), the screening source mu x0 with x0 uniform (R1-FOC-030): the one rounding.
  springs_a_ = static_cast<std::int64_t>(fx::detail::rne_div(params.mu.raw, particles));
}

Result<OperatorsQ32> OperatorsQ32::build_local(const Graph& g, const TriKernelParams& params, bool parallel,
                                               std::span<const std::uint32_t> region, std::span<const Q32> phi,
                                               std::vector<std::uint32_t>& local_to_global) {
  // The graph is the caller's own layout graph (built and checked with it); only what this
  // function indexes is checked here, so the cost stays with the region.
  if (g.n == 0 || g.row_ptr.size() != std::size_t{g.n} + 1 || g.out_ptr.size() != std::size_t{g.n} + 1 ||
      g.degree.size() != g.n)
    return bad("array sizes");
  if (phi.size() != g.n) return Status::input("focus update: phi has " + std::to_string(phi.size()) + " entries for " + std::to_string(g.n) + " particles");
  if (region.empty()) return Status::input("focus update: empty region");
  for (std::size_t a = 0; a < region.size(); ++a)
    if (region[a] >= g.n || (a > 0 && region[a] <= region[a - 1]))
      return Status::input("focus update: region entry " + std::to_string(a) + " out of range or out of order");
  // The ring: R's neighbours outside R, ascending. Local indices by binary search in R and in the
  // ring, so nothing here is sized by the graph.
  const auto in_region = [&region](std::uint32_t j) { return std::binary_search(region.begin(), region.end(), j); };
  std::vector<std::uint32_t> ring;
  for (const std::uint32_t i : region)
    for (std::uint64_t k = g.row_ptr[i]; k < g.row_ptr[i + 1]; ++k)
      if (!in_region(g.col[k])) ring.push_back(g.col[k]);
  std::sort(ring.begin(), ring.end());
  ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
  local_to_global.assign(region.begin(), region.end());
  local_to_global.insert(local_to_global.end(), ring.begin(), ring.end());
  const auto r = static_cast<std::uint32_t>(region.size());
  const auto where = [&](std::uint32_t j) -> std::uint32_t {
    const auto at = std::lower_bound(region.begin(), region.end(), j);
    if (at != region.end() && *at == j) return static_cast<std::uint32_t>(at - region.begin());
    return r + static_cast<std::uint32_t>(std::lower_bound(ring.begin(), ring.end(), j) - ring.begin());
  };
  const auto count = static_cast<std::uint32_t>(local_to_global.size());

  OperatorsQ32 ops;
  ops.parallel_ = parallel;
  auto rows = std::make_shared<LocalRows>();
  rows->row_ptr.assign(std::size_t{count} + 1, 0);
  rows->degree.assign(count, 0);
  for (std::uint32_t a = 0; a < r; ++a) {
    const std::uint32_t i = region[a];
    rows->row_ptr[a + 1] = rows->row_ptr[a] + (g.row_ptr[i + 1] - g.row_ptr[i]);
    rows->degree[a] = g.degree[i];
  }
  for (std::uint32_t a = r; a < count; ++a) rows->row_ptr[a + 1] = rows->row_ptr[a];  // the ring: empty rows
  rows->col.resize(rows->row_ptr[count]);
  rows->w.resize(rows->row_ptr[count]);
  std::vector<std::int64_t> walk(rows->row_ptr[count]), in_p;

  // Shares of a whole row of the graph, apportioned once per local particle that needs them.
  ApportionScratch scratch;
  std::vector<std::uint64_t> wbuf;
  std::vector<std::int64_t> shares;
  const auto shares_of = [&](std::vector<std::int64_t>& offset, std::uint32_t b, const std::vector<std::uint64_t>& ptr,
                             const std::vector<std::int64_t>& weight) -> std::int64_t {
    if (offset[b] >= 0) return offset[b];
    const std::uint32_t j = local_to_global[b];
    const std::uint64_t lo = ptr[j], hi = ptr[j + 1];
    wbuf.assign(weight.begin() + static_cast<std::ptrdiff_t>(lo), weight.begin() + static_cast<std::ptrdiff_t>(hi));
    offset[b] = static_cast<std::int64_t>(shares.size());
    shares.resize(shares.size() + wbuf.size());
    apportion_into(kOne, wbuf, std::span<std::int64_t>(shares).subspan(static_cast<std::size_t>(offset[b]), wbuf.size()), scratch);
    return offset[b];
  };
  std::vector<std::int64_t> walk_offset(count, -1), out_offset(count, -1);
  ops.pattern_.n = count;
  ops.fixed_from_ = r;
  ops.pattern_.in_ptr.assign(std::size_t{count} + 1, 0);
  for (std::uint32_t a = 0; a < r; ++a) {
    const std::uint32_t q = region[a];
    std::uint64_t lk = rows->row_ptr[a];
    for (std::uint64_t k = g.row_ptr[q]; k < g.row_ptr[q + 1]; ++k, ++lk) {
      const std::uint32_t j = g.col[k];
      const std::uint32_t b = where(j);
      rows->col[lk] = b;
      rows->w[lk] = g.w[k];
      // N(q, j): q's share of row j (R1-FOC-041), row j's columns ascending.
      const std::int64_t o = shares_of(walk_offset, b, g.row_ptr, g.w);
      const auto first = g.col.begin() + static_cast<std::ptrdiff_t>(g.row_ptr[j]);
      const auto last = g.col.begin() + static_cast<std::ptrdiff_t>(g.row_ptr[j + 1]);
      const auto at = std::lower_bound(first, last, q);
      if (at == last || *at != q) return bad("A_sym is not symmetric at (" + std::to_string(j) + ", " + std::to_string(q) + ")");
      walk[lk] = shares[static_cast<std::size_t>(o + (at - first))];
      // P(j, q) when j links to q: j's share of its out-row (R1-FOC-020); the in-links of q come
      // out by ascending source as in build().
      const auto ofirst = g.out_col.begin() + static_cast<std::ptrdiff_t>(g.out_ptr[j]);
      const auto olast = g.out_col.begin() + static_cast<std::ptrdiff_t>(g.out_ptr[j + 1]);
      const auto oat = std::lower_bound(ofirst, olast, q);
      if (oat != olast && *oat == q) {
        const std::int64_t oo = shares_of(out_offset, b, g.out_ptr, g.out_w);
        ops.pattern_.in_src.push_back(b);
        in_p.push_back(shares[static_cast<std::size_t>(oo + (oat - ofirst))]);
      }
    }
    ops.pattern_.in_ptr[a + 1] = ops.pattern_.in_src.size();
    if (g.out_ptr[q] == g.out_ptr[q + 1]) ops.pattern_.dangling.push_back(a);
  }
  for (std::uint32_t a = r; a < count; ++a) ops.pattern_.in_ptr[a + 1] = ops.pattern_.in_ptr[a];
  // The frozen dangling mass: every dangling particle outside R keeps its phi (all of them, less
  // R's, exactly).
  if (g.summarised()) {
    for (const std::uint32_t p : g.dangling) ops.frozen_dangling_ += phi[p].raw;
  } else {
    for (std::uint32_t p = 0; p < g.n; ++p)
      if (g.out_ptr[p] == g.out_ptr[p + 1]) ops.frozen_dangling_ += phi[p].raw;
  }
  for (const std::uint32_t p : region)
    if (g.out_ptr[p] == g.out_ptr[p + 1]) ops.frozen_dangling_ -= phi[p].raw;
  ops.prior_.assign(count, Q32{});
  std::vector<std::int64_t> own;
  const std::vector<std::int64_t>& prior = prior_of(g, own);
  for (std::uint32_t a = 0; a < r; ++a) ops.prior_[a] = Q32::from_raw(prior[region[a]]);
  ops.set_constants(params, g.n);
  ops.walk_ = Shares(std::move(walk));
  ops.in_p_ = Shares(std::move(in_p));
  ops.row_ptr_ = rows->row_ptr.data();
  ops.col_ = rows->col.data();
  ops.w_ = rows->w.data();
  ops.degree_ = rows->degree.data();
  ops.local_ = std::move(rows);
  return ops;
}

namespace {

// The raws of Q32 vectors, one after the other, as the products take them.
std::vector<std::int64_t> raws(std::span<const Q32> x, std::span<const Q32> then = {}) {
  std::vector<std::int64_t> r;
  r.reserve(x.size() + then.size());
  for (const Q32 v : x) r.push_back(v.raw);
  for (const Q32 v : then) r.push_back(v.raw);
  return r;
}

std::vector<std::int64_t> applied(ExactProduct& product, std::span<const std::int64_t> x) {
  auto y = product.apply(x);
  if (!y.is_ok()) throw ProductError(y.status().message());
  return std::move(y).value();
}

void to_q32(const std::vector<std::int64_t>& y, std::vector<Q32>& out) {
  out.resize(y.size());
  for (std::size_t i = 0; i < y.size(); ++i) out[i] = Q32::from_raw(y[i]);
}

}  // namespace

Status OperatorsQ32::use_products(const ExactProductFactory& factory) {
  if (local_ != nullptr) return Status::internal("focus: the products serve whole-graph operators only");
  const std::uint32_t count = n();
  const std::span<const std::uint64_t> ptr(row_ptr_, std::size_t{count} + 1);
  const std::span<const std::uint32_t> col(col_, walk_.size());
  const std::vector<std::int64_t> walk = walk_.raws();
  R1_ASSIGN(std::unique_ptr<ExactProduct> w, factory(ptr, col, walk, true));
  // The Chebyshev step over (t, prev), 2n columns: row i is 2 N(i, .) on t and -2^32 on prev_i,
  // so its exact sum is 2 sum_j N(i, j) t_j - prev_i 2^32; an isolated i takes 2 t_i 2^32, its
  // walk's identity row (R1-FOC-041, R1-FOC-043).
  std::vector<std::uint64_t> cptr(std::size_t{count} + 1, 0);
  std::vector<std::uint32_t> ccol;
  std::vector<std::int64_t> cval;
  ccol.reserve(walk_.size() + count);
  cval.reserve(walk_.size() + count);
  for (std::uint32_t i = 0; i < count; ++i) {
    if (ptr[i] == ptr[i + 1]) {
      ccol.push_back(i);
      cval.push_back(static_cast<std::int64_t>(2 * kOne));
    }
    for (std::uint64_t k = ptr[i]; k < ptr[i + 1]; ++k) {
      ccol.push_back(col_[k]);
      cval.push_back(2 * walk[k]);
    }
    ccol.push_back(count + i);
    cval.push_back(-static_cast<std::int64_t>(kOne));
    cptr[i + 1] = ccol.size();
  }
  R1_ASSIGN(std::unique_ptr<ExactProduct> c, factory(cptr, ccol, cval, false));
  R1_ASSIGN(std::unique_ptr<ExactProduct> in, factory(pattern_.in_ptr, pattern_.in_src, in_p_.raws(), false));
  if (w == nullptr || c == nullptr || in == nullptr) return Status::ok();  // declined: the row loops
  dev_walk_ = std::move(w);
  dev_chebyshev_ = std::move(c);
  dev_in_ = std::move(in);
  return Status::ok();
}

void OperatorsQ32::chebyshev_step(std::span<const Q32> t, std::span<const Q32> prev, std::vector<Q32>& out) const {
  to_q32(applied(*dev_chebyshev_, raws(t, prev)), out);
}

void OperatorsQ32::diffusion(std::span<const Q32> phi, std::vector<Q32>& out) const {
  out.resize(n());
  i128 dangling_mass = frozen_dangling_;  // exact: at most n raws below 2^63
  for (const std::uint32_t p : pattern_.dangling) dangling_mass += phi[p].raw;
  // c = RNE((1 - t) m + t): the dangling mass and the teleport both go to the prior.
  const std::int64_t c = round_q32(static_cast<i128>(one_minus_t_) * dangling_mass + (static_cast<i128>(teleport_) << 32));
  if (dev_in_ != nullptr) {
    // y_q on the products, the rest of the row as below.
    const std::vector<std::int64_t> y = applied(*dev_in_, raws(phi));
    for_rows(parallel_, fixed_from(), [&](std::uint32_t b, std::uint32_t e) {
      for (std::uint32_t q = b; q < e; ++q)
        out[q] = Q32::from_raw(round_q32(static_cast<i128>(one_minus_t_) * y[q] + static_cast<i128>(c) * prior_[q].raw));
    });
    return;
  }
  for_rows(parallel_, fixed_from(), [&](std::uint32_t b, std::uint32_t e) {
    for (std::uint32_t q = b; q < e; ++q) {
      const std::int64_t y =
          round_q32(dot_row(in_p_, pattern_.in_src.data(), phi.data(), pattern_.in_ptr[q], pattern_.in_ptr[q + 1]));
      out[q] = Q32::from_raw(round_q32(static_cast<i128>(one_minus_t_) * y + static_cast<i128>(c) * prior_[q].raw));
    }
  });
}

void OperatorsQ32::springs(std::span<const Q32> phi, std::vector<Q32>& out) const {
  out.resize(n());
  for_rows(parallel_, fixed_from(), [&](std::uint32_t b, std::uint32_t e) {
    for (std::uint32_t i = b; i < e; ++i)
      out[i] = Q32::from_raw(springs_value(i, dot_row(w_, col_, phi.data(), row_ptr_[i], row_ptr_[i + 1], walk_.size())));
  });
}

void OperatorsQ32::springs_and_walk(std::span<const Q32> phi, std::vector<Q32>& s, std::vector<Q32>& nphi) const {
  if (dev_walk_ != nullptr) throw std::logic_error("focus: springs_and_walk on the products");
  s.resize(n());
  nphi.resize(n());
  // The springs on fixed_from()'s rows (the others are never used), N phi on all.
  const std::uint32_t springs_rows = fixed_from();
  const auto rows = [&](const auto* shares) {
    for_rows(parallel_, n(), [&](std::uint32_t b, std::uint32_t e) {
      for (std::uint32_t i = b; i < e; ++i) {
        const std::uint64_t rb = row_ptr_[i], re = row_ptr_[i + 1];
        i128 ws = 0, ns = 0;
        if (rb != re) dot_row2(w_, shares, col_, phi.data(), rb, re, walk_.size(), ws, ns);
        // An empty row is a fixed point of the walk (R1-FOC-041).
        nphi[i] = rb == re ? phi[i] : Q32::from_raw(round_q32(ns));
        if (i < springs_rows) s[i] = Q32::from_raw(springs_value(i, ws));
      }
    });
  };
  if (walk_.narrow() != nullptr) rows(walk_.narrow());
  else rows(walk_.wide());
}

void OperatorsQ32::walk(std::span<const Q32> x, std::vector<Q32>& out) const {
  if (dev_walk_ != nullptr) return to_q32(applied(*dev_walk_, raws(x)), out);
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

namespace r1 {

void summarise_for_focus(Graph& g) {
  g.prior.clear();
  g.dangling.clear();
  g.max_degree = 0;
  if (g.n == 0) return;
  for (std::uint32_t p = 0; p < g.n; ++p) {
    g.max_degree = std::max(g.max_degree, g.degree[p]);
    if (g.out_ptr[p] == g.out_ptr[p + 1]) g.dangling.push_back(p);
  }
  g.prior = focus::prior_raws(g);
}

std::vector<std::uint32_t> within_hops(const Graph& g, std::span<const std::uint32_t> seeds, std::uint32_t h) {
  // Breadth first over sorted sets while the ball is small (no array of n, so the cost is the
  // ball's rows): each hop's neighbours, less those already in, merged in. Once a hop reaches
  // n / 16 entries, a mark per particle for the rest (the cost of a pass over n is then no more).
  std::vector<std::uint32_t> all, frontier;
  for (const std::uint32_t s : seeds)
    if (s < g.n) frontier.push_back(s);
  std::sort(frontier.begin(), frontier.end());
  frontier.erase(std::unique(frontier.begin(), frontier.end()), frontier.end());
  all = frontier;
  std::vector<std::uint32_t> reached, next, merged;
  std::uint32_t hop = 0;
  for (; hop < h && !frontier.empty(); ++hop) {
    reached.clear();
    for (const std::uint32_t i : frontier) {
      reached.insert(reached.end(), g.col.begin() + static_cast<std::ptrdiff_t>(g.row_ptr[i]),
                     g.col.begin() + static_cast<std::ptrdiff_t>(g.row_ptr[i + 1]));
      if (reached.size() > g.n / 16) break;
    }
    if (reached.size() > g.n / 16) break;
    std::sort(reached.begin(), reached.end());
    reached.erase(std::unique(reached.begin(), reached.end()), reached.end());
    next.clear();
    std::set_difference(reached.begin(), reached.end(), all.begin(), all.end(), std::back_inserter(next));
    merged.clear();
    std::merge(all.begin(), all.end(), next.begin(), next.end(), std::back_inserter(merged));
    all.swap(merged);
    frontier.swap(next);
  }
  if (hop == h || frontier.empty()) return all;
  // The rest of the hops, from `frontier` (hop `hop` not yet taken), with a mark per particle.
  std::vector<char> in(g.n, 0);
  for (const std::uint32_t i : all) in[i] = 1;
  for (; hop < h && !frontier.empty(); ++hop) {
    next.clear();
    for (const std::uint32_t i : frontier)
      for (std::uint64_t k = g.row_ptr[i]; k < g.row_ptr[i + 1]; ++k)
        if (!in[g.col[k]]) {
          in[g.col[k]] = 1;
          next.push_back(g.col[k]);
        }
    frontier.swap(next);
  }
  all.clear();
  for (std::uint32_t i = 0; i < g.n; ++i)
    if (in[i]) all.push_back(i);
  return all;
}

}  // namespace r1
