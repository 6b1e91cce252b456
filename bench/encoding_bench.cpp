// The encoding stage (R1-ENC-050) on a stored epoch and the snapshot it was computed from:
//   R1_BENCH_EPOCH=DIR R1_BENCH_SNAPSHOT=FILE build/bench/r1_bench_encoding
// times the betweenness behind the roles (R1-ENC-012..015: exact, or from hashed pivots on large
// graphs) and the whole stage on two cores, as an epoch runs it, and checks that the stage gives
// the epoch's own encoding. Without the two variables there is nothing to time (the stage needs a
// real graph; `bench/epoch_scale.sh` times it inside whole epochs).
#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <optional>
#include <string>

#include "r1/reference/encoding.hpp"
#include "r1/reference/epoch_io.hpp"
#include "r1/reference/graph_build.hpp"
#include "r1/reference/snapshot_io.hpp"

namespace {

struct Input {
  r1::Epoch epoch;
  r1::Snapshot snapshot;
  r1::Graph graph;
};

// The options the epoch's encoding was made with, as far as the epoch records them.
r1::EncodingOptions options_of(const r1::Epoch& e) {
  r1::EncodingOptions o;
  o.parallel = true;
  o.r0_squared_raw = e.encoding.r0_squared_raw;
  o.radius_scale = e.encoding.radius_scale;
  if (e.encoding.overlay != "custom") o.overlay = e.encoding.overlay;  // a custom overlay's file is not in the epoch
  return o;
}

bool same(const r1::Encoding& a, const r1::Encoding& b) {
  return a.radius == b.radius && a.luminosity == b.luminosity && a.hue == b.hue && a.saturation == b.saturation &&
         a.role == b.role && a.shape == b.shape && a.color == b.color && a.betweenness == b.betweenness;
}

void BM_BetweennessOfEpoch(benchmark::State& state, const std::shared_ptr<const Input>& in) {
  const r1::EncodingOptions o = options_of(in->epoch);
  std::uint32_t sources = 0;
  for (auto _ : state) {
    r1::Betweenness b = r1::betweenness(in->graph, in->snapshot.particles, o.betweenness, {}, r1::BetweennessRun{true, true});
    sources = b.sources;
    benchmark::DoNotOptimize(b.value.data());
  }
  state.counters["sources"] = sources;
  state.counters["particles"] = static_cast<double>(in->graph.n);
}

// r_0 from the layout (R1-ENC-007), which the epoch's encoding stage computes before encode():
// the median nearest-neighbour spacing of the distinct positions, on all cores.
void BM_RadiusScaleOfEpoch(benchmark::State& state, const std::shared_ptr<const Input>& in) {
  std::int64_t r0 = 0;
  for (auto _ : state) r0 = r1::radius_scale_from_layout(in->epoch.frame.position, in->epoch.focus.phi, true).r0_squared_raw;
  if (in->epoch.encoding.radius_scale == "spacing" && in->epoch.encoding.r0_squared_raw != r0) {
    state.SkipWithError("r_0 differs from the epoch's");
    return;
  }
  state.counters["particles"] = static_cast<double>(in->epoch.ids.size());
}

// The hashed pivots alone (R1-ENC-015): one Hemera hash per particle.
void BM_PivotsOfEpoch(benchmark::State& state, const std::shared_ptr<const Input>& in) {
  const std::uint32_t n = in->graph.n;
  const std::uint32_t k = r1::betweenness_sources(n, in->graph.nnz(), options_of(in->epoch).betweenness);
  if (k >= n) {
    state.SkipWithError("exact betweenness: every particle is a source, no pivots are hashed");
    return;
  }
  for (auto _ : state) benchmark::DoNotOptimize(r1::choose_pivots(in->snapshot.particles, k, true).data());
  state.counters["particles"] = static_cast<double>(n);
}

void BM_EncodingOfEpoch(benchmark::State& state, const std::shared_ptr<const Input>& in) {
  const r1::EncodingOptions o = options_of(in->epoch);
  std::optional<r1::Encoding> last;
  for (auto _ : state) {
    auto e = r1::encode(in->snapshot, in->graph, in->epoch.focus, in->epoch.spectrum, o);
    if (!e.is_ok()) {
      state.SkipWithError(e.status().message().c_str());
      return;
    }
    last = std::move(e).value();
  }
  if (last && !same(*last, in->epoch.encoding)) {
    state.SkipWithError("the encoding differs from the epoch's (made with a custom overlay?)");
    return;
  }
  state.counters["particles"] = static_cast<double>(in->graph.n);
}

[[noreturn]] void fail(const std::string& what) {
  std::fprintf(stderr, "r1_bench_encoding: %s\n", what.c_str());
  std::exit(2);
}

const bool registered = [] {
  const char* dir = std::getenv("R1_BENCH_EPOCH");
  const char* snap = std::getenv("R1_BENCH_SNAPSHOT");
  if (dir == nullptr || *dir == '\0' || snap == nullptr || *snap == '\0') {
    benchmark::RegisterBenchmark("BM_EncodingOfEpoch", [](benchmark::State& state) {
      state.SkipWithError("set R1_BENCH_EPOCH=DIR (an r1 epoch) and R1_BENCH_SNAPSHOT=FILE (its snapshot)");
      for (auto _ : state) {
      }
    })->Iterations(1);
    return false;
  }
  auto in = std::make_shared<Input>();
  auto e = r1::read_epoch(dir);
  if (!e.is_ok()) fail(e.status().message());
  in->epoch = std::move(e).value();
  auto s = r1::read_snapshot(snap);
  if (!s.is_ok()) fail(s.status().message());
  in->snapshot = std::move(s).value();
  if (in->snapshot.particles != in->epoch.ids) fail(std::string(snap) + ": not the snapshot " + dir + " was computed from");
  auto g = r1::build_graph(in->snapshot);
  if (!g.is_ok()) fail(g.status().message());
  in->graph = std::move(g).value();
  std::shared_ptr<const Input> shared = in;
  benchmark::RegisterBenchmark("BM_BetweennessOfEpoch", BM_BetweennessOfEpoch, shared)->Unit(benchmark::kMillisecond)->Iterations(1);
  benchmark::RegisterBenchmark("BM_PivotsOfEpoch", BM_PivotsOfEpoch, shared)->Unit(benchmark::kMillisecond)->Iterations(1);
  benchmark::RegisterBenchmark("BM_RadiusScaleOfEpoch", BM_RadiusScaleOfEpoch, shared)->Unit(benchmark::kMillisecond)->Iterations(1);
  benchmark::RegisterBenchmark("BM_EncodingOfEpoch", BM_EncodingOfEpoch, shared)->Unit(benchmark::kMillisecond)->Iterations(1);
  return true;
}();

}  // namespace
