// Hemera throughput: the permutation, the plain sponge and the parallel tree hash.
#include <benchmark/benchmark.h>

#include <vector>

#include "r1/fixedpoint/hemera.hpp"

namespace {

void BM_Permutation(benchmark::State& st) {
  r1::hemera::State s{};
  for (auto _ : st) {
    r1::hemera::permute(s);
    benchmark::DoNotOptimize(s);
  }
}
BENCHMARK(BM_Permutation);

void BM_PlainHash(benchmark::State& st) {
  std::vector<std::uint8_t> data(static_cast<std::size_t>(st.range(0)), 0x5A);
  for (auto _ : st) benchmark::DoNotOptimize(r1::hemera::hash(data));
  st.SetBytesProcessed(static_cast<std::int64_t>(st.iterations()) * st.range(0));
}
BENCHMARK(BM_PlainHash)->Arg(32)->Arg(4096)->Arg(1 << 20);

void BM_TreeHash(benchmark::State& st) {
  std::vector<std::uint8_t> data(static_cast<std::size_t>(st.range(0)), 0x5A);
  const bool parallel = st.range(1) != 0;
  for (auto _ : st) benchmark::DoNotOptimize(r1::hemera::root_hash(data, parallel));
  st.SetBytesProcessed(static_cast<std::int64_t>(st.iterations()) * st.range(0));
}
BENCHMARK(BM_TreeHash)->Args({1 << 22, 0})->Args({1 << 22, 1})->UseRealTime();

}  // namespace
