// Focus phi* throughput: the tri-kernel iteration in Q32 and fp64, serial and parallel, on the
// crystal and Barabasi-Albert graphs (R1-FOC-001, R1-FOC-090).
// Defaults: TriKernelParams{} and lambda2 = 0, the disconnected-graph value, which gives the most
// steps T(eps) for a graph (the heat term of kappa is then l_h): a conservative timing. The
// 10^6-particle, 10^7-link case (m = 10) runs only with R1_BENCH_LARGE=1 set in the environment:
// generating it needs about 2 GiB and a minute.
//
// Beside the stage, the floor under it on the machine at hand (BM_FocusGatherFloor_Ba1M). A Q32
// step gathers phi for the diffusion's in-link sums and for the springs and the heat kernel's
// first walk, then t_1 .. t_7 for the seven further walks (R1-FOC-090); on graphs past the caches
// the products' time is these random gathers. The in-links lie inside A_sym's pattern, so at
// best one pass over A_sym serves the first three and a step is eight gathering passes. The floor
// runs eight passes over A_sym's rows per step with nothing but each entry's gather and a 64-bit
// multiply-add: no exact 128-bit sums, no rounding, no combination, projection or recurrence
// terms, the stage's row split, prefetch distance and hint. Timed beside the stage for the T(eps)
// of the BA 10^6 epoch (lambda2 = 0.5695): a measure of this machine, not a result.
#include <benchmark/benchmark.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstdlib>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <utility>

#include "r1/fixedpoint/prefetch.hpp"
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
  // Seconds per step of T(eps), the figure that scales with the graph. A run that stops at a
  // repeated iterate (R1-FOC-093) runs fewer steps than T, so it is then below the time of a
  // step run.
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

// lambda2 of the BA 10^6 (m = 10) epoch, as its spectral stage finds it: T(eps) = 79 steps there.
constexpr double kBa1MLambda2 = 0.569464;

// The epoch's focus: the stage as `r1 epoch --backend cpu` runs it (parallel rows, stopping at a
// repeated iterate, which on this graph first comes at step T).
void focus_of_epoch(benchmark::State& st, const r1::Graph& g) {
  r1::FocusOptions opt;
  opt.parallel = true;
  std::uint32_t steps = 0;
  for (auto _ : st) {
    auto f = r1::compute_focus_q32(g, r1::TriKernelParams{}, kBa1MLambda2, {}, opt);
    if (!f.is_ok()) {
      st.SkipWithError(f.status().message().c_str());
      return;
    }
    steps = f->steps;
    benchmark::DoNotOptimize(f->phi.data());
  }
  st.counters["steps"] = steps;
}

// One pass over A_sym's rows: y_i = (sum_k w_k x_(col_k)) >> 32 in wrapping 64-bit arithmetic, rows split as the
// stage splits them (2048 per task), each gather hinted 160 entries ahead into the second-level
// cache (kGatherAhead, fx::gather_hint).
void gather_pass(const r1::Graph& g, const std::vector<std::uint32_t>& w, const std::vector<std::int64_t>& x,
                 std::vector<std::int64_t>& y) {
  constexpr std::uint64_t kAhead = 160;
  const std::uint64_t end = g.col.size();
  tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, g.n, 2048), [&](const tbb::blocked_range<std::uint32_t>& r) {
    for (std::uint32_t i = r.begin(); i < r.end(); ++i) {
      std::uint64_t acc = 0;
      for (std::uint64_t k = g.row_ptr[i]; k < g.row_ptr[i + 1]; ++k) {
        if (k + kAhead < end) r1::fx::gather_hint(x.data() + g.col[k + kAhead]);
        acc += std::uint64_t{w[k]} * static_cast<std::uint64_t>(x[g.col[k]]);
      }
      y[i] = static_cast<std::int64_t>(acc >> 32);
    }
  });
}

void gather_floor(benchmark::State& st, const r1::Graph& g) {
  auto plan = r1::plan_focus_steps(g, r1::TriKernelParams{}, kBa1MLambda2);
  if (!plan.is_ok()) {
    st.SkipWithError(plan.status().message().c_str());
    return;
  }
  // A_sym's weights in four bytes, as the stage stores its shares.
  std::vector<std::uint32_t> w(g.w.size());
  for (std::size_t k = 0; k < w.size(); ++k) w[k] = static_cast<std::uint32_t>(g.w[k]);
  std::vector<std::int64_t> x(g.n, std::int64_t{1} << 28), y(g.n);
  for (auto _ : st) {
    for (std::uint32_t s = 0; s < plan->steps; ++s)
      for (int pass = 0; pass < 8; ++pass) {  // the springs, t_1 and the diffusion, then t_2 .. t_8
        gather_pass(g, w, x, y);
        std::swap(x, y);
      }
    benchmark::DoNotOptimize(x.data());
  }
  st.counters["steps"] = plan->steps;
  st.counters["s_per_step"] = benchmark::Counter(static_cast<double>(plan->steps) * static_cast<double>(st.iterations()),
                                                 benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

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
  benchmark::RegisterBenchmark("BM_FocusQ32_Ba1M_Epoch", [](benchmark::State& st) {
    focus_of_epoch(st, graph(r1::GenKind::kBa, 1000000, 10));
  })->Unit(benchmark::kSecond)->Iterations(1);
  benchmark::RegisterBenchmark("BM_FocusGatherFloor_Ba1M", [](benchmark::State& st) {
    gather_floor(st, graph(r1::GenKind::kBa, 1000000, 10));
  })->Unit(benchmark::kSecond)->Iterations(1);
  benchmark::RegisterBenchmark("BM_FocusF64_Ba1M/parallel:1", [](benchmark::State& st) {
    run_focus<false>(st, graph(r1::GenKind::kBa, 1000000, 10), true);
  })->Unit(benchmark::kSecond)->Iterations(1);
  return true;
}();

}  // namespace
