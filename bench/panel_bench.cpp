// The spectral solver's vector kernels on panels shaped as the canonical solver's (R1-SPEC-021:
// b = 7, m = 189, 1 + 5 trivial and locked columns, a continuation and a scratch block: 209
// columns), at one SIMD level of the cpu backend or the portable kernels, on two cores:
//   * Dots: one fused pass's inner products, C = list^T W and G = W^T W (R1-SPEC-023), the list
//     `list` columns long (the trivial, the locked and the basis so far);
//   * Combine: the pass's combination W <- W X - list (C X);
//   * Pass: the two together, as a pass runs them (two sweeps over the panel);
//   * Ritz: the restart's combination of 70 Ritz vectors from the 189 basis columns (R1-SPEC-025).
// Entries are random multiples of 2^-48 of magnitude below 2^3, as unit basis vectors' are
// (R1-SPEC-011). Generation is outside the timed loop. Arguments: rows, list length, SIMD level
// (0 portable, 1 avx2, 2 avx512ifma); levels this CPU lacks are skipped with the reason.
//   * Operator: one block application of L~ to 7 vectors, and OperatorGatherFloor, its gathers
//     alone (below).
#include <benchmark/benchmark.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <numeric>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "r1/accel/cpu/panel_kernels.hpp"
#include "r1/fixedpoint/prefetch.hpp"
#include "r1/fixedpoint/counter_rng.hpp"
#include "r1/reference/generate.hpp"
#include "r1/reference/graph_build.hpp"
#include "r1/solvers/spectral.hpp"

namespace {

using r1::accel::cpu::Simd;
using r1::spectral::Panel;

constexpr std::uint32_t kCols = 209, kW0 = 195, kBlock = 7;

const Panel<r1::fx::Q32>& panel(std::size_t n) {
  static std::size_t made = 0;
  static Panel<r1::fx::Q32> p;
  if (made != n) {
    p = Panel<r1::fx::Q32>(n, kCols);
    for (std::size_t i = 0; i < n; ++i)
      for (std::uint32_t c = 0; c < kCols; ++c)
        p.at(i, c) = r1::fx::Q32::from_raw(static_cast<std::int64_t>(r1::rng::bits(0xbe7c, i, c) >> 13) - (std::int64_t{1} << 50));
    made = n;
  }
  return p;
}

std::vector<std::uint32_t> run(std::uint32_t first, std::size_t count) {
  std::vector<std::uint32_t> v(count);
  std::iota(v.begin(), v.end(), first);
  return v;
}

// A step's list (R1-SPEC-022): the trivial column, the five locked slots in the order of their
// eigenvalues, then basis columns up to the new block: `count` columns. 20 is a first pass's near
// list (the last two blocks), the longer ones a second pass's whole list.
std::vector<std::uint32_t> step_list(std::size_t count) {
  std::vector<std::uint32_t> v = {0, 3, 1, 2, 5, 4};
  const std::vector<std::uint32_t> basis = run(kW0 - static_cast<std::uint32_t>(count - v.size()), count - v.size());
  v.insert(v.end(), basis.begin(), basis.end());
  return v;
}

std::vector<double> coefficients(std::size_t count) {
  std::vector<double> c(count);
  for (std::size_t k = 0; k < count; ++k) c[k] = r1::rng::uniform_double(0xc0ef, k, 0) - 0.5;
  return c;
}

bool setup(benchmark::State& state, Simd& level) {
  level = static_cast<Simd>(state.range(2));
  if (static_cast<int>(level) > static_cast<int>(r1::accel::cpu::detect_simd())) {
    state.SkipWithError("this CPU does not run this SIMD level");
    return false;
  }
  state.SetLabel(std::string(r1::accel::cpu::simd_name(level)));
  return true;
}

// n rows; e and frac as the solver sets them for n (R1-SPEC-011).
std::unique_ptr<r1::spectral::PanelOps<r1::fx::Q32>> kernels(std::size_t n, Simd level) {
  int e = 0;
  while ((std::size_t{1} << e) < n) ++e;
  return r1::accel::cpu::make_panel_kernels(n, e, true, 48, level);
}

void BM_Dots(benchmark::State& state) {
  Simd level;
  if (!setup(state, level)) return;
  const std::size_t n = static_cast<std::size_t>(state.range(0)), nl = static_cast<std::size_t>(state.range(1));
  const Panel<r1::fx::Q32>& p = panel(n);
  const auto ops = kernels(n, level);
  std::vector<std::uint32_t> qs = step_list(nl);
  const std::vector<std::uint32_t> w = run(kW0, kBlock);
  qs.insert(qs.end(), w.begin(), w.end());
  std::vector<double> out(qs.size() * kBlock);
  for (auto _ : state) {
    ops->dots(p, qs, w, out);
    benchmark::DoNotOptimize(out.data());
  }
}

void BM_Combine(benchmark::State& state) {
  Simd level;
  if (!setup(state, level)) return;
  const std::size_t n = static_cast<std::size_t>(state.range(0)), nl = static_cast<std::size_t>(state.range(1));
  Panel<r1::fx::Q32> p = panel(n);
  const auto ops = kernels(n, level);
  const std::vector<std::uint32_t> w = run(kW0, kBlock);
  std::vector<std::uint32_t> terms = w;
  const std::vector<std::uint32_t> list = step_list(nl);
  terms.insert(terms.end(), list.begin(), list.end());
  const std::vector<double> coef = coefficients(terms.size() * kBlock);
  const Panel<r1::fx::Q32>& fresh = panel(n);
  for (auto _ : state) {
    ops->combine(p, w, {}, terms, coef);
    state.PauseTiming();
    for (std::size_t i = 0; i < n; ++i)  // the block's entries back to their magnitude
      for (const std::uint32_t c : w) p.at(i, c) = fresh.at(i, c);
    state.ResumeTiming();
  }
}

void BM_Ritz(benchmark::State& state) {
  Simd level;
  if (!setup(state, level)) return;
  const std::size_t n = static_cast<std::size_t>(state.range(0));
  Panel<r1::fx::Q32> p = panel(n);
  const auto ops = kernels(n, level);
  const std::vector<std::uint32_t> basis = run(6, 189), ritz = run(6, 70);
  std::vector<double> coef = coefficients(189 * 70);
  for (double& c : coef) c *= 0.1;  // an orthogonal matrix's rows: entries well below 1
  for (auto _ : state) {
    ops->combine(p, ritz, {}, basis, coef);
    state.PauseTiming();
    p = panel(n);
    state.ResumeTiming();
  }
}

// The Barabasi-Albert graph (m = 10) of n particles the operator benchmarks share, generated on
// first use and kept (10^6 particles: 10^7 links, a minute), past 10^5 only with R1_BENCH_LARGE=1.
const r1::Graph* ba_graph(benchmark::State& state, std::int64_t n) {
  if (n > 100000 && (std::getenv("R1_BENCH_LARGE") == nullptr || std::string(std::getenv("R1_BENCH_LARGE")) != "1")) {
    state.SkipWithError("set R1_BENCH_LARGE=1 for 10^6 particles");
    return nullptr;
  }
  static std::map<std::int64_t, std::unique_ptr<r1::Graph>> made;
  auto& slot = made[n];
  if (!slot) {
    r1::GenParams gp;
    gp.kind = r1::GenKind::kBa;
    gp.n = n;
    gp.m = 10;
    auto snap = r1::generate(gp);
    auto built = snap.is_ok() ? r1::build_graph(*snap) : r1::Result<r1::Graph>(snap.status());
    if (!built.is_ok()) {
      state.SkipWithError(built.status().message().c_str());
      return nullptr;
    }
    slot = std::make_unique<r1::Graph>(std::move(built).value());
  }
  return slot.get();
}

// The operator's block application (R1-SPEC-073) on a Barabasi-Albert graph (m = 10), 7 vectors
// of unit-vector magnitude, on the cpu backend's IFMA rows (level 2) or the solver's own (0).
// Arguments: particles, block columns, level.
void BM_Operator(benchmark::State& state) {
  Simd level;
  if (!setup(state, level)) return;
  const auto n = static_cast<std::int64_t>(state.range(0));
  const r1::Graph* g = ba_graph(state, n);
  if (g == nullptr) return;
  static const r1::Graph* made = nullptr;
  static std::unique_ptr<r1::SpectralOperator<r1::fx::Q32>> op;
  if (made != g) {
    auto o = r1::spectral_operator_q32(*g, r1::SpectralParams{});
    if (!o.is_ok()) {
      state.SkipWithError(o.status().message().c_str());
      return;
    }
    op = std::make_unique<r1::SpectralOperator<r1::fx::Q32>>(std::move(o).value());
    made = g;
  }
  op->rows = level == Simd::kAvx512Ifma ? std::shared_ptr<r1::spectral::BlockRows>(r1::accel::cpu::rows_factory(level, true)(*op)) : nullptr;
  const auto rows = static_cast<std::size_t>(n), count = static_cast<std::size_t>(state.range(1));
  std::vector<r1::fx::Q32> x(rows * count), y(rows * count);
  for (std::size_t i = 0; i < x.size(); ++i)
    x[i] = r1::fx::Q32::from_raw(static_cast<std::int64_t>(r1::rng::bits(0x0be7, i, 0) >> 15) - (std::int64_t{1} << 48));
  for (auto _ : state) {
    op->apply_block(x.data(), count, y.data(), count, count, true);
    benchmark::DoNotOptimize(y.data());
  }
}

// The floor under a block application on this machine: for every row i the sum of the 64-byte
// rows x_j (eight 64-bit lanes: a compact block of 7 columns padded to 8, R1-SPEC-074) over the
// stored entries j of row i of A_sym, plain 64-bit adds, no weights, no exact sums, no rounding;
// rows streamed and split over the cores as the cpu rows split them, each gather hinted 96
// entries ahead into the second-level cache (accel/cpu/block_rows.cpp). A block application
// gathers one such row per stored entry, so this is what its gathers cost alone. Argument:
// particles.
using Lanes = std::int64_t __attribute__((vector_size(64)));
using FloorBody = void (*)(const r1::Graph&, const std::int64_t*, std::int64_t*, std::uint32_t, std::uint32_t);

// x and y hold 8 lanes a row; loads and stores go through memcpy, so no alignment is assumed.
inline void floor_body(const r1::Graph& g, const std::int64_t* x, std::int64_t* y, std::uint32_t b, std::uint32_t e) {
  constexpr std::uint64_t kAhead = 96;
  const std::uint64_t end = g.col.size();
  for (std::uint32_t i = b; i < e; ++i) {
    Lanes acc = {};
    for (std::uint64_t k = g.row_ptr[i]; k < g.row_ptr[i + 1]; ++k) {
      if (k + kAhead < end) r1::fx::gather_hint(x + std::size_t{8} * g.col[k + kAhead]);
      Lanes v;
      std::memcpy(&v, x + std::size_t{8} * g.col[k], sizeof v);
      acc += v;
    }
    std::memcpy(y + std::size_t{8} * i, &acc, sizeof acc);
  }
}

#if defined(__x86_64__)
// The same loop with 512-bit adds where the CPU has them (one add an entry).
__attribute__((target("avx512f"))) void floor_body_avx512(const r1::Graph& g, const std::int64_t* x, std::int64_t* y,
                                                           std::uint32_t b, std::uint32_t e) {
  floor_body(g, x, y, b, e);
}
#endif

void BM_OperatorGatherFloor(benchmark::State& state) {
  const auto n = static_cast<std::int64_t>(state.range(0));
  const r1::Graph* g = ba_graph(state, n);
  if (g == nullptr) return;
  // Rows on whole cache lines, as the cpu rows copy a large block (one line a gathered row), in
  // blocks from operator new, which the benchmarks share with the r1 command (huge pages).
  const std::size_t entries = std::size_t{8} * g->n;
  std::vector<std::int64_t> xs(entries + 8), ys(entries + 8);
  auto line_start = [](std::vector<std::int64_t>& v) {
    const auto at = reinterpret_cast<std::uintptr_t>(v.data());
    return v.data() + ((64 - at % 64) % 64) / sizeof(std::int64_t);
  };
  std::int64_t* const x = line_start(xs);
  std::int64_t* const y = line_start(ys);
  for (std::size_t i = 0; i < entries; ++i) x[i] = static_cast<std::int64_t>(r1::rng::bits(0x0be7, i, 0) >> 15);
  FloorBody body = floor_body;
#if defined(__x86_64__)
  if (__builtin_cpu_supports("avx512f")) body = floor_body_avx512;
#endif
  for (auto _ : state) {
    // Rows split over the cores in blocks of 4096, as the cpu rows split them.
    tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, g->n, 4096),
                      [&](const tbb::blocked_range<std::uint32_t>& r) { body(*g, x, y, r.begin(), r.end()); });
    benchmark::DoNotOptimize(y);
  }
}

// rows x list length x SIMD level; the list lengths are a first pass's near list and a second
// pass's whole list at a cycle's first and last steps.
void step_args(benchmark::internal::Benchmark* b) {
  for (const long n : {100000L, 1000000L})
    for (const long nl : {20L, 83L, 195L})
      for (const long level : {0L, 1L, 2L}) b->Args({n, nl, level});
}

BENCHMARK(BM_Dots)->Apply(step_args)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Combine)->Apply(step_args)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Operator)->ArgsProduct({{100000L, 1000000L}, {7L}, {0L, 2L}})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_OperatorGatherFloor)->Arg(100000L)->Arg(1000000L)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Ritz)->ArgsProduct({{100000L, 1000000L}, {189L}, {0L, 2L}})->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

}  // namespace
