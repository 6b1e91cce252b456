// The layout graph: exact integer weights, A_sym CSR, A2, directed A0, degrees, components
// (decision 3, R1-IN-050..058).
#include "r1/reference/graph_build.hpp"

#include "r1/fixedpoint/prefetch.hpp"
#include "r1/solvers/focus.hpp"
#include "r1/solvers/panel.hpp"

#include <boost/multiprecision/cpp_int.hpp>

#include <algorithm>
#include <atomic>
#include <numeric>

namespace r1 {

namespace {

// A directed entry before normalisation: exact weight and exact signed A2 contribution.
struct Entry {
  std::uint32_t col;
  u128 w;
  i128 a2;
};

// Exact weights (single or summed) must stay below 2^127 so that A2, bounded by them, fits i128.
constexpr u128 kWeightLimit = u128{1} << 127;

// Adds an entry's exact weight and A2 to a pair's running sums; an input error when the summed
// weight would reach kWeightLimit.
Status add_to_pair(u128& w, i128& a2, u128 add_w, i128 add_a2, const std::string& source) {
  if (add_w >= kWeightLimit - w) return Status::input(source + ": summed link weight of one particle pair reaches 2^127");
  w += add_w;
  a2 += add_a2;  // |a2| <= w < 2^127: no overflow
  return Status::ok();
}

// Sorts each row by column and merges equal columns (parallel links, both directions), exactly.
Status compress_rows(std::vector<std::uint64_t>& ptr, std::vector<Entry>& e, const std::string& source) {
  const std::size_t n = ptr.size() - 1;
  std::vector<std::uint64_t> merged(n + 1, 0);
  std::uint64_t out = 0;  // compaction in place: out never passes the entry being read
  for (std::size_t i = 0; i < n; ++i) {
    auto first = e.begin() + static_cast<std::ptrdiff_t>(ptr[i]), last = e.begin() + static_cast<std::ptrdiff_t>(ptr[i + 1]);
    std::sort(first, last, [](const Entry& a, const Entry& b) { return a.col < b.col; });
    const std::uint64_t row_start = out;
    for (std::uint64_t k = ptr[i]; k < ptr[i + 1]; ++k) {
      if (out > row_start && e[out - 1].col == e[k].col) {
        R1_TRY(add_to_pair(e[out - 1].w, e[out - 1].a2, e[k].w, e[k].a2, source));
      } else {
        e[out++] = e[k];
      }
    }
    merged[i + 1] = out;
  }
  ptr = std::move(merged);
  e.resize(out);
  return Status::ok();
}

// The first error of the row blocks (spectral::for_row_blocks); every error of a pass has the same
// text, so which block found it first does not matter.
class FirstError {
 public:
  void set(const Status& st) {
    if (st.is_ok() || failed_.exchange(true)) return;
    status_ = st;
  }
  Status get() const { return failed_.load() ? status_ : Status::ok(); }

 private:
  std::atomic<bool> failed_{false};
  Status status_ = Status::ok();
};

}  // namespace

std::int64_t scale_to_q32(u128 value, u128 scale) {
  // Fast path when value * 2^32 fits 128 bits; cpp_int otherwise (chain-scale amounts).
  if (value < (u128{1} << 96)) {
    const u128 num = value << 32;
    u128 q = num / scale;
    const u128 r = num - q * scale;
    // Ties to even; r < scale, so 2r cannot overflow when scale < 2^127, and a tie needs scale even.
    const bool up = r > scale - r || (r == scale - r && (q & 1) != 0);
    return static_cast<std::int64_t>(q + (up ? 1 : 0));
  }
  using boost::multiprecision::cpp_int;
  auto big = [](u128 x) { return (cpp_int(static_cast<std::uint64_t>(x >> 64)) << 64) | cpp_int(static_cast<std::uint64_t>(x)); };
  const cpp_int num = big(value) << 32, den = big(scale);
  cpp_int q = num / den;
  const cpp_int r = num - q * den;
  if (r * 2 > den || (r * 2 == den && (q & 1) != 0)) ++q;
  return static_cast<std::int64_t>(q);
}

namespace {

// `release`: the snapshot's link records, released once the directed rows hold them (nothing
// after reads them), or null to keep them.
Result<Graph> build(const Snapshot& s, const ProgressFn& progress, bool parallel, std::vector<Link>* release) {
  Graph g;
  g.n = static_cast<std::uint32_t>(s.particles.size());
  g.links = s.links.size();
  const std::size_t n = g.n;

  // Exact per-link weight: amount x token per-mille weight (karma and price default to 1).
  auto link_weight = [&](const Link& l, u128& w) {
    const std::uint64_t tw = s.config.tokens.at(l.token).weight_permille;
    if (tw != 0 && l.amount > u128_max / tw) return false;
    w = l.amount * tw;
    return true;
  };

  // Directed A0 rows by counting sort on the source.
  std::vector<std::uint64_t> out_ptr(n + 1, 0);
  for (const Link& l : s.links) {
    if (l.from == l.to) {
      ++g.self_loops_dropped;
    } else {
      ++out_ptr[l.from + 1];
    }
  }
  if (g.self_loops_dropped == s.links.size())
    return Status::input(s.source + ": no links" +
                         (s.links.empty() ? std::string() : " besides " + std::to_string(g.self_loops_dropped) + " self-loops"));
  std::partial_sum(out_ptr.begin(), out_ptr.end(), out_ptr.begin());
  std::vector<Entry> out(out_ptr[n]);
  {
    std::vector<std::uint64_t> fill(out_ptr.begin(), out_ptr.end() - 1);
    for (std::size_t k = 0; k < s.links.size(); ++k) {
      const Link& l = s.links[k];
      if (l.from == l.to) continue;
      u128 w;
      if (!link_weight(l, w) || w >= kWeightLimit)
        return Status::input(s.source + ": link " + std::to_string(k) + ": amount x token weight reaches 2^127");
      // A2 contribution: w x |2m - 1| x sign(v) with |2m - 1| = 1 until market data exists.
      out[fill[l.from]++] = Entry{l.to, w, l.valence > 0 ? static_cast<i128>(w) : l.valence < 0 ? -static_cast<i128>(w) : 0};
      if ((k & 0xFFFFF) == 0) report(progress, "building graph", k, s.links.size());
    }
  }
  if (release != nullptr) std::vector<Link>().swap(*release);  // s.links is not read below
  R1_TRY(compress_rows(out_ptr, out, s.source));

  // A_sym: every directed (i, j, w, a2) appears as (i, j, w, a2) and (j, i, w, -a2). Its entries
  // are first references to A0's (16 bytes each, not 48: the load's peak at 10^7 links), sorted by
  // column within each row; the entries of one column (a link each way) are then summed exactly
  // from A0's weights, once to find the scale and once to write the Q32 values (R1-IN-054).
  struct SymRef {
    std::uint32_t col;
    std::uint32_t mirrored;  // 1: the entry (j, i) of A0's (i, j), with -a2
    std::uint64_t out;       // index of the A0 entry
  };
  std::vector<std::uint64_t> sym_ptr(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i)
    for (std::uint64_t k = out_ptr[i]; k < out_ptr[i + 1]; ++k) {
      ++sym_ptr[i + 1];
      ++sym_ptr[out[k].col + 1];
    }
  std::partial_sum(sym_ptr.begin(), sym_ptr.end(), sym_ptr.begin());
  std::vector<SymRef> sym(sym_ptr[n]);
  {
    std::vector<std::uint64_t> fill(sym_ptr.begin(), sym_ptr.end() - 1);
    for (std::size_t i = 0; i < n; ++i)
      for (std::uint64_t k = out_ptr[i]; k < out_ptr[i + 1]; ++k) {
        sym[fill[i]++] = SymRef{out[k].col, 0, k};
        sym[fill[out[k].col]++] = SymRef{static_cast<std::uint32_t>(i), 1, k};
      }
  }
  spectral::for_row_blocks(n, parallel, [&](std::size_t lo, std::size_t hi) {
    for (std::size_t i = lo; i < hi; ++i)
      std::sort(sym.begin() + static_cast<std::ptrdiff_t>(sym_ptr[i]), sym.begin() + static_cast<std::ptrdiff_t>(sym_ptr[i + 1]),
                [](const SymRef& a, const SymRef& b) { return a.col < b.col; });
  });
  // Calls emit(col, w, a2) for the merged entries of row i in column order: exact sums. The A0
  // entries a row refers to lie anywhere in `out` (a mirrored entry sits in its source's row), so
  // the entry kAhead references on is fetched ahead (fx::gather_hint): speed only.
  constexpr std::uint64_t kAhead = 64;
  const std::uint64_t sym_size = sym.size();
  const auto merged_row = [&](std::size_t i, const auto& emit) -> Status {
    for (std::uint64_t k = sym_ptr[i]; k < sym_ptr[i + 1];) {
      const std::uint32_t col = sym[k].col;
      u128 w = 0;
      i128 a2 = 0;
      for (; k < sym_ptr[i + 1] && sym[k].col == col; ++k) {
        if (k + kAhead < sym_size) {
          const Entry* ahead = &out[sym[k + kAhead].out];
          fx::gather_hint(ahead);
          fx::gather_hint(reinterpret_cast<const char*>(ahead) + sizeof(Entry) - 1);
        }
        const Entry& e = out[sym[k].out];
        R1_TRY(add_to_pair(w, a2, e.w, sym[k].mirrored != 0 ? -e.a2 : e.a2, s.source));
      }
      emit(col, w, a2);
    }
    return Status::ok();
  };
  // Pass 1: each row's merged count and the largest weight, per block of rows (the maximum is
  // the same in any grouping).
  std::vector<std::uint64_t> row_ptr(n + 1, 0);
  std::vector<u128> block_max((n + spectral::kBlock - 1) / spectral::kBlock, 0);
  {
    FirstError error;
    spectral::for_row_blocks(n, parallel, [&](std::size_t lo, std::size_t hi) {
      u128 m = 0;
      for (std::size_t i = lo; i < hi; ++i) {
        const Status st = merged_row(i, [&](std::uint32_t, u128 w, i128) {
          ++row_ptr[i + 1];
          m = std::max(m, w);
        });
        if (!st.is_ok()) {
          error.set(st);
          return;
        }
      }
      block_max[lo / spectral::kBlock] = std::max(block_max[lo / spectral::kBlock], m);
    });
    R1_TRY(error.get());
  }
  std::partial_sum(row_ptr.begin(), row_ptr.end(), row_ptr.begin());
  g.weight_scale = 0;
  for (const u128 m : block_max) g.weight_scale = std::max(g.weight_scale, m);
  if (g.weight_scale == 0) return Status::input(s.source + ": every link has weight zero");

  // Normalise to Q32 (R1-IN-052): weights round to at least one unit so links never vanish.
  auto to_q32 = [&](u128 w) { return w == 0 ? std::int64_t{0} : std::max<std::int64_t>(1, scale_to_q32(w, g.weight_scale)); };
  auto to_q32_signed = [&](i128 a) {
    const std::int64_t m = a == 0 ? 0 : scale_to_q32(static_cast<u128>(a < 0 ? -a : a), g.weight_scale);
    return a < 0 ? -m : m;
  };
  g.col.resize(row_ptr[n]);
  g.w.resize(row_ptr[n]);
  g.a2.resize(row_ptr[n]);
  // Pass 2: the entries, each row into its own range (its sums were checked by pass 1).
  spectral::for_row_blocks(n, parallel, [&](std::size_t lo, std::size_t hi) {
    for (std::size_t i = lo; i < hi; ++i) {
      std::uint64_t k = row_ptr[i];
      (void)merged_row(i, [&](std::uint32_t col, u128 w, i128 a2) {
        g.col[k] = col;
        g.w[k] = to_q32(w);
        g.a2[k] = to_q32_signed(a2);
        ++k;
      });
    }
  });
  g.row_ptr = std::move(row_ptr);
  std::vector<SymRef>().swap(sym);
  g.out_ptr = std::move(out_ptr);
  g.out_col.resize(out.size());
  g.out_w.resize(out.size());
  spectral::for_row_blocks(n, parallel, [&](std::size_t lo, std::size_t hi) {
    for (std::uint64_t k = g.out_ptr[lo]; k < g.out_ptr[hi]; ++k) {
      g.out_col[k] = out[k].col;
      g.out_w[k] = to_q32(out[k].w);
    }
  });

  g.degree.assign(n, 0);
  spectral::for_row_blocks(n, parallel, [&](std::size_t lo, std::size_t hi) {
    for (std::size_t i = lo; i < hi; ++i)
      for (std::uint64_t k = g.row_ptr[i]; k < g.row_ptr[i + 1]; ++k) g.degree[i] += static_cast<std::uint64_t>(g.w[k]);
  });

  summarise_for_focus(g);  // R1-IN-059

  // Components by union-find; ids in order of each component's lowest particle index.
  std::vector<std::uint32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (std::uint32_t i = 0; i < n; ++i)
    for (std::uint64_t k = g.row_ptr[i]; k < g.row_ptr[i + 1]; ++k) {
      const std::uint32_t a = find(i), b = find(g.col[k]);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);  // the lower index roots the set
    }
  constexpr std::uint32_t kNone = 0xFFFFFFFFu;
  std::vector<std::uint32_t> id_of_root(n, kNone);
  g.component.resize(n);
  for (std::uint32_t i = 0; i < n; ++i) {
    const std::uint32_t r = find(i);
    if (id_of_root[r] == kNone) {
      id_of_root[r] = static_cast<std::uint32_t>(g.component_size.size());
      g.component_size.push_back(0);
    }
    g.component[i] = id_of_root[r];
    ++g.component_size[g.component[i]];
  }
  return g;
}

}  // namespace

Result<Graph> build_graph(const Snapshot& s, const ProgressFn& progress, bool parallel) {
  return build(s, progress, parallel, nullptr);
}

Result<Graph> build_graph_releasing_links(Snapshot& s, const ProgressFn& progress, bool parallel) {
  return build(s, progress, parallel, &s.links);
}

}  // namespace r1
