// Shared pieces of the generators: resolved parameters, integer Bernoulli thresholds, the link
// emitter that numbers particles by first appearance, and the parallel pair sampler
// (R1-GEN-002, R1-GEN-005..009).
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "r1/fixedpoint/counter_rng.hpp"
#include "r1/fixedpoint/int128.hpp"
#include "r1/reference/generate.hpp"
#include "r1/reference/snapshot_builder.hpp"

namespace r1::gen {

// GenParams after defaults and validation: every value the kind uses is set and in range.
struct Resolved {
  GenKind kind = GenKind::kRing;
  std::uint64_t seed = 1;
  std::uint32_t n = 0;                // nodes (grid, torus: product of dims; crystal: 5040)
  std::uint32_t m = 0;                // ba
  std::vector<std::uint32_t> sizes;   // sbm block sizes, sum n
  std::vector<std::uint32_t> dims;    // grid: w, h; torus: a, b, c
  double p_in = 0, p_out = 0, p_triad = 0, radius = 0;
};

// Link weight 1.0 as a text-style amount (R1-GEN-006): weight * 2^32.
inline constexpr u128 kUnitAmount = u128{1} << 32;

// Probability p in [0, 1] as the integer threshold floor(p * 2^32) in [0, 2^32] (R1-GEN-007).
// Scaling by a power of two is exact, so the threshold is the same on every IEEE machine.
inline std::uint64_t prob_threshold(double p) {
  return static_cast<std::uint64_t>(p * 0x1p32);  // truncation = floor, p >= 0
}

// A Bernoulli draw: the top 32 bits of bits(seed, item, dim) below the threshold. Threshold 2^32
// (p = 1) always succeeds, 0 (p = 0) never does; those two skip the draw (same result, faster).
inline bool bernoulli(std::uint64_t seed, std::uint64_t item, std::uint64_t dim, std::uint64_t threshold) {
  if (threshold == 0) return false;
  if (threshold >> 32) return true;
  return (rng::bits(seed, item, dim) >> 32) < threshold;
}

// Decision dimensions for pair (i, j): dim = c * 2^32 + j, c names the decision (R1-GEN-008).
// Node indices stay below 2^24, so every dimension is far below rng::kDimLimit.
inline constexpr std::uint64_t pair_dim(std::uint64_t c, std::uint64_t j) { return (c << 32) + j; }

// Appends links in chain order; numbers a generator node as a particle on its first appearance,
// source before target (decision 2), naming it with `name`.
class Emitter {
 public:
  using Namer = std::function<std::string(std::uint32_t node)>;
  Emitter(std::string source, std::uint32_t nodes, Namer name);

  void reserve_links(std::uint64_t links) { b_.snapshot().links.reserve(links); }
  // One link from -> to (generator node indices), token 0, neuron 0, height 1.
  void link(std::uint32_t from, std::uint32_t to, u128 amount = kUnitAmount, std::int8_t valence = 1);
  // Generator node of each particle, in canonical particle order.
  const std::vector<std::uint32_t>& node_of_particle() const { return node_of_; }
  // Sets config (text_input_config) and card, then hashes the names (SnapshotBuilder::finish).
  Result<Snapshot> finish(std::string card, const ProgressFn& progress);

 private:
  std::uint32_t particle(std::uint32_t node);
  static constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  SnapshotBuilder b_;
  Namer name_;
  std::vector<std::uint32_t> particle_of_;
  std::vector<std::uint32_t> node_of_;
};

// "<prefix>/<node>": the names of every kind but crystal (R1-GEN-005).
Emitter::Namer indexed_names(std::string prefix);

struct Edge {
  std::uint32_t a, b;
};

// Every pair (i, j), 0 <= i < j < n, for which accept(i, j) holds, in lexicographic order.
// accept must be a pure function of (i, j): rows are split into fixed blocks decided in parallel
// and concatenated in block order, so the result does not depend on the thread count.
template <class Accept>
std::vector<Edge> sample_pairs(std::uint32_t n, const Accept& accept, const ProgressFn& progress,
                               std::string_view stage) {
  // 64 rows per block: enough work per task to amortise scheduling, enough blocks to balance
  // rows of unequal length (row i has n - 1 - i pairs).
  constexpr std::uint32_t kRows = 64;
  const std::uint32_t blocks = (n + kRows - 1) / kRows;
  std::vector<std::vector<Edge>> out(blocks);
  const std::uint64_t total = static_cast<std::uint64_t>(n) * (n - 1) / 2;
  std::atomic<std::uint64_t> done{0};
  tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, blocks, 1), [&](const tbb::blocked_range<std::uint32_t>& r) {
    for (std::uint32_t blk = r.begin(); blk != r.end(); ++blk) {
      const std::uint32_t last = std::min(n, (blk + 1) * kRows);
      std::uint64_t pairs = 0;
      for (std::uint32_t i = blk * kRows; i < last; ++i) {
        for (std::uint32_t j = i + 1; j < n; ++j)
          if (accept(i, j)) out[blk].push_back(Edge{i, j});
        pairs += n - 1 - i;
      }
      report(progress, stage, done += pairs, total);
    }
  });
  std::size_t count = 0;
  for (const auto& v : out) count += v.size();
  std::vector<Edge> edges;
  edges.reserve(count);
  for (auto& v : out) {
    edges.insert(edges.end(), v.begin(), v.end());
    std::vector<Edge>().swap(v);
  }
  return edges;
}

// The generators, one per kind; each gets validated parameters and the card text.
Result<Snapshot> gen_ring(const Resolved& p, std::string card, const ProgressFn& progress);
Result<Snapshot> gen_path(const Resolved& p, std::string card, const ProgressFn& progress);
Result<Snapshot> gen_star(const Resolved& p, std::string card, const ProgressFn& progress);
Result<Snapshot> gen_grid(const Resolved& p, std::string card, const ProgressFn& progress);
Result<Snapshot> gen_torus(const Resolved& p, std::string card, const ProgressFn& progress);
Result<Snapshot> gen_complete(const Resolved& p, std::string card, const ProgressFn& progress);
Result<Snapshot> gen_sbm(const Resolved& p, std::string card, const ProgressFn& progress);
Result<Snapshot> gen_ba(const Resolved& p, std::string card, const ProgressFn& progress);
Result<Snapshot> gen_rgg(const Resolved& p, std::string card, const ProgressFn& progress);
Result<Snapshot> gen_rmat(const Resolved& p, std::string card, const ProgressFn& progress);
Result<Snapshot> gen_crystal(const Resolved& p, std::string card, const ProgressFn& progress);

}  // namespace r1::gen
