// Random graph models: stochastic block model and Barabasi-Albert preferential attachment
// (R1-GEN-020..022).
#include "gen_internal.hpp"

namespace r1::gen {

Result<Snapshot> gen_sbm(const Resolved& p, std::string card, const ProgressFn& progress) {
  // Nodes are numbered block by block: block b holds a contiguous index range.
  std::vector<std::uint32_t> block(p.n);
  std::uint32_t next = 0;
  for (std::uint32_t b = 0; b < p.sizes.size(); ++b)
    for (std::uint32_t k = 0; k < p.sizes[b]; ++k) block[next++] = b;
  const std::uint64_t t_in = prob_threshold(p.p_in), t_out = prob_threshold(p.p_out);
  // Pair (i, j), i < j, is linked when bits(seed, i, j) passes the threshold of its block pair.
  const auto accept = [&](std::uint32_t i, std::uint32_t j) {
    return bernoulli(p.seed, i, pair_dim(0, j), block[i] == block[j] ? t_in : t_out);
  };
  const std::vector<Edge> edges = sample_pairs(p.n, accept, progress, "generating sbm");
  Emitter e("gen:sbm", p.n, indexed_names("sbm"));
  e.reserve_links(edges.size());
  for (const Edge& x : edges) e.link(x.a, x.b);
  return e.finish(std::move(card), progress);
}

Result<Snapshot> gen_ba(const Resolved& p, std::string card, const ProgressFn& progress) {
  const std::uint32_t m = p.m;
  const std::uint64_t core_links = static_cast<std::uint64_t>(m) * (m + 1) / 2;
  const std::uint64_t total = core_links + static_cast<std::uint64_t>(p.n - m - 1) * m;
  Emitter e("gen:ba", p.n, indexed_names("ba"));
  e.reserve_links(total);
  // Every link's two endpoints, in emission order: a uniform pick from this list is a pick
  // proportional to degree (preferential attachment).
  std::vector<std::uint32_t> ends;
  ends.reserve(2 * total);
  const auto emit = [&](std::uint32_t from, std::uint32_t to) {
    e.link(from, to);
    ends.push_back(from);
    ends.push_back(to);
  };
  // Core: nodes 0..m form a complete graph; each core node links to every earlier one, so every
  // node starts with degree >= m and new links always point from newer to older nodes.
  for (std::uint32_t j = 1; j <= m; ++j)
    for (std::uint32_t i = 0; i < j; ++i) emit(j, i);
  // chosen_by[v] == t marks v as already picked by node t: distinct targets in O(1) per draw.
  std::vector<std::uint32_t> chosen_by(p.n, 0);
  std::vector<std::uint32_t> targets(m);
  // Progress every 2^14 nodes: about a thousand updates for 10^7 links at m = 10.
  constexpr std::uint32_t kReportEvery = 1u << 14;
  for (std::uint32_t t = m + 1; t < p.n; ++t) {
    // Targets are drawn from the list as it stood before t: attempt a picks
    // ends[uniform_below(seed, t, a, |ends|)], repeats are rejected, until m are distinct.
    const std::uint64_t len = ends.size();
    std::uint32_t got = 0;
    for (std::uint64_t a = 0; got < m; ++a) {
      const std::uint32_t v = ends[rng::uniform_below(p.seed, t, a, len)];
      if (chosen_by[v] == t) continue;
      chosen_by[v] = t;
      targets[got++] = v;
    }
    for (std::uint32_t k = 0; k < m; ++k) emit(t, targets[k]);
    if (t % kReportEvery == 0 || t + 1 == p.n) report(progress, "generating ba", t + 1, p.n);
  }
  return e.finish(std::move(card), progress);
}

// R-MAT (Chakrabarti, Zhan and Faloutsos 2004) with Graph500's quadrant probabilities
// (R1-GEN-025..027): m n links, each drawn by `scale` quadrant choices in the 2^scale adjacency
// matrix; draws outside the n node ids or on the diagonal are redrawn.
Result<Snapshot> gen_rmat(const Resolved& p, std::string card, const ProgressFn& progress) {
  std::uint32_t scale = 0;
  while ((std::uint64_t{1} << scale) < p.n) ++scale;
  // Cumulative thresholds of a, a + b, a + b + c as 32-bit integers (R1-GEN-007).
  const std::uint64_t ta = prob_threshold(0.57), tb = prob_threshold(0.76), tc = prob_threshold(0.95);
  const std::uint64_t links = static_cast<std::uint64_t>(p.n) * p.m;
  Emitter e("gen:rmat", p.n, indexed_names("rmat"));
  e.reserve_links(links);
  constexpr std::uint64_t kReportEvery = 1u << 16;
  for (std::uint64_t k = 0; k < links; ++k) {
    for (std::uint64_t attempt = 0;; ++attempt) {
      std::uint32_t from = 0, to = 0;
      for (std::uint32_t level = 0; level < scale; ++level) {
        const std::uint64_t u = rng::bits(p.seed, k, (attempt << 8) + level) >> 32;
        from = (from << 1) | (u >= tb ? 1u : 0u);
        to = (to << 1) | ((u >= ta && u < tb) || u >= tc ? 1u : 0u);
      }
      if (from >= p.n || to >= p.n || from == to) continue;
      e.link(from, to);
      break;
    }
    if (k % kReportEvery == 0 || k + 1 == links) report(progress, "generating rmat", k + 1, links);
  }
  return e.finish(std::move(card), progress);
}

}  // namespace r1::gen
