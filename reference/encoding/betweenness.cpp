// Betweenness centrality: Brandes over unweighted shortest paths in a fixed order, exact or from hashed pivots (R1-ENC-012..016).
#include <algorithm>
#include <cmath>
#include <cstring>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "r1/fixedpoint/hemera.hpp"
#include "r1/reference/encoding.hpp"

namespace r1 {

namespace {

// A shortest-path count m x 2^(512 e), m in [1, 2^512) once normalised (R1-ENC-013). 512 bits
// per step keep m far from the double range's ends in both directions.
struct PathCount {
  double m = 0;
  std::int32_t e = 0;
};
constexpr double kStep = 0x1p512;
constexpr double kStepInv = 0x1p-512;

// x x 2^(-512 d) for d >= 0: exact until it underflows, and then a fixed result (0 stays 0).
double scale_down(double x, std::int32_t d) {
  for (; d > 0 && x != 0; --d) x *= kStepInv;
  return x;
}

// a += b, aligned to the larger exponent, then renormalised (one step suffices: the sum of two
// values below 2^512 is below 2^513).
void add_into(PathCount& a, const PathCount& b) {
  if (a.e == b.e) {
    a.m += b.m;
  } else if (a.e > b.e) {
    a.m += scale_down(b.m, a.e - b.e);
  } else {
    a.m = b.m + scale_down(a.m, b.e - a.e);
    a.e = b.e;
  }
  if (a.m >= kStep) {
    a.m *= kStepInv;
    ++a.e;
  }
}

// q x 2^(512 (e_v - e_w)): successors never have a smaller exponent than their predecessor
// (their count is at least as large), but the general case costs nothing to state.
double rescale(double q, std::int32_t ew, std::int32_t ev) {
  if (ew == ev) return q;
  if (ew > ev) return scale_down(q, ew - ev);
  for (std::int32_t d = ev - ew; d > 0; --d) q *= kStep;
  return q;
}

}  // namespace

namespace {

// Per-source work arrays, allocated once per call and reset only where a BFS touched them.
struct Workspace {
  explicit Workspace(std::uint32_t n) : dist(n, -1), m(n, 0.0), e(n, 0), q(n, 0.0), delta(n, 0.0), order(n, 0), succ(n, 0) {}
  std::vector<std::int32_t> dist;
  std::vector<double> m;        // path count mantissa (R1-ENC-013)
  std::vector<std::int32_t> e;  // path count exponent, steps of 2^512
  std::vector<double> q;        // (1 + delta_w) / m_w
  std::vector<double> delta;    // delta_s(v) of the current source
  std::vector<std::uint32_t> order;  // BFS queue; the first `reached` entries are valid
  std::size_t reached = 0;
  std::vector<std::uint32_t> succ;  // successors of one particle: a row has at most n - 1 entries
};

// BFS from s filling dist and order; path counts in the plain-double fast path. Returns false
// when some count reaches 2^512, where the (m, e) form of R1-ENC-013 must renormalise: the caller
// then redoes the source in full form. While every e is 0, add_into is the single addition
// a.m += b.m and rescale is the identity, so the fast path yields the same bits. Raw pointers
// and a preallocated queue keep the loop free of reloads through the vectors.
bool forward_fast(const Graph& g, std::uint32_t s, Workspace& ws) {
  const std::uint64_t* row = g.row_ptr.data();
  const std::uint32_t* col = g.col.data();
  std::int32_t* dist = ws.dist.data();
  double* m = ws.m.data();
  std::uint32_t* queue = ws.order.data();
  std::uint32_t* succ = ws.succ.data();
  std::size_t tail = 0;
  queue[tail++] = s;
  dist[s] = 0;
  m[s] = 1.0;
  for (std::size_t head = 0; head < tail; ++head) {
    const std::uint32_t v = queue[head];
    const std::int32_t next = dist[v] + 1;
    const double mv = m[v];
    const std::uint64_t end = row[v + 1];
    // Successors gathered branch-free (the test is unpredictable), in ascending column order,
    // then the additions, which touch only them.
    std::size_t cnt = 0;
    for (std::uint64_t k = row[v]; k < end; ++k) {
      const std::uint32_t w = col[k];
      if (dist[w] < 0) {
        dist[w] = next;
        m[w] = 0.0;
        queue[tail++] = w;
      }
      succ[cnt] = w;
      cnt += dist[w] == next ? 1 : 0;
    }
    for (std::size_t i = 0; i < cnt; ++i) m[succ[i]] += mv;
  }
  ws.reached = tail;
  // Counts only grow (non-negative addends, monotone rounding), so checking the final values
  // finds every count that ever reached 2^512; !(x < 2^512) also catches inf.
  for (std::size_t i = 0; i < tail; ++i)
    if (!(m[queue[i]] < kStep)) return false;
  return true;
}

// The same BFS with the full (m, e) path counts.
void forward_full(const Graph& g, std::uint32_t s, Workspace& ws) {
  auto& dist = ws.dist;
  auto& order = ws.order;
  for (std::size_t i = 0; i < ws.reached; ++i) dist[order[i]] = -1;
  std::size_t tail = 0;
  order[tail++] = s;
  dist[s] = 0;
  ws.m[s] = 1.0;
  ws.e[s] = 0;
  for (std::size_t head = 0; head < tail; ++head) {
    const std::uint32_t v = order[head];
    const std::int32_t next = dist[v] + 1;
    for (std::uint64_t k = g.row_ptr[v]; k < g.row_ptr[v + 1]; ++k) {
      const std::uint32_t w = g.col[k];
      if (dist[w] < 0) {
        dist[w] = next;
        ws.m[w] = 0.0;
        ws.e[w] = 0;
        order[tail++] = w;
      }
      if (dist[w] == next) {
        PathCount a{ws.m[w], ws.e[w]};
        add_into(a, PathCount{ws.m[v], ws.e[v]});
        ws.m[w] = a.m;
        ws.e[w] = a.e;
      }
    }
  }
  ws.reached = tail;
}

// Backward, reverse BFS order: delta_v = m_v x sum over successors of q_w (ascending index, from
// +0.0), q_v = (1 + delta_v) / m_v. `uniform` says every e is 0 (the fast path), where rescale
// is the identity.
void backward(const Graph& g, Workspace& ws, bool uniform) {
  const std::uint64_t* row = g.row_ptr.data();
  const std::uint32_t* col = g.col.data();
  const std::int32_t* dist = ws.dist.data();
  double* q = ws.q.data();
  const double* m = ws.m.data();
  double* delta = ws.delta.data();
  const std::uint32_t* order = ws.order.data();
  std::uint32_t* succ = ws.succ.data();
  for (std::size_t idx = ws.reached; idx-- > 0;) {
    const std::uint32_t v = order[idx];
    const std::int32_t next = dist[v] + 1;
    const std::uint64_t end = row[v + 1];
    double sum = 0.0;
    if (uniform) {
      // Successors gathered branch-free in ascending column order, then summed left to right.
      std::size_t cnt = 0;
      for (std::uint64_t k = row[v]; k < end; ++k) {
        const std::uint32_t w = col[k];
        succ[cnt] = w;
        cnt += dist[w] == next ? 1 : 0;
      }
      for (std::size_t i = 0; i < cnt; ++i) sum += q[succ[i]];
    } else {
      for (std::uint64_t k = row[v]; k < end; ++k) {
        const std::uint32_t w = col[k];
        if (dist[w] == next) sum += rescale(q[w], ws.e[w], ws.e[v]);
      }
    }
    const double d = m[v] * sum;
    q[v] = (1.0 + d) / m[v];
    delta[v] = d;
  }
}

}  // namespace

std::vector<double> betweenness_from_sources(const Graph& g, std::span<const std::uint32_t> sources_in, double scale,
                                             const ProgressFn& progress) {
  const std::uint32_t n = g.n;
  std::vector<std::uint32_t> sources(sources_in.begin(), sources_in.end());
  std::sort(sources.begin(), sources.end());  // the summation order of R1-ENC-013
  std::vector<double> acc(n, 0.0);
  // Sources run in batches, one per workspace in parallel; the deltas are then added on this
  // thread in ascending source order, so B is the same bits for any thread count. The cap bounds
  // memory (about 40 bytes per particle per workspace).
  constexpr int kMaxSlots = 8;
  const auto slots = static_cast<std::size_t>(std::clamp(tbb::this_task_arena::max_concurrency(), 1, kMaxSlots));
  std::vector<Workspace> ws;
  ws.reserve(std::min(slots, std::max<std::size_t>(sources.size(), 1)));
  for (std::size_t i = 0; i < ws.capacity(); ++i) ws.emplace_back(n);
  std::uint64_t done = 0;
  for (std::size_t first = 0; first < sources.size(); first += ws.size()) {
    const std::size_t batch = std::min(ws.size(), sources.size() - first);
    tbb::parallel_for(std::size_t{0}, batch, [&](std::size_t i) {
      const bool uniform = forward_fast(g, sources[first + i], ws[i]);
      if (!uniform) forward_full(g, sources[first + i], ws[i]);
      backward(g, ws[i], uniform);
    });
    for (std::size_t i = 0; i < batch; ++i) {
      const std::uint32_t s = sources[first + i];
      Workspace& w = ws[i];
      // B(v) += delta_s(v) for v != s, one addition per reached particle (R1-ENC-013).
      for (std::size_t j = 0; j < w.reached; ++j) {
        const std::uint32_t v = w.order[j];
        if (v != s) acc[v] += w.delta[v];
        w.dist[v] = -1;
      }
      report(progress, "betweenness", ++done, sources.size());
    }
  }
  for (auto& x : acc) x *= scale;
  return acc;
}

std::vector<std::uint32_t> choose_pivots(std::span<const ParticleId> ids, std::uint32_t k) {
  const std::size_t n = ids.size();
  if (k >= n) {
    std::vector<std::uint32_t> all(n);
    for (std::uint32_t i = 0; i < n; ++i) all[i] = i;
    return all;
  }
  // Hemera(id || "r1-pivot") for every particle (R1-ENC-015); the batched, parallel hash gives
  // the same digests as the plain one.
  constexpr std::string_view kSalt = "r1-pivot";
  constexpr std::size_t kLen = 32 + kSalt.size();
  std::vector<std::uint8_t> buf(n * kLen);
  std::vector<std::span<const std::uint8_t>> inputs(n);
  for (std::size_t i = 0; i < n; ++i) {
    std::memcpy(buf.data() + i * kLen, ids[i].data(), 32);
    std::memcpy(buf.data() + i * kLen + 32, kSalt.data(), kSalt.size());
    inputs[i] = std::span<const std::uint8_t>(buf.data() + i * kLen, kLen);
  }
  std::vector<hemera::Digest> digest(n);
  hemera::hash_many(inputs, digest);
  std::vector<std::uint32_t> idx(n);
  for (std::uint32_t i = 0; i < n; ++i) idx[i] = i;
  // (digest bytes, index) is a strict total order, so the chosen set does not depend on how
  // nth_element arranges ties.
  auto less = [&](std::uint32_t a, std::uint32_t b) { return digest[a] != digest[b] ? digest[a] < digest[b] : a < b; };
  std::nth_element(idx.begin(), idx.begin() + k, idx.end(), less);
  idx.resize(k);
  std::sort(idx.begin(), idx.end());
  return idx;
}

Betweenness betweenness(const Graph& g, std::span<const ParticleId> ids, const BetweennessOptions& options,
                        const ProgressFn& progress) {
  const std::uint32_t n = g.n;
  const u128 per_source = static_cast<u128>(n) + g.nnz();
  std::uint32_t k = n;  // n means exact
  if (options.pivots) {
    if (*options.pivots != 0 && *options.pivots < n) k = *options.pivots;
  } else if (static_cast<u128>(n) * per_source > options.budget) {
    const u128 by_budget = options.budget / per_source;
    const u128 want = std::max<u128>(options.min_pivots, by_budget);
    if (want < n) k = static_cast<std::uint32_t>(want);
  }
  Betweenness b;
  b.sources = k;
  b.exact = k >= n;
  if (b.exact) {
    std::vector<std::uint32_t> all(n);
    for (std::uint32_t i = 0; i < n; ++i) all[i] = i;
    // Every unordered pair is counted from both ends: b = B / 2 (R1-ENC-014).
    b.value = betweenness_from_sources(g, all, 0.5, progress);
  } else {
    const auto pivots = choose_pivots(ids, k);
    // c = n / (2k): one IEEE division of two exactly represented integers.
    const double c = static_cast<double>(n) / static_cast<double>(2 * static_cast<std::uint64_t>(k));
    b.value = betweenness_from_sources(g, pivots, c, progress);
  }
  return b;
}

double betweenness_error_bound(std::uint32_t n, std::uint32_t k, double delta) {
  // Informational (the manifest and tests), not part of any canonical result, so libm's log is fine.
  const double nn = static_cast<double>(n);
  return nn * (nn - 2.0) / 2.0 * std::sqrt(std::log(2.0 / delta) / (2.0 * static_cast<double>(k)));
}

}  // namespace r1
