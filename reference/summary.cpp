// Snapshot and layout-graph statistics for `r1 info` (R1-IN-060).
#include "r1/reference/summary.hpp"

#include <algorithm>
#include <vector>

namespace r1 {

namespace {
template <class T>
DegreeStats stats(std::vector<T> v, double scale) {
  DegreeStats d;
  if (v.empty()) return d;
  std::sort(v.begin(), v.end());
  long double sum = 0;
  for (const T& x : v) sum += static_cast<long double>(x);
  d.min = static_cast<double>(v.front()) * scale;
  d.max = static_cast<double>(v.back()) * scale;
  d.mean = static_cast<double>(sum / static_cast<long double>(v.size())) * scale;
  // Median of an even count: the mean of the two middle values.
  const std::size_t m = v.size() / 2;
  d.median = (v.size() % 2 == 1 ? static_cast<double>(v[m]) : (static_cast<double>(v[m - 1]) + static_cast<double>(v[m])) / 2) * scale;
  return d;
}
}  // namespace

SnapshotSummary summarize(const Snapshot& s, const Graph& g) {
  SnapshotSummary r;
  r.chain_id = s.config.chain_id;
  r.block = s.config.block;
  r.particles = g.n;
  r.links = g.links;
  r.neurons = s.neurons.size();
  r.self_loops_dropped = g.self_loops_dropped;
  r.pairs = g.nnz() / 2;
  r.components = g.component_size.size();
  r.largest_component = g.component_size.empty() ? 0 : *std::max_element(g.component_size.begin(), g.component_size.end());
  r.anchor = anchor_count(g.n);
  r.titles = static_cast<std::uint64_t>(std::count_if(s.titles.begin(), s.titles.end(), [](const std::string& t) { return !t.empty(); }));
  r.crystal = static_cast<std::uint64_t>(std::count_if(s.crystal.begin(), s.crystal.end(), [](const CrystalTag& t) { return t.known(); }));
  std::vector<std::uint32_t> nb(g.n);
  for (std::uint32_t i = 0; i < g.n; ++i) {
    nb[i] = g.neighbours(i);
    r.isolated += nb[i] == 0;
  }
  r.degree = stats(std::move(nb), 1.0);
  r.weighted_degree = stats(g.degree, 0x1p-32);
  return r;
}

}  // namespace r1
