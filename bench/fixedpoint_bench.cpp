// fixedpoint/ throughput: add_product, Q32 operators, pairwise sums, elementary functions (R1-NUM-012, -030, -040, -051).
// ExactSum::add_product is the inner loop of every dot product; the fp64 tree runs serial and parallel.
#include <benchmark/benchmark.h>

#include <vector>

#include "r1/fixedpoint/counter_rng.hpp"
#include "r1/fixedpoint/elementary.hpp"
#include "r1/fixedpoint/exact_sum.hpp"
#include "r1/fixedpoint/pairwise.hpp"
#include "r1/fixedpoint/q32.hpp"

namespace {

namespace fx = r1::fx;
using fx::Q32;

// Random raws scaled down by `shift` bits so that products and results stay in range.
std::vector<Q32> random_q32(std::size_t n, std::uint64_t seed, int shift) {
  std::vector<Q32> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = Q32{static_cast<std::int64_t>(r1::rng::bits(seed, i, 0)) >> shift};
  return v;
}

std::vector<double> random_doubles(std::size_t n, std::uint64_t seed) {
  std::vector<double> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = r1::rng::uniform_double(seed, i, 0) - 0.5;
  return v;
}

void BM_ExactDot(benchmark::State& st) {
  const auto n = static_cast<std::size_t>(st.range(0));
  const auto a = random_q32(n, 1, 0), b = random_q32(n, 2, 0);
  for (auto _ : st) {
    fx::ExactSum s;
    for (std::size_t i = 0; i < n; ++i) s.add_product(a[i], b[i]);
    benchmark::DoNotOptimize(s);
  }
  st.SetItemsProcessed(static_cast<std::int64_t>(st.iterations() * n));
}
BENCHMARK(BM_ExactDot)->Arg(1 << 12)->Arg(1 << 20);

void BM_Q32MulAdd(benchmark::State& st) {
  const auto n = static_cast<std::size_t>(st.range(0));
  const auto a = random_q32(n, 3, 40), b = random_q32(n, 4, 40);
  for (auto _ : st) {
    Q32 acc{};
    for (std::size_t i = 0; i < n; ++i) acc += a[i] * b[i];  // rounds every product: not canonical, a baseline
    benchmark::DoNotOptimize(acc);
  }
  st.SetItemsProcessed(static_cast<std::int64_t>(st.iterations() * n));
}
BENCHMARK(BM_Q32MulAdd)->Arg(1 << 12);

void BM_Q32Div(benchmark::State& st) {
  const auto a = random_q32(1024, 5, 20), b = random_q32(1024, 6, 8);
  for (auto _ : st) {
    for (std::size_t i = 0; i < a.size(); ++i) benchmark::DoNotOptimize(fx::checked_div(a[i], b[i]));
  }
  st.SetItemsProcessed(static_cast<std::int64_t>(st.iterations() * a.size()));
}
BENCHMARK(BM_Q32Div);

void BM_PairwiseSum(benchmark::State& st) {
  const auto x = random_doubles(static_cast<std::size_t>(st.range(0)), 7);
  for (auto _ : st) benchmark::DoNotOptimize(fx::pairwise_sum(x));
  st.SetItemsProcessed(static_cast<std::int64_t>(st.iterations() * x.size()));
}
BENCHMARK(BM_PairwiseSum)->Arg(1 << 12)->Arg(1 << 20);

void BM_ParallelPairwiseSum(benchmark::State& st) {
  const auto x = random_doubles(static_cast<std::size_t>(st.range(0)), 8);
  for (auto _ : st) benchmark::DoNotOptimize(fx::parallel_pairwise_sum(x));
  st.SetItemsProcessed(static_cast<std::int64_t>(st.iterations() * x.size()));
}
BENCHMARK(BM_ParallelPairwiseSum)->Arg(1 << 20)->UseRealTime();

void BM_SequentialSumBaseline(benchmark::State& st) {
  const auto x = random_doubles(static_cast<std::size_t>(st.range(0)), 7);
  for (auto _ : st) {
    double s = 0.0;
    for (const double v : x) s += v;
    benchmark::DoNotOptimize(s);
  }
  st.SetItemsProcessed(static_cast<std::int64_t>(st.iterations() * x.size()));
}
BENCHMARK(BM_SequentialSumBaseline)->Arg(1 << 20);

// One benchmark per elementary function over 1024 arguments of a typical range.
template <Q32 (*F)(Q32)>
void BM_Elementary(benchmark::State& st) {
  const auto args = random_q32(1024, 9, 27);  // |raw| < 2^36: |x| < 16
  for (auto _ : st) {
    for (const Q32 a : args) benchmark::DoNotOptimize(F(a));
  }
  st.SetItemsProcessed(static_cast<std::int64_t>(st.iterations() * args.size()));
}
Q32 exp_clamped(Q32 x) { return fx::exp(Q32{x.raw / 2}); }
Q32 log_abs(Q32 x) { return fx::log(Q32{x.raw == 0 ? 1 : (x.raw < 0 ? -x.raw : x.raw)}); }
Q32 pow_fixed(Q32 x) { return fx::pow(Q32{(x.raw < 0 ? -x.raw : x.raw) + 1}, Q32::from_decimal("0.75")); }
Q32 atan2_fixed(Q32 x) { return fx::atan2(x, Q32::from_decimal("-0.5")); }
BENCHMARK(BM_Elementary<exp_clamped>)->Name("BM_Exp");
BENCHMARK(BM_Elementary<fx::exp2>)->Name("BM_Exp2");
BENCHMARK(BM_Elementary<log_abs>)->Name("BM_Log");
BENCHMARK(BM_Elementary<pow_fixed>)->Name("BM_Pow");
BENCHMARK(BM_Elementary<fx::sin>)->Name("BM_Sin");
BENCHMARK(BM_Elementary<fx::cos>)->Name("BM_Cos");
BENCHMARK(BM_Elementary<atan2_fixed>)->Name("BM_Atan2");
BENCHMARK(BM_Elementary<fx::tanh>)->Name("BM_Tanh");
BENCHMARK(BM_Elementary<fx::sigmoid>)->Name("BM_Sigmoid");

}  // namespace
