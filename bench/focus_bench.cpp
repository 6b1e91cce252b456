// Focus phi* throughput: the tri-kernel iteration in Q32 and fp64, serial and parallel, on the
// crystal and Barabasi-Albert graphs (R1-FOC-001, R1-FOC-090).
// Defaults: TriKernelParams{} and lambda2 = 0, the disconnected-graph value, which gives the most
// steps T(eps) for a graph (the heat term of kappa is then l_h): a conservative timing. The
// 10^6-particle, 10^7-link case (m = 10) runs only with R1_BENCH_LARGE=1 set in the environment:
// generating it needs about 2 GiB and a minute.
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <utility>

#include "r1/solvers/focus.hpp"
#include "r1/reference/generate.hpp"
#include "r1/reference/graph_build.hpp"

namespace {

// One graph per (kind, n, m), generated on first use and kept for the process.
const r1::Graph& graph(r1::GenKind kind, std::int64_t n, std::int64_t m) {
  static std::map<std::tuple<int, std::int64_t, std::int64_t>, std::unique_ptr<r1::Graph>> cache;
  auto& slot = cache[{static_cast<int>(kind), n, m}];
  if (!slot) {
    r1::GenParams p;
    p.kind = kind;
    if (kind == r1::GenKind::kBa) {
      p.n = n;
      p.m = m;
    }
    auto s = r1::generate(p);
    if (!s.is_ok()) std::abort();
    auto g = r1::build_graph(*s);
    if (!g.is_ok()) std::abort();
    slot = std::make_unique<r1::Graph>(std::move(g).value());
  }
  return *slot;
}

template <bool kQ32>
void run_focus(benchmark::State& st, const r1::Graph& g, bool parallel) {
  r1::FocusOptions opt;
  opt.parallel = parallel;
  const r1::TriKernelParams params;
  std::uint32_t steps = 0;
  double kappa = 0;
  for (auto _ : st) {
    if constexpr (kQ32) {
      auto f = r1::compute_focus_q32(g, params, 0.0, {}, opt);
      if (!f.is_ok()) {
        st.SkipWithError(f.status().message().c_str());
        break;
      }
      steps = f->steps;
      kappa = f->kappa;
      benchmark::DoNotOptimize(f->phi.data());
    } else {
      auto f = r1::compute_focus_f64(g, params, 0.0, {}, opt);
      if (!f.is_ok()) {
        st.SkipWithError(f.status().message().c_str());
        break;
      }
      steps = f->steps;
      kappa = f->kappa;
      benchmark::DoNotOptimize(f->phi.data());
    }
  }
  st.counters["n"] = g.n;
  st.counters["nnz"] = static_cast<double>(g.nnz());
  st.counters["steps"] = steps;
  st.counters["kappa"] = kappa;
  // Seconds per step, the figure that scales with the graph.
  st.counters["s_per_step"] = benchmark::Counter(static_cast<double>(steps) * static_cast<double>(st.iterations()),
                                                 benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

void BM_FocusQ32_Crystal(benchmark::State& st) { run_focus<true>(st, graph(r1::GenKind::kCrystal, 0, 0), false); }
void BM_FocusF64_Crystal(benchmark::State& st) { run_focus<false>(st, graph(r1::GenKind::kCrystal, 0, 0), false); }
void BM_FocusQ32_Ba(benchmark::State& st) { run_focus<true>(st, graph(r1::GenKind::kBa, st.range(0), 10), st.range(1) != 0); }
void BM_FocusF64_Ba(benchmark::State& st) { run_focus<false>(st, graph(r1::GenKind::kBa, st.range(0), 10), st.range(1) != 0); }

BENCHMARK(BM_FocusQ32_Crystal)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FocusF64_Crystal)->Unit(benchmark::kMillisecond);
// args: n, parallel (0 = the serial reference, 1 = TBB rows)
BENCHMARK(BM_FocusQ32_Ba)->Args({10000, 0})->Args({100000, 0})->Args({100000, 1})->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_FocusF64_Ba)->Args({10000, 0})->Args({100000, 0})->Args({100000, 1})->Unit(benchmark::kMillisecond)->Iterations(1);

// The 10^7-link case, registered only on request (R1_BENCH_LARGE=1).
const bool kLargeRegistered = [] {
  const char* on = std::getenv("R1_BENCH_LARGE");
  if (on == nullptr || std::string(on) != "1") return false;
  benchmark::RegisterBenchmark("BM_FocusQ32_Ba1M/parallel:0", [](benchmark::State& st) {
    run_focus<true>(st, graph(r1::GenKind::kBa, 1000000, 10), false);
  })->Unit(benchmark::kSecond)->Iterations(1);
  benchmark::RegisterBenchmark("BM_FocusQ32_Ba1M/parallel:1", [](benchmark::State& st) {
    run_focus<true>(st, graph(r1::GenKind::kBa, 1000000, 10), true);
  })->Unit(benchmark::kSecond)->Iterations(1);
  benchmark::RegisterBenchmark("BM_FocusF64_Ba1M/parallel:1", [](benchmark::State& st) {
    run_focus<false>(st, graph(r1::GenKind::kBa, 1000000, 10), true);
  })->Unit(benchmark::kSecond)->Iterations(1);
  return true;
}();

}  // namespace
