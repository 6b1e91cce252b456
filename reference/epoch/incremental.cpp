// Incremental epochs (R-1.0 3.3; spec/incremental.md R1-INC-001..050): the edit batch, N_h, the
// local update of u_2..u_6 on N_h with a Davis-Kahan certificate, and the fall-back to a full
// solve.
#include "r1/reference/incremental.hpp"

#include "r1/fixedpoint/prefetch.hpp"

#include <boost/multiprecision/cpp_int.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>

#include "r1/reference/epoch.hpp"
#include "r1/reference/frame.hpp"
#include "r1/reference/intern_index.hpp"
#include "r1/solvers/exact_round.hpp"
#include "r1/solvers/focus.hpp"
#include "r1/solvers/panel.hpp"
#include "r1/solvers/spectral.hpp"

namespace r1 {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// The earlier epoch's A_sym and A2 as rows (both directions of every layout edge), and every
// particle's weighted degree. With a set of wanted rows, only those rows hold entries.
struct Rows {
  std::vector<std::uint64_t> ptr;
  std::vector<std::uint32_t> col;
  std::vector<std::int64_t> w, a2;
  std::vector<std::uint64_t> degree;
};

// `wanted` (one flag per PREV particle) limits the rows that get entries; null: every row.
Rows prev_rows(const Epoch& prev, const std::vector<char>* wanted = nullptr) {
  const std::size_t n = prev.ids.size();
  Rows r;
  r.ptr.assign(n + 1, 0);
  r.degree.assign(n, 0);
  const auto want = [&](std::uint32_t p) { return wanted == nullptr || (*wanted)[p] != 0; };
  for (const LayoutEdge& e : prev.edges) {
    if (want(e.p)) ++r.ptr[e.p + 1];
    if (want(e.q)) ++r.ptr[e.q + 1];
    r.degree[e.p] += static_cast<std::uint64_t>(e.w_raw);
    r.degree[e.q] += static_cast<std::uint64_t>(e.w_raw);
  }
  for (std::size_t i = 0; i < n; ++i) r.ptr[i + 1] += r.ptr[i];
  r.col.resize(r.ptr[n]);
  r.w.resize(r.ptr[n]);
  r.a2.resize(r.ptr[n]);
  std::vector<std::uint64_t> fill(r.ptr.begin(), r.ptr.end() - 1);
  // Edges are sorted by (p, q): row p receives q ascending, row q receives p ascending, so every
  // row ends up sorted by column.
  for (const LayoutEdge& e : prev.edges) {
    if (want(e.p)) {
      const std::uint64_t a = fill[e.p]++;
      r.col[a] = e.q;
      r.w[a] = e.w_raw;
      r.a2[a] = e.a2_raw;
    }
    if (want(e.q)) {
      const std::uint64_t b = fill[e.q]++;
      r.col[b] = e.p;
      r.w[b] = e.w_raw;
      r.a2[b] = -e.a2_raw;
    }
  }
  return r;
}

double m_entry(std::int64_t w, std::uint64_t di, std::uint64_t dj) {
  return static_cast<double>(w) / std::sqrt(static_cast<double>(di) * static_cast<double>(dj));
}

struct Entry {
  std::uint64_t key;  // next column, or n + earlier column for a particle that left
  std::int64_t w, a2;
  double m;
};

}  // namespace

std::uint32_t hops_for(double eps, double mu) {
  // The least h >= 1 with mu (1 + mu)^(h + 1) >= 1 / eps: the tail of the springs Green's function
  // beyond h hops, sum_(k > h) (1 + mu)^-(k + 1) ||M||^k <= (1 + mu)^-(h + 1) / mu, is within eps.
  // Plain products, no libm: the same h on every machine.
  std::uint32_t h = 1;
  double x = mu * (1 + mu) * (1 + mu);
  while (x * eps < 1 && h < 64) {
    x = x * (1 + mu);
    ++h;
  }
  return h;
}

namespace {
// The splitmix64 finaliser (Steele, Lea and Flood 2014): a bijection of 64-bit words whose output
// bits each depend on every input bit.
std::uint64_t mix64(std::uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}
}  // namespace

std::vector<std::uint64_t> out_row_digests(const Graph& g, std::span<const ParticleId> ids) {
  std::vector<std::uint64_t> d(g.n, 0);
  // The ids are read in column order, cache misses on large graphs: the one 16 entries on is
  // fetched early (speed only). Rows are independent: blocks of them on the TBB workers.
  constexpr std::uint64_t kAhead = 16;
  const std::uint64_t last = g.out_ptr[g.n] == 0 ? 0 : g.out_ptr[g.n] - 1;
  spectral::for_row_blocks(g.n, true, [&](std::size_t lo, std::size_t hi) {
    for (std::size_t p = lo; p < hi; ++p)
      for (std::uint64_t k = g.out_ptr[p]; k < g.out_ptr[p + 1]; ++k) {
        fx::gather_hint(ids.data() + g.out_col[std::min(k + kAhead, last)]);
        std::uint64_t t = 0;
        for (int b = 7; b >= 0; --b) t = (t << 8) | ids[g.out_col[k]][static_cast<std::size_t>(b)];
        d[p] += mix64(t ^ mix64(static_cast<std::uint64_t>(g.out_w[k])));
      }
  });
  return d;
}

std::vector<std::uint32_t> neighbourhood(const Graph& g, const std::vector<std::uint32_t>& seeds, std::uint32_t h) {
  return within_hops(g, seeds, h);
}

namespace {

// The edit batch (R1-INC-010..012), with PREV's rows in `pr` as far as the update reads them: every
// degree, and the entries of the rows of N_1 (all rows when a particle left).
Result<EditBatch> batch_of(const Epoch& prev, const Snapshot& next, const Graph& g, const std::string& prev_name, Rows& pr) {
  const std::size_t np = prev.ids.size(), n = next.particles.size();
  if (prev.out_rows.size() != np)
    return Status::input(prev_name + ": " + std::to_string(prev.out_rows.size()) + " out-row digests for " + std::to_string(np) +
                         " particles");
  const IdIndex index = IdIndex::over(next.particles);
  std::vector<std::int64_t> next_of(np);
  for (std::size_t p = 0; p < np; ++p) {
    index.prefetch_slot(prev.ids[std::min(p + 16, np - 1)]);  // a cache miss on large graphs (speed only)
    next_of[p] = index.find(prev.ids[p], next.particles);
  }
  // R1-INC-002: the anchor set is immutable along a chain.
  for (std::size_t p = 0; p < anchor_count(np); ++p)
    if (next_of[p] < 0)
      return Status::input(prev_name + ": not an epoch of this snapshot's chain: its anchor particle " + std::to_string(p) +
                           " (" + hemera::to_hex(prev.ids[p]).substr(0, 16) + "...) is not in " + next.source);
  EditBatch b;
  b.prev_of.assign(n, -1);
  for (std::size_t p = 0; p < np; ++p) {
    if (next_of[p] >= 0) {
      b.prev_of[static_cast<std::size_t>(next_of[p])] = static_cast<std::int64_t>(p);
    } else {
      ++b.dropped;
      b.left.push_back(static_cast<std::uint32_t>(p));
    }
  }

  // When no particle left and every one kept its number (particles may be added after them), a
  // row differs exactly when a layout edge at it does, and the edges are compared as two sorted
  // lists of pairs (p < q): NEXT's upper triangle row by row against PREV's edges.bin. PREV's rows
  // are then needed only for N_1 (below), not for every particle (416 MB at 10^7 links).
  bool same_numbers = b.dropped == 0;
  for (std::size_t p = 0; same_numbers && p < np; ++p) same_numbers = next_of[p] == static_cast<std::int64_t>(p);
  const std::vector<std::uint64_t> out_rows = out_row_digests(g, next.particles);
  const std::size_t blocks = (n + spectral::kBlock - 1) / spectral::kBlock;
  std::vector<std::vector<std::uint32_t>> touched_in(blocks);
  if (same_numbers) {
    // Where each PREV row's edges begin (PREV's edges are sorted by (p, q)).
    std::vector<std::uint64_t> first(np + 1, 0);
    for (const LayoutEdge& e : prev.edges) ++first[e.p + 1];
    for (std::size_t p = 0; p < np; ++p) first[p + 1] += first[p];
    // Each block lists its rows whose digest differs or that are new, and the far end of every
    // pair that differs; the lists join in block order, then sorted and made unique.
    spectral::for_row_blocks(n, true, [&](std::size_t lo, std::size_t hi) {
      std::vector<std::uint32_t>& t = touched_in[lo / spectral::kBlock];
      for (std::size_t i = lo; i < hi; ++i) {
        const bool old = i < np;
        bool row_differs = !old || out_rows[i] != prev.out_rows[i];
        std::uint64_t k = std::upper_bound(g.col.begin() + static_cast<std::ptrdiff_t>(g.row_ptr[i]),
                                           g.col.begin() + static_cast<std::ptrdiff_t>(g.row_ptr[i + 1]), static_cast<std::uint32_t>(i)) -
                          g.col.begin();
        std::uint64_t e = old ? first[i] : 0;
        const std::uint64_t k_end = g.row_ptr[i + 1], e_end = old ? first[i + 1] : 0;
        while (k < k_end || e < e_end) {
          std::uint32_t far;
          if (e == e_end || (k < k_end && g.col[k] < prev.edges[e].q)) {
            far = g.col[k++];
          } else if (k == k_end || prev.edges[e].q < g.col[k]) {
            far = prev.edges[e++].q;
          } else {
            const bool same = g.w[k] == prev.edges[e].w_raw && g.a2[k] == prev.edges[e].a2_raw;
            far = g.col[k];
            ++k;
            ++e;
            if (same) continue;
          }
          row_differs = true;
          t.push_back(far);
        }
        if (row_differs) t.push_back(static_cast<std::uint32_t>(i));
      }
    });
  }

  // Row i's entries keyed by next column: the next graph's, and the earlier one's mapped; the M
  // entries only where the norm bound needs them (`with_m`; 0 otherwise).
  auto next_row = [&](std::uint32_t i, std::vector<Entry>& out, bool with_m) {
    out.clear();
    for (std::uint64_t k = g.row_ptr[i]; k < g.row_ptr[i + 1]; ++k)
      out.push_back({g.col[k], g.w[k], g.a2[k], with_m ? m_entry(g.w[k], g.degree[i], g.degree[g.col[k]]) : 0.0});
  };
  auto prev_row = [&](std::size_t p, std::vector<Entry>& out, bool with_m) {
    out.clear();
    for (std::uint64_t k = pr.ptr[p]; k < pr.ptr[p + 1]; ++k) {
      const std::uint32_t c = pr.col[k];
      const std::uint64_t key = next_of[c] >= 0 ? static_cast<std::uint64_t>(next_of[c]) : n + c;
      out.push_back({key, pr.w[k], pr.a2[k], with_m ? m_entry(pr.w[k], pr.degree[p], pr.degree[c]) : 0.0});
    }
    if (!std::is_sorted(out.begin(), out.end(), [](const Entry& x, const Entry& y) { return x.key < y.key; }))
      std::sort(out.begin(), out.end(), [](const Entry& x, const Entry& y) { return x.key < y.key; });
  };

  if (!same_numbers) {
    // The general case: every row of NEXT against PREV's row of the same particle, columns
    // mapped. The directed rows (A0, which the focus reads) compare by digest: a link that only
    // changes direction leaves A_sym and A2 as they were. Rows compare independently: each block
    // of rows lists its touched rows, and the lists join in block order.
    pr = prev_rows(prev);
    spectral::for_row_blocks(n, true, [&](std::size_t lo, std::size_t hi) {
      std::vector<Entry> a, c;
      std::vector<std::uint32_t>& t = touched_in[lo / spectral::kBlock];
      for (std::size_t i = lo; i < hi; ++i) {
        if (b.prev_of[i] < 0) {
          t.push_back(static_cast<std::uint32_t>(i));
          continue;
        }
        next_row(static_cast<std::uint32_t>(i), a, false);
        prev_row(static_cast<std::size_t>(b.prev_of[i]), c, false);
        bool same = a.size() == c.size() && out_rows[i] == prev.out_rows[static_cast<std::size_t>(b.prev_of[i])];
        for (std::size_t k = 0; same && k < a.size(); ++k) same = a[k].key == c[k].key && a[k].w == c[k].w && a[k].a2 == c[k].a2;
        if (!same) t.push_back(static_cast<std::uint32_t>(i));
      }
    });
  }
  // The blocks' lists in block order; the pair merge lists far ends out of order and twice.
  for (const auto& t : touched_in) b.touched.insert(b.touched.end(), t.begin(), t.end());
  std::sort(b.touched.begin(), b.touched.end());
  b.touched.erase(std::unique(b.touched.begin(), b.touched.end()), b.touched.end());
  for (std::size_t i = 0; i < n; ++i) b.added += b.prev_of[i] < 0 ? 1 : 0;
  std::vector<Entry> a, c;

  // ||Delta M||_F over every changed entry (R1-INC-012): each lies in a row of N_1 = touched and
  // their neighbours, or in a row of a particle that left. Entries in fp64 (relative error
  // ~1e-16, covered by the margin); the rounding of each Q32 entry to its raw (2^-33 on either
  // side) adds 2^-32 per changed entry.
  std::vector<std::uint32_t> n1 = neighbourhood(g, b.touched, 1);
  if (same_numbers) {
    std::vector<char> wanted(np, 0);
    for (const std::uint32_t i : n1)
      if (i < np) wanted[i] = 1;
    pr = prev_rows(prev, &wanted);
  }
  double sum = 0, max_row = 0;  // ||Delta M||_F^2 and ||Delta M||_inf (max absolute row sum)
  std::uint64_t changed = 0;
  for (std::uint32_t i : n1) {
    next_row(i, a, true);
    if (b.prev_of[i] >= 0) {
      prev_row(static_cast<std::size_t>(b.prev_of[i]), c, true);
    } else {
      c.clear();
    }
    std::size_t x = 0, y = 0;
    double row = 0;
    while (x < a.size() || y < c.size()) {
      double d;
      if (y == c.size() || (x < a.size() && a[x].key < c[y].key)) {
        d = a[x++].m;
      } else if (x == a.size() || c[y].key < a[x].key) {
        d = c[y++].m;
      } else {
        d = a[x++].m - c[y++].m;
      }
      if (d != 0) {
        sum = sum + d * d;
        row = row + std::fabs(d);
        ++changed;
      }
    }
    max_row = std::max(max_row, row);
  }
  for (std::size_t p = 0; p < np; ++p) {
    if (next_of[p] >= 0) continue;
    prev_row(p, c, true);
    double row = 0;
    for (const Entry& e : c) {
      sum = sum + e.m * e.m;
      row = row + e.m;
      ++changed;
    }
    max_row = std::max(max_row, row);
  }
  // ||Delta M||_2 <= min(||.||_F, ||.||_inf) (symmetric: ||.||_2 <= sqrt(||.||_1 ||.||_inf) = ||.||_inf).
  b.delta_norm = std::min(std::sqrt(sum), max_row) * (1 + 1e-9) + 0x1p-32 * std::sqrt(static_cast<double>(changed)) + 1e-15;
  b.same_scale = true;
  return b;
}

}  // namespace

Result<EditBatch> edit_batch(const Epoch& prev, const Snapshot& next, const Graph& g, const std::string& prev_name) {
  Rows pr;
  return batch_of(prev, next, g, prev_name, pr);
}

namespace {

// The local least-squares correction of one vector (R1-INC-031), in fp64 over the rows of
// N_(h+1) (compact indices), the correction supported on N_h: M on those rows (ascending)
// restricted to the columns of N_h.
struct Local {
  std::vector<char> inner;         // per compact row: in N_h
  std::vector<std::uint64_t> ptr;  // per compact row, its entries in N_h's columns, ascending
  std::vector<std::uint32_t> col;  // compact column
  std::vector<std::int64_t> m;     // M raw
  std::size_t size() const { return inner.size(); }
};

// y = (L~ - theta) x on the compact rows, x zero outside N_h.
void local_apply(const Local& loc, const std::vector<double>& x, double theta, std::vector<double>& y) {
  y.assign(loc.size(), 0.0);
  for (std::size_t a = 0; a < loc.size(); ++a) {
    double s = 0;
    for (std::uint64_t k = loc.ptr[a]; k < loc.ptr[a + 1]; ++k)
      s = s + static_cast<double>(loc.m[k]) * 0x1p-32 * x[loc.col[k]];
    y[a] = (1 - theta) * x[a] - s;
  }
}

double dot(const std::vector<double>& x, const std::vector<double>& y) {
  double s = 0;
  for (std::size_t i = 0; i < x.size(); ++i) s = s + x[i] * y[i];
  return s;
}

// Orthogonalises v against the columns q (two classical passes) and returns the coefficients.
std::vector<double> orthogonalise(std::vector<double>& v, const std::vector<std::vector<double>>& q) {
  std::vector<double> coef(q.size(), 0.0);
  for (int pass = 0; pass < 2; ++pass)
    for (std::size_t j = 0; j < q.size(); ++j) {
      const double c = dot(q[j], v);
      coef[j] = coef[j] + c;
      for (std::size_t i = 0; i < v.size(); ++i) v[i] = v[i] - c * q[j][i];
    }
  return coef;
}

// z on the compact rows (zero outside N_h) minimising ||r + (L~ - theta) z|| over the Krylov
// space of the residual restricted to N_h.
// The basis lives on N_h: its vectors are kept on N_h's rows only (`in`, ascending), where the
// rows outside add exact zeros to every dot product, and spread over the rows for the product.
std::vector<double> local_correction(const Local& loc, const std::vector<double>& r, double theta, std::uint32_t krylov) {
  const std::size_t rn = loc.size();
  std::vector<double> z(rn, 0.0);
  std::vector<std::size_t> in;
  for (std::size_t a = 0; a < rn; ++a)
    if (loc.inner[a]) in.push_back(a);
  std::vector<double> v(in.size()), spread(rn, 0.0);
  for (std::size_t b = 0; b < in.size(); ++b) v[b] = r[in[b]];
  std::vector<std::vector<double>> basis, qc;  // B (on N_h) and the orthonormalised C = (L - theta) B
  std::vector<std::vector<double>> rc;         // R of C = Q R, column by column
  const double v0 = std::sqrt(dot(v, v));
  if (!(v0 > 0)) return z;
  std::vector<double> y;
  for (std::uint32_t j = 0; j < krylov; ++j) {
    orthogonalise(v, basis);
    const double nv = std::sqrt(dot(v, v));
    if (!(nv > 1e-12 * v0)) break;
    for (double& x : v) x = x / nv;
    for (std::size_t b = 0; b < in.size(); ++b) spread[in[b]] = v[b];
    local_apply(loc, spread, theta, y);
    std::vector<double> cj = y;
    std::vector<double> col = orthogonalise(cj, qc);
    const double nc = std::sqrt(dot(cj, cj));
    if (!(nc > 1e-12 * std::sqrt(dot(y, y)))) break;
    for (double& x : cj) x = x / nc;
    col.push_back(nc);
    basis.push_back(v);
    qc.push_back(std::move(cj));
    rc.push_back(std::move(col));
    // The next Krylov direction: (L - theta) v restricted to N_h.
    for (std::size_t b = 0; b < in.size(); ++b) v[b] = y[in[b]];
  }
  const std::size_t k = basis.size();
  if (k == 0) return z;
  // min ||r + Q R d||: R d = -Q^T r, back substitution.
  std::vector<double> d(k, 0.0);
  std::vector<double> rhs(k);
  for (std::size_t j = 0; j < k; ++j) rhs[j] = -dot(qc[j], r);
  for (std::size_t j = k; j-- > 0;) {
    double s = rhs[j];
    for (std::size_t l = j + 1; l < k; ++l) s = s - rc[l][j] * d[l];
    d[j] = s / rc[j][j];
  }
  for (std::size_t j = 0; j < k; ++j)
    for (std::size_t b = 0; b < in.size(); ++b) z[in[b]] = z[in[b]] + d[j] * basis[j][b];
  return z;
}

using Sums = std::array<std::array<fx::ExactSum, 3>, 5>;

boost::multiprecision::cpp_int big(const fx::ExactSum& x) {
  const auto l = x.limbs();
  boost::multiprecision::cpp_int v = l[2];
  v = (v << 64) | l[1];
  v = (v << 64) | l[0];
  if ((l[2] >> 63) != 0) v -= boost::multiprecision::cpp_int(1) << 192;
  return v;
}

// A non-negative integer times 2^-k as a double: its top 63 bits, rounded once.
double big_to_double(boost::multiprecision::cpp_int v, int k) {
  if (v <= 0) return 0;
  const auto top = static_cast<int>(boost::multiprecision::msb(v));
  if (top > 62) {
    v >>= top - 62;
    k -= top - 62;
  }
  return std::ldexp(static_cast<double>(static_cast<std::uint64_t>(v)), -k);
}

// Rayleigh quotients and residual norms of the five vectors from their exact sums (R1-INC-032,
// R1-INC-038): theta = S_xy / S_xx, and ||y - theta x||^2 = S_yy - 2 theta S_xy + theta^2 S_xx
// evaluated exactly at the double theta; rho for the unit vector, the rounding of y included.
struct Residuals {
  std::array<double, 5> theta{}, rho{}, norm{};
};
Residuals residuals_of(const Sums& sums, std::size_t n, int shift) {
  using boost::multiprecision::cpp_int;
  Residuals out;
  for (std::size_t c = 0; c < 5; ++c) {
    const double nn = spectral::to_double_scaled(sums[c][0], 64), ny = spectral::to_double_scaled(sums[c][1], 64);
    if (!(nn > 0)) {
      out.theta[c] = 0;
      out.rho[c] = kInf;
      continue;
    }
    const double theta = ny / nn;
    // theta = t 2^-q exactly, t an integer of at most 53 bits.
    int ex = 0;
    const double mant = std::frexp(theta, &ex);
    const auto t = static_cast<std::int64_t>(std::ldexp(mant, 53));
    const int q = t == 0 ? 0 : 53 - ex;
    const cpp_int tb(t);
    cpp_int rr = big(sums[c][2]);
    rr <<= 2 * q;
    cpp_int cross = big(sums[c][1]);
    cross *= tb;
    cross <<= q + 1;
    rr -= cross;
    cpp_int square = big(sums[c][0]);
    square *= tb;
    square *= tb;
    rr += square;
    const double len = std::sqrt(nn);  // value units
    // Each applied entry is within half a raw of exact: sqrt(n) / 2 raws in all; the conversions
    // above are within a relative 2^-52.
    const double apply_err = 0.5 * std::sqrt(static_cast<double>(n)) * 0x1p-32;
    out.theta[c] = theta;
    out.rho[c] = (std::sqrt(big_to_double(rr, 2 * q)) * 0x1p-32 * (1 + 1e-12) + apply_err) / len;
    out.norm[c] = len / std::ldexp(1.0, shift);
  }
  return out;
}

// The rows of N_1 outside N_h (h = 0 only): a row i whose own entries did not change (i not
// touched: its degree and weights are PREV's) differs from PREV's operator row only in the columns
// of touched particles j, whose degree moved. Its carried numerator moves by
// -(M_next_ij - M_prev_ij) x_j there (R1-INC-038), exact: no square root for the rest of the row,
// which on a scale-free graph is a hub's thousands of entries. `touched_rows` holds the rows of N_h;
// at h >= 1 every neighbour of a touched particle is in N_h and nothing moves here.
Status move_by_changed_entries(const Graph& g, const Rows& pr, const EditBatch& batch, const RowOperatorQ32& touched_rows,
                               const std::array<std::vector<Q32>, 5>& x, int shift, std::vector<i128>& image) {
  const std::vector<std::uint32_t>& nh = touched_rows.rows;
  const std::int64_t scale = std::int64_t{1} << shift;
  for (std::size_t r = 0; r < nh.size(); ++r) {
    const std::uint32_t j = nh[r];
    if (!std::binary_search(batch.touched.begin(), batch.touched.end(), j)) continue;  // its degree is PREV's
    for (std::uint64_t k = touched_rows.ptr[r]; k < touched_rows.ptr[r + 1]; ++k) {
      const std::uint32_t i = touched_rows.col[k];
      if (std::binary_search(nh.begin(), nh.end(), i)) continue;
      // i is not touched, so (i, j) is an edge of PREV with the same weight, and j was in PREV.
      if (batch.prev_of[j] < 0) return Status::internal("incremental update: an untouched particle links to an added one");
      const std::int64_t w = g.w[g.row_ptr[j] + (k - touched_rows.ptr[r])];
      const std::int64_t before = spectral::m_entry(w, g.degree[i], pr.degree[static_cast<std::size_t>(batch.prev_of[j])]).raw;
      const std::int64_t dm = touched_rows.m[k].raw - before;
      if (dm == 0) continue;
      for (std::size_t c = 0; c < 5; ++c) image[std::size_t{i} * 5 + c] -= static_cast<i128>(dm) * (x[c][j].raw * scale);
    }
  }
  return Status::ok();
}

// The earlier frame applied to vectors (R1-INC-033): genesis scale, then the recorded similarity,
// written into `pos` (n entries) at the particles `at`, or at every particle when `at` is null.
Status frame_positions(const Frame& f, const std::array<std::vector<Q32>, 5>& u, const std::vector<std::uint32_t>* at,
                       const std::string& prev_name, std::vector<std::array<Q32, 3>>& pos) {
  const auto scale = Q32::checked_from_double(f.scale);
  if (!scale) return Status::input(prev_name + ": the scale is outside the Q32 range");
  std::optional<Result<Similarity>> sim;
  if (!f.alignment.genesis) {
    sim.emplace(similarity_of(f.alignment));
    if (!sim->is_ok()) return sim->status().with_prefix(prev_name + ": ");
  }
  const auto place = [&](std::size_t p) -> Status {
    for (std::size_t c = 0; c < 3; ++c) {
      const auto x = fx::checked_mul(u[c][p], *scale);
      if (!x) return Status::internal("incremental frame: a scaled coordinate does not fit Q32");
      pos[p][c] = *x;
    }
    if (!sim) return Status::ok();
    const auto y = apply_similarity(**sim, pos[p]);
    if (!y) return Status::internal("incremental frame: a position leaves the Q32 range");
    pos[p] = *y;
    return Status::ok();
  };
  if (at != nullptr) {
    for (const std::uint32_t p : *at) R1_TRY(place(p));
  } else {
    for (std::size_t p = 0; p < pos.size(); ++p) R1_TRY(place(p));
  }
  return Status::ok();
}

bool same_parameters(const Epoch& prev, const EpochOptions& o) {
  const TriKernelParams &a = prev.trikernel, &b = o.trikernel;
  const bool tk = a.lambda_d == b.lambda_d && a.lambda_s == b.lambda_s && a.lambda_h == b.lambda_h &&
                  a.teleport == b.teleport && a.mu == b.mu && a.tau == b.tau && a.eps == b.eps &&
                  a.max_steps == b.max_steps && a.chebyshev_degree == b.chebyshev_degree;
  const SpectralParams &c = prev.spectral_params, &d = o.spectral;
  return tk && c.rho == d.rho && c.basis == d.basis && c.tolerance == d.tolerance &&
         c.filter_degree == d.filter_degree;
}

std::string fmt(double x) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g", x);
  return b;
}

}  // namespace

double frame_scale(const Frame& f) { return f.scale * (f.alignment.genesis ? 1.0 : f.alignment.scale); }

double vector_drift(const Epoch& a, const Epoch& b) {
  const std::size_t n = a.ids.size();
  if (b.ids.size() != n) return kInf;
  double d2 = 0;
  for (std::size_t c = 0; c < 3; ++c) {
    if (a.spectrum.u[c].size() != n || b.spectrum.u[c].size() != n) return kInf;
    double dot = 0;
    for (std::size_t p = 0; p < n; ++p) dot = dot + a.spectrum.u[c][p].to_double() * b.spectrum.u[c][p].to_double();
    const double sign = dot < 0 ? -1.0 : 1.0;
    for (std::size_t p = 0; p < n; ++p) {
      const double d = a.spectrum.u[c][p].to_double() - sign * b.spectrum.u[c][p].to_double();
      d2 = d2 + d * d;
    }
  }
  return frame_scale(a.frame) * std::sqrt(d2);
}

double full_solve_bound(const Epoch& f, double s) {
  const auto& ev = f.spectrum.eigenvalues;
  const auto& rs = f.spectrum.residuals;
  double sum = 0;
  for (std::size_t c = 0; c < 3; ++c) {
    const double gap = std::min(ev[c + 1] - ev[c] - rs[c], ev[c + 2] - rs[c + 2] - ev[c + 1]);
    if (!(gap > 0)) return kInf;
    const double b = std::sqrt(2.0) * std::min(1.0, rs[c + 1] / gap);
    sum = sum + b * b;
  }
  return s * std::sqrt(sum);
}

Result<Epoch> run_epoch_from(Epoch prev, const Anchor& prev_anchor, const std::string& prev_name,
                             const Snapshot& next, const Graph& g, const EpochOptions& options,
                             const UpdateOptions& uo, EpochStages& stages, const ProgressFn& progress) {
  const auto batch_start = std::chrono::steady_clock::now();
  Rows pr;
  R1_ASSIGN(EditBatch batch, batch_of(prev, next, g, prev_name, pr));
  // PREV's layout edges live on as the rows the update reads (`pr`); the list itself (24 bytes an
  // edge, 240 MB at 10^7 links) is not read again (R1-EPO-005).
  std::vector<LayoutEdge>().swap(prev.edges);
  const std::size_t n = g.n;

  UpdateInfo info;
  info.touched = batch.touched.size();
  info.added = batch.added;
  info.dropped = batch.dropped;
  info.delta_norm = batch.delta_norm;
  info.eps_x = uo.eps * static_cast<double>(kSceneRadius);
  info.hops = uo.hops ? *uo.hops : hops_for(uo.eps, prev.trikernel.mu.to_double());
  const UpdateInfo* before = prev.update ? &*prev.update : nullptr;
  const bool prev_full = before == nullptr || !before->incremental;
  info.epochs_since_full = (prev_full ? 0 : before->epochs_since_full) + 1;
  info.delta_norm_since_full = (prev_full ? 0 : before->delta_norm_since_full) + batch.delta_norm;
  info.resized_since_full = (prev_full ? 0 : before->resized_since_full) + batch.added + batch.dropped;
  info.full_eigenvalues = prev_full ? prev.spectrum.eigenvalues : before->full_eigenvalues;
  info.full_residuals = prev_full ? prev.spectrum.residuals : before->full_residuals;
  info.vector_bound.fill(kInf);
  info.certificate = kInf;

  // The full solve, aligned to the earlier epoch's anchor (R1-INC-034).
  auto full = [&](std::string reason) -> Result<Epoch> {
    pr = Rows{};  // not read by the full solve, whose basis is the epoch's peak (R1-EPO-005)
    EpochOptions o = options;
    o.anchor = prev_anchor;
    o.anchor_name = prev_name + "/anchor.bin";
    RecordChunks chunks;
    if (!o.snapshot_digest) {  // PREV's leaves for the unchanged chunks (R1-EPO-017)
      const auto t = std::chrono::steady_clock::now();
      o.snapshot_digest = snapshot_digest(next, chunks, &prev.record_chunks);
      o.snapshot_digest_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
    }
    R1_ASSIGN(Epoch e, run_epoch(next, g, o, stages, progress));
    if (!chunks.leaves.empty()) e.record_chunks = std::move(chunks);
    UpdateInfo u = info;
    u.incremental = false;
    u.reason = std::move(reason);
    u.epochs_since_full = 0;
    u.delta_norm_since_full = 0;
    u.resized_since_full = 0;
    u.full_eigenvalues = e.spectrum.eigenvalues;
    u.full_residuals = e.spectrum.residuals;
    e.update = u;
    return e;
  };

  // Reasons for a full solve that need no work on N_h (R1-INC-030).
  if (uo.force_full) return full("forced (--full)");
  if (options.domain != NumericDomain::kQ32 || prev.domain != NumericDomain::kQ32)
    return full("the fp64 domain has no incremental update");
  if (!same_parameters(prev, options)) return full("parameters differ from the earlier epoch's");
  if (g.component_size.size() != 1 || prev.spectrum.rho != 0 || prev.components != 1)
    return full("the graph is not connected: rho > 0 couples every particle");
  if (prev.spectrum.found < 5 || n < 8) return full("fewer than 5 eigenvectors");
  if (info.epochs_since_full >= uo.full_every) return full("cadence: " + std::to_string(uo.full_every) + " epochs since the last full solve");
  if (info.delta_norm_since_full > uo.full_norm)
    return full("||L~ - L~_full|| bound " + fmt(info.delta_norm_since_full) + " exceeds " + fmt(uo.full_norm));

  const std::vector<std::uint32_t> nh = neighbourhood(g, batch.touched, info.hops);
  info.region = nh.size();
  if (2 * nh.size() > n)
    return full("N_h (" + std::to_string(info.hops) + " hops) holds " + std::to_string(nh.size()) + " of " + std::to_string(n) +
                " particles");

  // ---- the local update of u_2..u_6 (R1-INC-031) ----
  auto clock = std::chrono::steady_clock::now();
  const double batch_s = std::chrono::duration<double>(clock - batch_start).count();
  // The certificate's bookkeeping (the carried sums, the rows of N_(h+1) after the update; a pass
  // over every particle only without carried sums) is timed apart from the local work:
  // `certificate` against `spectral`; gathering PREV's arrays by particle is `carry`.
  const auto since = [](std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  };
  double global_s = 0, carry_s = 0;
  const int shift = spectral::scale_exponent(static_cast<std::uint32_t>(n)) / 2;  // vectors scaled by 2^shift: the operator's rounding shrinks by as much
  const std::int64_t scale = std::int64_t{1} << shift;
  // PREV's vectors are unit vectors, entries within 2 (read_epoch refuses a spectral.q32 beyond).
  const std::size_t np = prev.ids.size();
  const bool sums_carried = prev.spectrum.sums_shift == shift && prev.spectrum.image.size() == np * 5;
  // Per next particle: the stored raws (an added particle 0), the start of the update and, outside
  // N_h, the result; and the image numerators of L~_next applied to them.
  // With the same particles in the same order, PREV's arrays are taken over (`prev` is this
  // function's own); else gathered by particle.
  auto t_carry = std::chrono::steady_clock::now();
  bool same_particles = batch.added == 0 && batch.dropped == 0 && np == n;
  for (std::size_t i = 0; same_particles && i < n; ++i) same_particles = batch.prev_of[i] == static_cast<std::int64_t>(i);
  std::array<std::vector<Q32>, 5> out;
  for (std::size_t c = 0; c < 5; ++c) {
    if (same_particles) {
      out[c] = std::move(prev.spectrum.u[c]);
      continue;
    }
    out[c].resize(n);
    for (std::size_t i = 0; i < n; ++i)
      out[c][i] = batch.prev_of[i] >= 0 ? prev.spectrum.u[c][static_cast<std::size_t>(batch.prev_of[i])] : Q32{};
  }
  std::vector<i128> image;
  if (sums_carried && same_particles) {
    image = std::move(prev.spectrum.image);
  } else {
    image.assign(n * 5, 0);
    if (sums_carried)
      for (std::size_t i = 0; i < n; ++i)
        if (batch.prev_of[i] >= 0)
          std::copy_n(&prev.spectrum.image[static_cast<std::size_t>(batch.prev_of[i]) * 5], 5, &image[i * 5]);
  }
  carry_s += since(t_carry);

  // The rows (R1-INC-038): N_(h+1), the only rows of L~ u the batch and the update change; of them
  // F = N_h (every touched particle, whose own row changed, among them) are computed in full, and
  // the rest only through their entries in touched columns (h = 0) and in N_h.
  const std::vector<std::uint32_t> rows = neighbourhood(g, batch.touched, info.hops + 1);
  info.rows = rows.size();
  // F = N_h: at h >= 1 it holds every particle whose own entries move; at h = 0 (N_h = the touched
  // particles) the other rows of N_1 change only in their entries of touched columns.
  const std::vector<std::uint32_t>& full_rows = nh;
  const RowOperatorQ32 next_op = RowOperatorQ32::build(g.row_ptr, g.col, g.w, g.degree, full_rows, options.parallel);

  // The exact sums without the rows of N_(h+1) (base): the earlier epoch's with the particles
  // that left and its own terms of those rows taken out; without carried sums at this scale, one
  // exact pass over every particle. Then F's rows under the next operator, and the sums of PREV's
  // vectors under L~_next: base plus the terms of N_(h+1) (the rows outside F are PREV's).
  auto t_global = std::chrono::steady_clock::now();
  Sums base{};
  if (sums_carried) {
    base = prev.spectrum.sums;
    for (const std::uint32_t p : batch.left) spectral::add_row_sums(prev.spectrum.u, shift, p, &prev.spectrum.image[std::size_t{p} * 5], -1, base);
    for (const std::uint32_t i : rows) spectral::add_row_sums(out, shift, i, &image[std::size_t{i} * 5], -1, base);
    next_op.numerators(out, shift, image, options.parallel);
    R1_TRY(move_by_changed_entries(g, pr, batch, next_op, out, shift, image));
  } else {
    R1_ASSIGN(const SpectralOperator<Q32> op, spectral_operator_q32(g, options.spectral));
    spectral::image_and_sums(op, out, shift, image, base, options.parallel);
    for (const std::uint32_t i : rows) spectral::add_row_sums(out, shift, i, &image[std::size_t{i} * 5], -1, base);
  }
  pr = Rows{};  // PREV's rows are not read after this (416 MB at 10^7 links)
  Sums sums = base;
  for (const std::uint32_t i : rows) spectral::add_row_sums(out, shift, i, &image[std::size_t{i} * 5], 1, sums);
  const Residuals before_update = residuals_of(sums, n, shift);
  global_s += since(t_global);

  // M restricted to the columns of N_h, by compact row (ascending columns, as the rows are stored):
  // the transpose of N_h's rows, M being exactly symmetric.
  // A particle's compact row in N_(h+1) (ascending), found by binary search: no array of n.
  const auto where = [&rows](std::uint32_t i) {
    return static_cast<std::size_t>(std::lower_bound(rows.begin(), rows.end(), i) - rows.begin());
  };
  Local loc;
  loc.inner.assign(rows.size(), 0);
  for (const std::uint32_t i : nh) loc.inner[where(i)] = 1;
  {
    std::vector<std::uint32_t> row_of(full_rows.size());  // next_op's row of each particle of N_h, by N_h's order
    std::size_t r = 0;
    for (std::size_t j = 0; j < nh.size(); ++j) {
      while (full_rows[r] != nh[j]) ++r;
      row_of[j] = static_cast<std::uint32_t>(r);
    }
    loc.ptr.assign(rows.size() + 1, 0);
    for (std::size_t j = 0; j < nh.size(); ++j)
      for (std::uint64_t k = next_op.ptr[row_of[j]]; k < next_op.ptr[row_of[j] + 1]; ++k) ++loc.ptr[where(next_op.col[k]) + 1];
    for (std::size_t a = 0; a < rows.size(); ++a) loc.ptr[a + 1] += loc.ptr[a];
    loc.col.resize(loc.ptr.back());
    loc.m.resize(loc.ptr.back());
    std::vector<std::uint64_t> fill(loc.ptr.begin(), loc.ptr.end() - 1);
    for (std::size_t j = 0; j < nh.size(); ++j)
      for (std::uint64_t k = next_op.ptr[row_of[j]]; k < next_op.ptr[row_of[j] + 1]; ++k) {
        const std::uint64_t o = fill[where(next_op.col[k])]++;
        loc.col[o] = static_cast<std::uint32_t>(where(nh[j]));
        loc.m[o] = next_op.m[k].raw;
      }
  }
  // The raws of N_h before the update, for the rows outside F.
  std::vector<std::int64_t> start_raw(nh.size() * 5);
  for (std::size_t j = 0; j < nh.size(); ++j)
    for (std::size_t c = 0; c < 5; ++c) start_raw[j * 5 + c] = out[c][nh[j]].raw;

  for (std::size_t c = 0; c < 5 && !rows.empty(); ++c) {
    // The residual on the compact rows, value units of the scaled vector, from the exact product.
    const double theta = before_update.theta[c];
    std::vector<double> x(rows.size()), r(rows.size());
    for (std::size_t a = 0; a < rows.size(); ++a) {
      const double u = static_cast<double>(out[c][rows[a]].raw * scale);
      x[a] = u * 0x1p-32;
      r[a] = (static_cast<double>(spectral::image_raw(image[std::size_t{rows[a]} * 5 + c])) - theta * u) * 0x1p-32;
    }
    const std::vector<double> z = local_correction(loc, r, theta, uo.krylov);
    // Stored vector: the earlier raw plus the correction, rounded once to the unit-norm scale.
    const double to_raw = std::ldexp(1.0, 32 - shift);
    for (std::size_t a = 0; a < rows.size(); ++a) {
      if (!loc.inner[a]) continue;
      const double v = std::nearbyint((x[a] + z[a]) * to_raw);
      if (!(std::fabs(v) < 0x1p62)) return Status::internal("incremental update: a vector entry leaves the Q32 range");
      out[c][rows[a]] = Q32::from_raw(static_cast<std::int64_t>(v));
    }
  }

  // ---- the certificate (R1-INC-032) ----
  t_global = std::chrono::steady_clock::now();
  // F's rows in full; every other row of N_(h+1) moves by its entries in N_h times the change.
  next_op.numerators(out, shift, image, options.parallel);
  {
    std::vector<std::int64_t> delta(rows.size() * 5, 0);
    for (std::size_t j = 0; j < nh.size(); ++j)
      for (std::size_t c = 0; c < 5; ++c)
        delta[where(nh[j]) * 5 + c] = (out[c][nh[j]].raw - start_raw[j * 5 + c]) * scale;
    std::vector<char> in_full(rows.size(), 0);
    for (const std::uint32_t i : full_rows) in_full[where(i)] = 1;
    for (std::size_t a = 0; a < rows.size(); ++a) {
      if (in_full[a]) continue;
      for (std::uint64_t k = loc.ptr[a]; k < loc.ptr[a + 1]; ++k)
        for (std::size_t c = 0; c < 5; ++c)
          image[std::size_t{rows[a]} * 5 + c] -= static_cast<i128>(loc.m[k]) * delta[std::size_t{loc.col[k]} * 5 + c];
    }
  }
  sums = base;
  for (const std::uint32_t i : rows) spectral::add_row_sums(out, shift, i, &image[std::size_t{i} * 5], 1, sums);
  const Residuals after = residuals_of(sums, n, shift);
  global_s += since(t_global);
  // lambda_i(L~_next) lies within rho_i^full + sum ||Delta L~|| of the full solve's value (Weyl).
  std::array<double, 6> lo{}, hi{};
  // 2^-32 more covers the rounding of the products behind the full solve's residuals.
  for (std::size_t i = 0; i < 6; ++i) {
    const double margin = info.full_residuals[i] + info.delta_norm_since_full + 0x1p-32;
    lo[i] = info.full_eigenvalues[i] - margin;
    hi[i] = info.full_eigenvalues[i] + margin;
  }
  // Particles added or dropped pad the operators with eigenvalue 1 (R1-INC-032): harmless while
  // every wanted eigenvalue stays below it.
  const bool padded_ok = info.resized_since_full == 0 || hi[5] < 1;
  for (std::size_t c = 0; c < 4 && padded_ok; ++c) {
    const double theta = after.theta[c], rho = after.rho[c];
    const double gap = std::min(theta - hi[c], lo[c + 2] - theta);
    if (!(gap > 0) || !std::isfinite(rho)) continue;
    info.vector_bound[c] = std::sqrt(2.0) * std::min(1.0, rho / gap) + std::fabs(after.norm[c] - 1);
  }
  const double s_total = frame_scale(prev.frame);
  const double b2 = info.vector_bound[0] * info.vector_bound[0] + info.vector_bound[1] * info.vector_bound[1] +
                    info.vector_bound[2] * info.vector_bound[2];
  info.certificate = std::isfinite(b2) ? s_total * std::sqrt(b2) + 1e-6 : kInf;
  info.certified = info.certificate <= info.eps_x;
  if (!info.certified && uo.keep_local)
    info.reason = std::isfinite(info.certificate) ? "uncertified (--keep-local): certificate " + fmt(info.certificate) + " exceeds eps_X " + fmt(info.eps_x)
                                                  : std::string("uncertified (--keep-local): no certificate");
  if (!info.certified && !uo.keep_local)
    return full(std::isfinite(info.certificate)
                    ? "certificate " + fmt(info.certificate) + " exceeds eps_X " + fmt(info.eps_x)
                    : std::string(padded_ok ? "no certificate: an updated eigenvalue is not separated from its neighbours"
                                            : "no certificate: particles changed and an eigenvalue bound reaches 1"));

  // ---- the incremental epoch ----
  const double spectral_s = since(clock) - global_s - carry_s;
  // The digest: after the decision, which a full solve repeats; PREV's chunk leaves where the
  // record stream's chunks are PREV's (R1-EPO-017).
  Epoch e = epoch_header(next, g, options, &prev.record_chunks);
  epoch_particles(e, next, g);
  Spectrum<Q32>& s = e.spectrum;
  s.n = static_cast<std::uint32_t>(n);
  s.rho = 0;
  s.found = prev.spectrum.found;
  s.eigenvalues[0] = info.full_eigenvalues[0];
  s.residuals[0] = info.full_residuals[0] + info.delta_norm_since_full;
  for (std::size_t c = 0; c < 5; ++c) {
    s.eigenvalues[c + 1] = after.theta[c];
    s.residuals[c + 1] = after.rho[c];
  }
  s.u = std::move(out);
  s.sums = sums;
  s.sums_shift = shift;
  s.image = std::move(image);
  s.matvecs = 10;  // two applications of the rows for the residuals (one block product each)
  s.passes = 2;
  e.timings.push_back({"batch", batch_s});  // the edit batch and N_h (R1-INC-010..021)
  const std::size_t carry_at = e.timings.size();
  e.timings.push_back({"carry", carry_s});  // PREV's vectors, image and focus gathered by particle: O(|P|) copies
  e.timings.push_back({std::string(stage_name(Stage::kSpectral)), spectral_s});  // the local update on N_h
  e.timings.push_back({"certificate", global_s});  // the carried sums (or, without them, a product over all particles)
  clock = std::chrono::steady_clock::now();
  const double lambda2 = s.eigenvalues[1];
  {
    // phi on N_h from PREV's, every other particle frozen (R1-INC-050); the full iteration when
    // the frozen particles leave the region less than one raw each.
    // Gathered by particle like the vectors, and timed with them (`carry`).
    const auto t_start = std::chrono::steady_clock::now();
    Focus<Q32> start;
    // The carried sum of phi ln phi (R1-INC-054) without the particles that left.
    if (prev.focus.plogp) {
      start.plogp = *prev.focus.plogp;
      for (const std::uint32_t p : batch.left) start.plogp->add_term(-phi_log_phi(prev.focus.phi[p]));
    }
    // The carried heat term (R1-INC-052), an added particle 0; without it (PREV's lambda_h was 0,
    // which the parameter check makes NEXT's too) none is needed.
    if (same_particles) {
      start.phi = std::move(prev.focus.phi);
      start.heat = std::move(prev.focus.heat);
      start.cyberank = std::move(prev.focus.cyberank);  // with on_simplex: read_epoch found both
      start.on_simplex = prev.focus.on_simplex;
    } else {
      start.phi.resize(n);
      for (std::size_t i = 0; i < n; ++i)
        if (batch.prev_of[i] >= 0) start.phi[i] = prev.focus.phi[static_cast<std::size_t>(batch.prev_of[i])];
      if (!prev.focus.heat.empty()) {
        start.heat.resize(n);
        for (std::size_t i = 0; i < n; ++i)
          if (batch.prev_of[i] >= 0) start.heat[i] = prev.focus.heat[static_cast<std::size_t>(batch.prev_of[i])];
      }
    }
    e.timings[carry_at].seconds += since(t_start);
    clock = std::chrono::steady_clock::now();
    auto local = stages.focus_update(g, options, lambda2, std::move(start), nh, progress);
    if (local.is_ok()) {
      e.focus = std::move(*local);
      info.focus_local = true;
    } else if (local.status().kind() == ErrorKind::kInput) {
      R1_ASSIGN(e.focus, stages.focus(g, options, lambda2, progress));
    } else {
      return local.status();
    }
  }
  const auto t_focus = std::chrono::steady_clock::now();
  e.timings.push_back({std::string(stage_name(Stage::kFocus)), std::chrono::duration<double>(t_focus - clock).count()});
  // The earlier frame, kept (R1-INC-033): outside N_h every position keeps its bits.
  e.frame.scale = prev.frame.scale;
  e.frame.alignment = prev.frame.alignment;
  // With the same particles, PREV's positions are taken over and N_h's recomputed: elsewhere the
  // vectors and the frame are PREV's, so are the bits.
  if (same_particles && prev.frame.position.size() == n) {
    e.frame.position = std::move(prev.frame.position);
    R1_TRY(frame_positions(prev.frame, s.u, &nh, prev_name, e.frame.position));
  } else {
    e.frame.position.assign(n, {});
    R1_TRY(frame_positions(prev.frame, s.u, nullptr, prev_name, e.frame.position));
  }
  e.timings.push_back({std::string(stage_name(Stage::kFrame)),
                       std::chrono::duration<double>(std::chrono::steady_clock::now() - t_focus).count()});
  // Roles from the earlier epoch's betweenness, by particle (R1-INC-037): an added particle has
  // no shortest paths through it yet as far as the carried values know.
  EpochOptions tail_options = options;
  if (!prev.encoding.betweenness.empty() && options.encoding.role_shapes) {
    std::shared_ptr<std::vector<double>> carried;
    if (same_particles) {
      carried = std::make_shared<std::vector<double>>(std::move(prev.encoding.betweenness));
    } else {
      carried = std::make_shared<std::vector<double>>(n, 0.0);
      for (std::size_t i = 0; i < n; ++i)
        if (batch.prev_of[i] >= 0) (*carried)[i] = prev.encoding.betweenness[static_cast<std::size_t>(batch.prev_of[i])];
    }
    tail_options.encoding.carried_betweenness = std::move(carried);
    info.betweenness_carried = true;
  }
  // The chain's hierarchy scale (R1-INC-035): PREV's r_0, so the levels are built once instead
  // of searching r_0 again over positions that moved only on N_h.
  if (!tail_options.hierarchy.radius0_raw) {
    tail_options.hierarchy.radius0_raw = prev.hierarchy.radius_raw[0];
    info.hierarchy_radius_kept = true;
  }
  // Likewise the encoding's r_0 (R1-ENC-007): PREV's, where both measure it from the spacing,
  // instead of a nearest-neighbour query per particle over positions that moved only on N_h.
  if (tail_options.encoding.radius_scale == "spacing" && !tail_options.encoding.r0_squared_raw &&
      prev.encoding.radius_scale == "spacing") {
    tail_options.encoding.r0_squared_raw = prev.encoding.r0_squared_raw;
    info.radius_scale_kept = true;
  }
  R1_TRY(epoch_tail(e, next, g, tail_options, stages, progress));
  info.incremental = true;
  e.update = info;
  return e;
}

}  // namespace r1
