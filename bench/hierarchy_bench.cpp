// Hierarchy build throughput, serial and parallel (R1-HIER-010..033, R1-HIER-070), on synthetic
// layouts of 10^4, 10^5 and 10^6 particles: points clustered in blobs inside the scene sphere (as
// spectral layouts are), phi spread unevenly, every rule exact on Q32 raws. Input generation is
// outside the timed loop.
#include <benchmark/benchmark.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "r1/fixedpoint/counter_rng.hpp"
#include "r1/fixedpoint/hemera.hpp"
#include "r1/format/hierarchy.hpp"
#include "r1/reference/epoch_io.hpp"
#include "r1/reference/hierarchy.hpp"

namespace {

struct Layout {
  std::vector<std::array<r1::Q32, 3>> pos;
  std::vector<r1::Q32> phi;
  std::vector<r1::Color> color;
  std::vector<r1::ParticleId> ids;
};

// n points in sqrt(n) blobs: blob centres uniform in a cube of side 1600 scene units, members
// within +-40 units of their centre (uniform per axis). phi raws 1 + (i mod 97), the remainder of
// 2^32 spread one raw at a time from particle 0, so the raws sum to exactly 2^32.
Layout make_layout(std::size_t n) {
  Layout l;
  l.pos.resize(n);
  l.phi.resize(n);
  l.color.resize(n);
  std::size_t blobs = 1;
  while (blobs * blobs < n) ++blobs;
  std::int64_t total = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t b = r1::rng::uniform_below(3, i, 0, blobs);
    for (int c = 0; c < 3; ++c) {
      const double centre = 1600.0 * r1::rng::uniform_double(5, b, static_cast<std::uint64_t>(c)) - 800.0;
      const double offset = 80.0 * r1::rng::uniform_double(7, i, static_cast<std::uint64_t>(c)) - 40.0;
      l.pos[i][static_cast<std::size_t>(c)] = r1::Q32::from_double(centre + offset);
    }
    l.phi[i] = r1::Q32::from_raw(static_cast<std::int64_t>(1 + i % 97));
    total += l.phi[i].raw;
    l.color[i] = {static_cast<std::uint8_t>(b), static_cast<std::uint8_t>(b >> 8), 128};
  }
  const std::int64_t rest = (std::int64_t{1} << 32) - total;
  for (std::size_t i = 0; i < n; ++i)
    l.phi[i].raw += rest / static_cast<std::int64_t>(n) + (static_cast<std::int64_t>(i) < rest % static_cast<std::int64_t>(n) ? 1 : 0);
  std::vector<std::string> names(n);
  for (std::size_t i = 0; i < n; ++i) names[i] = "bench/" + std::to_string(i);
  l.ids.resize(n);
  r1::hemera::hash_many(names, l.ids);
  return l;
}

const Layout& layout(std::size_t n) {
  static std::map<std::size_t, std::unique_ptr<Layout>> cache;
  auto& slot = cache[n];
  if (!slot) slot = std::make_unique<Layout>(make_layout(n));
  return *slot;
}

// Arg 0: particles; arg 1: HierarchyOptions::parallel (R1-HIER-070; the same bytes either way).
void BM_Hierarchy(benchmark::State& state) {
  const Layout& l = layout(static_cast<std::size_t>(state.range(0)));
  r1::HierarchyOptions options;
  options.parallel = state.range(1) != 0;
  std::size_t clusters = 0;
  for (auto _ : state) {
    auto h = r1::build_hierarchy(l.pos, l.phi, l.color, l.ids, options);
    if (!h.is_ok()) {
      state.SkipWithError(h.status().message().c_str());
      return;
    }
    clusters = h->levels[0].size();
    benchmark::DoNotOptimize(clusters);
  }
  state.counters["level0_clusters"] = static_cast<double>(clusters);
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_Hierarchy)
    ->ArgsProduct({{10'000, 100'000, 1'000'000}, {0, 1}})
    ->ArgNames({"n", "parallel"})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);

}  // namespace

// The hierarchy of a stored epoch's own layout (R1_BENCH_EPOCH=DIR, an `r1 epoch` directory):
// spectral layouts are not blobs, and the real 10^6-particle layout is what the stage meets in an
// epoch. Parallel (R1-HIER-070); the result must be the epoch's hierarchy byte for byte.
namespace {

void BM_HierarchyOfEpoch(benchmark::State& state, const std::shared_ptr<const r1::Epoch>& e) {
  r1::HierarchyOptions options;
  options.parallel = true;
  std::optional<r1::Hierarchy> last;
  for (auto _ : state) {
    auto h = r1::build_hierarchy(e->frame.position, e->focus.phi, e->encoding.color, e->ids, options);
    if (!h.is_ok()) {
      state.SkipWithError(h.status().message().c_str());
      return;
    }
    last = std::move(h).value();
  }
  // Checked outside the timed loop: serialising 10^6 particles' levels is not the stage's work.
  if (last && r1::hierarchy_bytes(*last) != r1::hierarchy_bytes(e->hierarchy)) {
    state.SkipWithError("the hierarchy differs from the epoch's");
    return;
  }
  state.counters["particles"] = static_cast<double>(e->ids.size());
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(e->ids.size()));
}

const bool registered = [] {
  const char* dir = std::getenv("R1_BENCH_EPOCH");
  if (dir == nullptr || *dir == '\0') return false;
  auto e = r1::read_epoch(dir);
  if (!e.is_ok()) {
    std::fprintf(stderr, "R1_BENCH_EPOCH: %s\n", e.status().message().c_str());
    std::exit(2);
  }
  auto shared = std::make_shared<const r1::Epoch>(std::move(e).value());
  benchmark::RegisterBenchmark("BM_HierarchyOfEpoch", BM_HierarchyOfEpoch, shared)
      ->Unit(benchmark::kMillisecond)
      ->Iterations(1);
  return true;
}();

}  // namespace
