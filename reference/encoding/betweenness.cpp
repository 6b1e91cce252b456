// Betweenness centrality: Brandes over unweighted shortest paths in a fixed order, exact or from hashed pivots, seven sources per traversal, serial or parallel with the same bits (R1-ENC-012..016, R1-ENC-020..021).
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <memory>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "r1/fixedpoint/hemera.hpp"
#include "r1/fixedpoint/prefetch.hpp"
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

// ---- seven sources per traversal (R1-ENC-021) -----------------------------------------------
//
// A batch runs up to kLanes sources level by level over one shared frontier. A particle's state
// for the batch (its BFS level in each lane, one byte each, and one count per lane) fills one
// cache line, read once per edge instead of once per source per edge: on a large graph the
// traversal's time is these random reads. Per lane the arithmetic is R1-ENC-013's with one
// difference, the order in which a particle's path count adds its predecessors' counts (frontier
// order here, the source's own BFS queue order there). Path counts are non-negative integers:
// while every count of a source stays below 2^53, every partial sum is an integer below 2^53
// (the sums only grow and rounding is monotone, so a true partial sum >= 2^53 would leave a
// computed count >= 2^53), hence exact in any order, and the counts are the canonical bits. A
// source with a count >= 2^53 is redone alone by the canonical code above. The backward sums run
// over each row in ascending column order exactly as R1-ENC-013 says, and the batch's deltas are
// added to B per particle in ascending source order, so B is the same bits batched or not.

// Seven counts and the level word make 64 bytes, one cache line.
constexpr std::uint32_t kLanes = 7;
// Levels are bytes; 0xFF marks a particle a lane has not reached (byte 7 of the level word is
// always 0xFF), so a batch whose BFS gets deeper than 254 levels (long paths and rings) runs its
// sources one at a time instead.
constexpr std::uint8_t kUnreached = 0xFF;
constexpr std::uint32_t kMaxLevel = 254;
constexpr std::uint64_t kNoLane = ~std::uint64_t{0};  // no lane has reached the particle
// Counts below 2^53 are exact integers whatever the summation order (the argument above).
constexpr double kExactInt = 0x1p53;

constexpr std::uint64_t kOnes = 0x0101010101010101u;
constexpr std::uint64_t kLow7 = 0x7F7F7F7F7F7F7F7Fu;

// Bit k set when byte k of x equals b (SWAR, exact: no false positives).
unsigned lanes_equal(std::uint64_t x, std::uint8_t b) {
  const std::uint64_t y = x ^ (kOnes * b);
  // Per byte: high bit set iff the byte is zero.
  const std::uint64_t z = ~(((y & kLow7) + kLow7) | y | kLow7);
  // Gather the eight high bits into bits 0..7 (each partial product lands on its own bit).
  return static_cast<unsigned>(((z >> 7) * 0x0102040810204080u) >> 56);
}

// kByteMask[m]: byte k all ones for every bit k of m (2 KiB, made at compile time).
constexpr std::array<std::uint64_t, 256> make_byte_masks() {
  std::array<std::uint64_t, 256> out{};
  for (unsigned m = 0; m < 256; ++m)
    for (unsigned k = 0; k < 8; ++k)
      if ((m >> k) & 1u) out[m] |= std::uint64_t{0xFF} << (8 * k);
  return out;
}
constexpr std::array<std::uint64_t, 256> kByteMask = make_byte_masks();

// The neighbour this many edges ahead of the traversal gets its cell fetched early (the reads
// are cache misses on a large graph; fx::gather_hint). Rows are gathered kChunk particles at a
// time so that "ahead" runs across row ends. Both shape only the speed. BA 10^6, 51 sources on
// two cores: 4.9-5.7 s with first-level hints 64 ahead, 4.4-4.8 s with second-level ones 128
// ahead (64: 4.7-5.1 s, 256: 4.4-5.1 s).
constexpr std::size_t kPrefetchAhead = 128;
constexpr std::size_t kChunk = 512;

// The rows of list[0, count) concatenated into cols; row i is cols[start[i], start[i + 1]).
void gather_rows(const Graph& g, const std::uint32_t* list, std::size_t count, std::vector<std::uint32_t>& cols,
                 std::vector<std::size_t>& start) {
  cols.clear();
  start.resize(count + 1);
  start[0] = 0;
  for (std::size_t i = 0; i < count; ++i) {
    const std::uint32_t v = list[i];
    cols.insert(cols.end(), g.col.begin() + static_cast<std::ptrdiff_t>(g.row_ptr[v]),
                g.col.begin() + static_cast<std::ptrdiff_t>(g.row_ptr[v + 1]));
    start[i + 1] = cols.size();
  }
}

// One particle's state in a batch.
struct alignas(64) Cell {
  std::uint64_t level = kNoLane;  // byte k < kLanes: BFS level in lane k, kUnreached if none
  // Lane k's path count m (+0.0 where lane k has not reached the particle), replaced by
  // q = (1 + delta) / m going back; add_batch sets it back to +0.0.
  std::array<double, kLanes> mq{};
};
static_assert(sizeof(Cell) == 64);

struct BatchWorkspace {
  explicit BatchWorkspace(std::uint32_t n) : cell(n), delta(std::size_t{n} * kLanes), next((n + 63) / 64, 0) {}
  std::vector<Cell> cell;
  std::vector<double> delta;            // [p][k]: delta of lane k's source at p
  std::vector<std::uint64_t> next;      // bit p: some lane reached p at the level being built
  std::vector<std::uint32_t> cols;      // rows of a chunk of the frontier (gather_rows)
  std::vector<std::size_t> start;
  std::vector<std::uint32_t> frontier;  // particles by level, ascending within a level: each
  std::vector<std::size_t> level_start; // level lists every particle some lane reaches there
  std::array<std::uint32_t, kLanes> source{};
  std::uint32_t lanes = 0;
  unsigned redo = 0;  // lanes to run again one source at a time (a count reached 2^53)
  bool too_deep = false;
};

// Forward: levels, path counts and the frontier lists of every lane at once. Each level's list
// comes out of a bitmap in ascending particle order, which keeps the row reads sequential.
void batch_forward(const Graph& g, BatchWorkspace& b) {
  Cell* cell = b.cell.data();
  std::uint64_t* next_bits = b.next.data();
  b.frontier.clear();
  b.level_start.assign(1, 0);
  b.too_deep = false;
  for (std::uint32_t k = 0; k < b.lanes; ++k) {
    const std::uint32_t s = b.source[k];
    cell[s].level &= ~kByteMask[1u << k];  // level 0
    cell[s].mq[k] = 1.0;
    next_bits[s / 64] |= std::uint64_t{1} << (s % 64);  // a source given twice is listed once
  }
  for (std::uint32_t d = 0;; ++d) {
    // The particles first reached at level d, ascending.
    const std::size_t first = b.frontier.size();
    for (std::size_t word = 0; word < b.next.size(); ++word)
      for (std::uint64_t bits = next_bits[word]; bits != 0; bits &= bits - 1)
        b.frontier.push_back(static_cast<std::uint32_t>(word * 64 + static_cast<std::size_t>(std::countr_zero(bits))));
    std::fill(b.next.begin(), b.next.end(), 0);
    const std::size_t last = b.frontier.size();
    b.level_start.push_back(last);
    if (first == last) break;
    if (d == kMaxLevel) {
      b.too_deep = true;
      return;
    }
    const auto next = static_cast<std::uint8_t>(d + 1);
    const std::uint64_t next_byte = kOnes * next;
    for (std::size_t c0 = first; c0 < last; c0 += kChunk) {
      const std::size_t count = std::min(kChunk, last - c0);
      gather_rows(g, b.frontier.data() + c0, count, b.cols, b.start);
      const std::uint32_t* cols = b.cols.data();
      const std::size_t total = b.cols.size();
      for (std::size_t i = 0; i < count; ++i) {
        const Cell& cv = cell[b.frontier[c0 + i]];
        const unsigned mine = lanes_equal(cv.level, static_cast<std::uint8_t>(d));
        for (std::size_t e = b.start[i]; e < b.start[i + 1]; ++e) {
          if (e + kPrefetchAhead < total) fx::gather_hint(cell + cols[e + kPrefetchAhead]);
          Cell& cw = cell[cols[e]];
          const unsigned fresh = lanes_equal(cw.level, kUnreached) & mine;
          const std::uint64_t fresh_bytes = kByteMask[fresh];
          const std::uint64_t lw = (cw.level & ~fresh_bytes) | (next_byte & fresh_bytes);
          cw.level = lw;
          next_bits[cols[e] / 64] |= static_cast<std::uint64_t>(fresh != 0) << (cols[e] % 64);
          // m_w += m_v in every lane where w succeeds v (a fresh lane's count was +0.0).
          for (unsigned mk = lanes_equal(lw, next) & mine; mk != 0; mk &= mk - 1) {
            const auto k = static_cast<std::size_t>(std::countr_zero(mk));
            cw.mq[k] += cv.mq[k];
          }
        }
      }
    }
  }
  b.redo = 0;
  for (const std::uint32_t v : b.frontier)
    for (std::uint32_t k = 0; k < b.lanes; ++k)
      if (!(cell[v].mq[k] < kExactInt)) b.redo |= 1u << k;
}

// Backward, deepest level first: per particle and lane, the successors' q in ascending column
// order from +0.0, then delta and q exactly as R1-ENC-013. Particles of one level depend only on
// the level below, so their order within a level is free.
void batch_backward(const Graph& g, BatchWorkspace& b) {
  Cell* cell = b.cell.data();
  double* delta = b.delta.data();
  for (std::size_t d = b.level_start.size() - 1; d-- > 0;) {
    const auto next = static_cast<std::uint8_t>(d + 1);
    const std::size_t first = b.level_start[d], last = b.level_start[d + 1];
    for (std::size_t c0 = first; c0 < last; c0 += kChunk) {
      const std::size_t count = std::min(kChunk, last - c0);
      gather_rows(g, b.frontier.data() + c0, count, b.cols, b.start);
      const std::uint32_t* cols = b.cols.data();
      const std::size_t total = b.cols.size();
      for (std::size_t i = 0; i < count; ++i) {
        const std::uint32_t v = b.frontier[c0 + i];
        Cell& cv = cell[v];
        const unsigned mine = lanes_equal(cv.level, static_cast<std::uint8_t>(d));
        std::array<double, kLanes> sum{};
        for (std::size_t e = b.start[i]; e < b.start[i + 1]; ++e) {
          if (e + kPrefetchAhead < total) fx::gather_hint(cell + cols[e + kPrefetchAhead]);
          const Cell& cw = cell[cols[e]];
          for (unsigned mk = lanes_equal(cw.level, next) & mine; mk != 0; mk &= mk - 1) {
            const auto k = static_cast<std::size_t>(std::countr_zero(mk));
            sum[k] += cw.mq[k];
          }
        }
        double* dv = delta + std::size_t{v} * kLanes;
        for (unsigned mk = mine; mk != 0; mk &= mk - 1) {
          const auto k = static_cast<std::size_t>(std::countr_zero(mk));
          const double dd = cv.mq[k] * sum[k];
          cv.mq[k] = (1.0 + dd) / cv.mq[k];
          dv[k] = dd;
        }
      }
    }
  }
}

// Runs lane k's source alone by the canonical code and puts its deltas in the lane.
void redo_lane(const Graph& g, BatchWorkspace& b, std::uint32_t k, std::unique_ptr<Workspace>& single) {
  if (!single) single = std::make_unique<Workspace>(g.n);
  Workspace& ws = *single;
  const std::uint32_t s = b.source[k];
  const bool uniform = forward_fast(g, s, ws);
  if (!uniform) forward_full(g, s, ws);
  backward(g, ws, uniform);
  const int shift = static_cast<int>(8 * k);
  // The lane's levels become "unreached" everywhere the batch went, then level 0 ("reached": only
  // add_batch reads them now) wherever the canonical run went.
  for (const std::uint32_t v : b.frontier) b.cell[v].level |= std::uint64_t{0xFF} << shift;
  for (std::size_t j = 0; j < ws.reached; ++j) {
    const std::uint32_t v = ws.order[j];
    b.cell[v].level &= ~(std::uint64_t{0xFF} << shift);
    b.delta[std::size_t{v} * kLanes + k] = ws.delta[v];
    ws.dist[v] = -1;
  }
}

// One batch: traversal, then the lanes that need the canonical path.
void run_batch(const Graph& g, BatchWorkspace& b, std::unique_ptr<Workspace>& single) {
  batch_forward(g, b);
  if (b.too_deep) {
    b.redo = (1u << b.lanes) - 1;
  } else {
    batch_backward(g, b);
  }
  for (std::uint32_t k = 0; k < b.lanes; ++k)
    if ((b.redo >> k) & 1u) redo_lane(g, b, k, single);
}

// add_batch over the particles [lo, hi).
void add_batch_range(BatchWorkspace& b, std::vector<double>& acc, std::uint32_t lo, std::uint32_t hi) {
  for (std::uint32_t v = lo; v < hi; ++v) {
    Cell& c = b.cell[v];
    const std::uint64_t lv = c.level;
    if (lv == kNoLane) continue;
    const double* dv = b.delta.data() + std::size_t{v} * kLanes;
    for (std::uint32_t k = 0; k < b.lanes; ++k)
      if (((lv >> (8 * k)) & 0xFF) != kUnreached && v != b.source[k]) acc[v] += dv[k];
    c = Cell{};
  }
}

// B(v) += delta_s(v) for every reached v != s, lanes (sources) ascending; then clears the batch.
// Each particle's sum is its own, so ranges of particles may run on workers (the same bits).
void add_batch(BatchWorkspace& b, std::vector<double>& acc, bool parallel) {
  const std::uint32_t n = static_cast<std::uint32_t>(acc.size());
  constexpr std::uint32_t kGrain = 1u << 14;
  if (parallel && n > kGrain) {
    tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, n, kGrain), [&](const tbb::blocked_range<std::uint32_t>& r) {
      add_batch_range(b, acc, r.begin(), r.end());
    });
  } else {
    add_batch_range(b, acc, 0, n);
  }
}

}  // namespace

std::vector<double> betweenness_from_sources(const Graph& g, std::span<const std::uint32_t> sources_in, double scale,
                                             const ProgressFn& progress, const BetweennessRun& run) {
  const std::uint32_t n = g.n;
  std::vector<std::uint32_t> sources(sources_in.begin(), sources_in.end());
  std::sort(sources.begin(), sources.end());  // the summation order of R1-ENC-013
  std::vector<double> acc(n, 0.0);
  if (sources.empty()) return acc;
  std::uint64_t done = 0;
  // Workspaces run side by side in parallel; their results are added on this thread in ascending
  // source order, so B is the same bits for any thread count. The cap bounds memory.
  constexpr int kMaxSlots = 4;
  const auto slots = run.parallel ? static_cast<std::size_t>(std::clamp(tbb::this_task_arena::max_concurrency(), 1, kMaxSlots)) : 1;
  if (!run.batched) {
    std::vector<Workspace> ws;
    ws.reserve(std::min(slots, sources.size()));
    for (std::size_t i = 0; i < ws.capacity(); ++i) ws.emplace_back(n);
    for (std::size_t first = 0; first < sources.size(); first += ws.size()) {
      const std::size_t count = std::min(ws.size(), sources.size() - first);
      auto one = [&](std::size_t i) {
        const bool uniform = forward_fast(g, sources[first + i], ws[i]);
        if (!uniform) forward_full(g, sources[first + i], ws[i]);
        backward(g, ws[i], uniform);
      };
      if (count > 1) tbb::parallel_for(std::size_t{0}, count, one);
      else one(0);
      for (std::size_t i = 0; i < count; ++i) {
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
  } else {
    // Consecutive slices of the sorted list, as few batches as 7 lanes allow and their sizes
    // within one of each other (51 sources: 7, 7, 7, 6, 6, 6, 6, 6), so the batches that run side
    // by side take about the same time; B is added batch after batch, each lane ascending, so
    // the sum runs over the sources in ascending order whatever the split.
    const std::size_t batches = (sources.size() + kLanes - 1) / kLanes;
    const std::size_t base = sources.size() / batches, extra = sources.size() % batches;
    const auto batch_first = [&](std::size_t i) { return i * base + std::min(i, extra); };
    std::vector<BatchWorkspace> ws;
    std::vector<std::unique_ptr<Workspace>> single(std::min(slots, batches));
    ws.reserve(single.size());
    for (std::size_t i = 0; i < single.size(); ++i) ws.emplace_back(n);
    for (std::size_t first = 0; first < batches; first += ws.size()) {
      const std::size_t count = std::min(ws.size(), batches - first);
      auto one = [&](std::size_t i) {
        BatchWorkspace& b = ws[i];
        const std::size_t lo = batch_first(first + i);
        b.lanes = static_cast<std::uint32_t>(batch_first(first + i + 1) - lo);
        for (std::uint32_t k = 0; k < b.lanes; ++k) b.source[k] = sources[lo + k];
        run_batch(g, b, single[i]);
      };
      if (count > 1) tbb::parallel_for(std::size_t{0}, count, one);
      else one(0);
      for (std::size_t i = 0; i < count; ++i) {
        add_batch(ws[i], acc, run.parallel);
        done += ws[i].lanes;
        report(progress, "betweenness", done, sources.size());
      }
    }
  }
  for (auto& x : acc) x *= scale;
  return acc;
}

std::vector<std::uint32_t> choose_pivots(std::span<const ParticleId> ids, std::uint32_t k, bool parallel) {
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
  hemera::hash_many(inputs, digest, parallel);
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

std::uint32_t betweenness_sources(std::uint32_t n, std::uint64_t nnz, const BetweennessOptions& options) {
  const u128 per_source = static_cast<u128>(n) + nnz;
  std::uint32_t k = n;  // n means exact
  if (options.pivots) {
    if (*options.pivots != 0 && *options.pivots < n) k = *options.pivots;
  } else if (static_cast<u128>(n) * per_source > options.budget) {
    const u128 by_budget = options.budget / per_source;
    const u128 want = std::max<u128>(options.min_pivots, by_budget);
    if (want < n) k = static_cast<std::uint32_t>(want);
  }
  return k;
}

Betweenness betweenness(const Graph& g, std::span<const ParticleId> ids, const BetweennessOptions& options,
                        const ProgressFn& progress, const BetweennessRun& run) {
  const std::uint32_t n = g.n;
  const std::uint32_t k = betweenness_sources(n, g.nnz(), options);
  Betweenness b;
  b.sources = k;
  b.exact = k >= n;
  if (b.exact) {
    std::vector<std::uint32_t> all(n);
    for (std::uint32_t i = 0; i < n; ++i) all[i] = i;
    // Every unordered pair is counted from both ends: b = B / 2 (R1-ENC-014).
    b.value = betweenness_from_sources(g, all, 0.5, progress, run);
  } else {
    const auto pivots = choose_pivots(ids, k, run.parallel);
    // c = n / (2k): one IEEE division of two exactly represented integers.
    const double c = static_cast<double>(n) / static_cast<double>(2 * static_cast<std::uint64_t>(k));
    b.value = betweenness_from_sources(g, pivots, c, progress, run);
  }
  return b;
}

double betweenness_error_bound(std::uint32_t n, std::uint32_t k, double delta) {
  // Informational (the manifest and tests), not part of any canonical result, so libm's log is fine.
  const double nn = static_cast<double>(n);
  return nn * (nn - 2.0) / 2.0 * std::sqrt(std::log(2.0 / delta) / (2.0 * static_cast<double>(k)));
}

}  // namespace r1
