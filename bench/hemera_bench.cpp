// Hemera throughput (R1-HASH-020..022): permutation (one state, lanes), plain sponge, tree hash
// serial and parallel, hash_many over particle-name-like inputs.
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "r1/fixedpoint/counter_rng.hpp"
#include "r1/fixedpoint/hemera.hpp"

namespace {

namespace hm = r1::hemera;

// A state that changes every iteration, so the benchmark sees the carries of real data rather
// than one input the branch predictors could learn.
hm::State start_state(std::uint64_t seed) {
  hm::State s{};
  for (std::size_t i = 0; i < hm::WIDTH; ++i) s[i] = seed * 0x9E3779B97F4A7C15ull + i * 0xD1B54A32D192ED03ull;
  return s;
}

void BM_Permutation(benchmark::State& st) {
  hm::State s = start_state(1);
  for (auto _ : st) {
    hm::permute(s);
    benchmark::DoNotOptimize(s);
  }
  st.counters["per_state"] = benchmark::Counter(static_cast<double>(st.iterations()),
                                                benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_Permutation);

// permute_many over `lanes` states: one lockstep batch per call; per_state is the time per state.
// Second argument: the AVX-512 rounds (1, where the CPU has them) or the scalar ones (0).
void BM_PermutationLanes(benchmark::State& st) {
  const auto lanes = static_cast<std::size_t>(st.range(0));
  hm::set_vector_rounds(st.range(1) != 0);
  std::vector<hm::State> s(lanes);
  for (std::size_t k = 0; k < lanes; ++k) s[k] = start_state(k + 1);
  for (auto _ : st) {
    hm::permute_many(s);
    benchmark::DoNotOptimize(s.data());
  }
  hm::set_vector_rounds(true);
  st.counters["per_state"] = benchmark::Counter(static_cast<double>(st.iterations() * lanes),
                                                benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_PermutationLanes)->ArgsProduct({{2, 4, 8, 64}, {0, 1}});

void BM_PlainHash(benchmark::State& st) {
  std::vector<std::uint8_t> data(static_cast<std::size_t>(st.range(0)), 0x5A);
  for (auto _ : st) benchmark::DoNotOptimize(hm::hash(data));
  st.SetBytesProcessed(static_cast<std::int64_t>(st.iterations()) * st.range(0));
}
BENCHMARK(BM_PlainHash)->Arg(32)->Arg(4096)->Arg(1 << 20);

// 64 MiB, the size class of a 500k-link snapshot's record stream; second argument: parallel.
void BM_TreeHash(benchmark::State& st) {
  std::vector<std::uint8_t> data(static_cast<std::size_t>(st.range(0)));
  for (std::size_t i = 0; i < data.size(); ++i) data[i] = static_cast<std::uint8_t>((i * 2654435761u) >> 13);
  const bool parallel = st.range(1) != 0;
  hm::set_vector_rounds(st.range(2) != 0);
  for (auto _ : st) benchmark::DoNotOptimize(hm::root_hash(data, parallel));
  hm::set_vector_rounds(true);
  st.SetBytesProcessed(static_cast<std::int64_t>(st.iterations()) * st.range(0));
}
// Third argument: the AVX-512 rounds (1) or the scalar ones (0).
BENCHMARK(BM_TreeHash)->ArgsProduct({{64 << 20}, {0, 1}, {0, 1}})->Unit(benchmark::kMillisecond)->UseRealTime();

// 10^5 names of 8..40 bytes, like the particle names of an edge list.
std::vector<std::string> names() {
  std::vector<std::string> v(100000);
  for (std::size_t i = 0; i < v.size(); ++i) {
    const std::uint64_t r = r1::rng::bits(7, i, 0);
    v[i].resize(8 + r % 33);
    for (std::size_t j = 0; j < v[i].size(); ++j) v[i][j] = static_cast<char>('a' + (r >> (j % 40)) % 26);
  }
  return v;
}

// Second argument: parallel. Items are names.
void BM_HashMany(benchmark::State& st) {
  const auto v = names();
  std::vector<hm::Digest> out(v.size());
  const bool parallel = st.range(0) != 0;
  for (auto _ : st) {
    hm::hash_many(v, out, parallel);
    benchmark::DoNotOptimize(out.data());
  }
  st.SetItemsProcessed(static_cast<std::int64_t>(st.iterations() * v.size()));
}
BENCHMARK(BM_HashMany)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

// The same names one hash() at a time: the path hash_many replaces.
void BM_HashLoop(benchmark::State& st) {
  const auto v = names();
  std::vector<hm::Digest> out(v.size());
  for (auto _ : st) {
    for (std::size_t i = 0; i < v.size(); ++i) out[i] = hm::hash(v[i]);
    benchmark::DoNotOptimize(out.data());
  }
  st.SetItemsProcessed(static_cast<std::int64_t>(st.iterations() * v.size()));
}
BENCHMARK(BM_HashLoop)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
