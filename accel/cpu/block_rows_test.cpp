// The cpu backend's operator rows (R1-SPEC-073, R1-BKD-041) against the solver's own
// SpectralOperator<Q32>::apply_block: the same bits for every row, on a graph with a hub longer
// than a lane's flush, with and without the rank-one term (rho > 0), for block entries inside the
// offset range, at its edges and beyond, and for blocks of 1 to 9 columns.
#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "r1/accel/cpu/panel_kernels.hpp"
#include "r1/fixedpoint/counter_rng.hpp"
#include "spectral_test_support.hpp"

namespace r1::accel::cpu {
namespace {

// A star of `spokes` leaves around one hub, a ring through the leaves, and (when `apart`) a
// second component, so that rho > 0 and the rank-one term is present.
Graph hub_graph(int spokes, bool apart) {
  std::vector<spectral_test::Link> links;
  for (int i = 0; i < spokes; ++i) {
    links.emplace_back("hub", "leaf" + std::to_string(i), 1 + i % 5);
    links.emplace_back("leaf" + std::to_string(i), "leaf" + std::to_string((i + 1) % spokes), 1 + i % 3);
  }
  if (apart)
    for (int i = 0; i < 40; ++i) links.emplace_back("far" + std::to_string(i), "far" + std::to_string((i + 1) % 40), 2);
  return spectral_test::from_links(links);
}

// Block entries of about `bits` bits with random signs; a few rows at the offset range's edges
// (-2^51 inside, 2^51 - 1 inside, 2^51 outside) when `edges`. bits = 0: multiples of 2^31 below
// 2^50, so every row's numerator is a multiple of 2^31 and about half the rows round a tie.
std::vector<fx::Q32> block(std::size_t n, std::size_t count, int bits, bool edges, std::uint64_t seed) {
  std::vector<fx::Q32> x(n * count);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t c = 0; c < count; ++c) {
      const std::uint64_t r = rng::bits(seed, i, c);
      x[i * count + c] = bits == 0 ? fx::Q32::from_raw((static_cast<std::int64_t>(r >> 45) - (std::int64_t{1} << 18)) << 31)
                                   : fx::Q32::from_raw(static_cast<std::int64_t>(r >> (64 - bits)) - (std::int64_t{1} << (bits - 1)));
    }
  if (edges && n > 10) {
    x[3 * count] = fx::Q32::from_raw(-(std::int64_t{1} << 51));
    x[5 * count + (count - 1)] = fx::Q32::from_raw((std::int64_t{1} << 51) - 1);
    x[7 * count] = fx::Q32::from_raw(std::int64_t{1} << 51);
  }
  return x;
}

TEST(CpuBlockRows, TheIfmaRowsGiveTheOperatorsRowsBitForBit) {
  if (detect_simd() != Simd::kAvx512Ifma) GTEST_SKIP() << "this CPU has no AVX-512 IFMA; below it the solver's rows run";
  // 4,500 spokes: the hub's row passes two lane flushes (2048 entries) and takes the lane-sum path,
  // the leaves' rows (without the rank-one term) the one-flush path that rounds in the lanes;
  // 40,000: above the size from which blocks of fewer than 8 columns are gathered from a
  // line-aligned copy.
  for (const auto& [spokes, apart] :
       {std::pair{4500, false}, std::pair{4500, true}, std::pair{40000, false}, std::pair{40000, true}}) {
    const Graph g = hub_graph(spokes, apart);
    auto op = spectral_operator_q32(g, SpectralParams{});
    ASSERT_TRUE(op.is_ok()) << op.status().message();
    ASSERT_EQ(op->g.empty(), !apart);
    for (const bool parallel : {false, true}) {
      const std::shared_ptr<spectral::BlockRows> rows = rows_factory(Simd::kAvx512Ifma, parallel)(*op);
      ASSERT_TRUE(rows != nullptr);
      for (const std::size_t count : {std::size_t{1}, std::size_t{7}, std::size_t{9}})
        for (const auto& [bits, edges] : {std::pair{49, false}, std::pair{50, true}, std::pair{53, false}, std::pair{0, false}}) {
          SCOPED_TRACE("spokes " + std::to_string(spokes) + " apart " + std::to_string(apart) + " parallel " + std::to_string(parallel) + " count " +
                       std::to_string(count) + " bits " + std::to_string(bits));
          const std::vector<fx::Q32> x = block(g.n, count, bits, edges, 0xb10c + count + bits);
          std::vector<fx::Q32> want(x.size()), got(x.size());
          op->rows = nullptr;  // the solver's own rows
          op->apply_block(x.data(), count, want.data(), count, count, false);
          op->rows = rows;
          op->apply_block(x.data(), count, got.data(), count, count, parallel);
          for (std::size_t k = 0; k < x.size(); ++k) ASSERT_EQ(got[k].raw, want[k].raw) << "row " << k / count << " column " << k % count;
        }
    }
  }
}

// Line-wide blocks (R1-SPEC-074) read in place, and the filter's fused step (R1-SPEC-075):
// the bits of the solver's own rows followed by the portable recurrence, the entries past the
// block's columns left zero, with and without the rank-one term, with gamma = 0 (p not read).
TEST(CpuBlockRows, LineWideBlocksAndTheFusedFilterStepGiveTheSolversBits) {
  if (detect_simd() != Simd::kAvx512Ifma) GTEST_SKIP() << "this CPU has no AVX-512 IFMA; below it the solver's rows run";
  for (const auto& [spokes, apart] : {std::pair{4500, true}, std::pair{40000, false}}) {
    const Graph g = hub_graph(spokes, apart);
    auto op = spectral_operator_q32(g, SpectralParams{});
    ASSERT_TRUE(op.is_ok()) << op.status().message();
    const std::size_t n = g.n, ld = 8;
    for (const bool parallel : {false, true})
      for (const std::size_t count : {std::size_t{5}, std::size_t{7}})
        for (const double gamma : {0.0, -0.4375}) {
          SCOPED_TRACE("spokes " + std::to_string(spokes) + " parallel " + std::to_string(parallel) + " count " +
                       std::to_string(count) + " gamma " + std::to_string(gamma));
          // x and p with rows of 8 entries on 64-byte lines, zero past count.
          std::vector<fx::Q32> xs(n * ld + 8), ps(n * ld + 8);
          const auto line = [](std::vector<fx::Q32>& v) {
            const auto mis = reinterpret_cast<std::uintptr_t>(v.data()) % 64;
            return v.data() + (mis == 0 ? 0 : (64 - mis) / sizeof(fx::Q32));
          };
          fx::Q32* x = line(xs);
          fx::Q32* p = line(ps);
          const std::vector<fx::Q32> xv = block(n, count, 49, false, 0xf11 + count);
          const std::vector<fx::Q32> pv = block(n, count, 48, false, 0xf12 + count);
          for (std::size_t i = 0; i < n; ++i)
            for (std::size_t c = 0; c < count; ++c) {
              x[i * ld + c] = xv[i * count + c];
              p[i * ld + c] = pv[i * count + c];
            }
          // The solver's own rows on the compact block, then the portable recurrence.
          op->rows = nullptr;
          std::vector<fx::Q32> want_y(n * count), want_p(pv);
          op->apply_block(xv.data(), count, want_y.data(), count, count, false);
          spectral::three_term(n * count, want_y.data(), xv.data(), want_p.data(), 0.8125, -1.0625, gamma, false);
          op->rows = rows_factory(Simd::kAvx512Ifma, parallel, 0)(*op);  // fused at every size
          ASSERT_TRUE(op->rows != nullptr);
          // Strided: y rows 8 apart, the entries past count untouched.
          std::vector<fx::Q32> ys(n * ld + 8, fx::Q32::from_raw(77));
          fx::Q32* y = line(ys);
          op->apply_block(x, ld, y, ld, count, parallel);
          for (std::size_t i = 0; i < n; ++i) {
            for (std::size_t c = 0; c < count; ++c) ASSERT_EQ(y[i * ld + c].raw, want_y[i * count + c].raw) << "row " << i;
            for (std::size_t c = count; c < ld; ++c) ASSERT_EQ(y[i * ld + c].raw, 77) << "row " << i;
          }
          // Fused.
          ASSERT_TRUE(op->apply_three_term(x, ld, p, count, 0.8125, -1.0625, gamma, parallel));
          for (std::size_t i = 0; i < n; ++i) {
            for (std::size_t c = 0; c < count; ++c) ASSERT_EQ(p[i * ld + c].raw, want_p[i * count + c].raw) << "row " << i;
            for (std::size_t c = count; c < ld; ++c) ASSERT_EQ(p[i * ld + c].raw, 0) << "row " << i;
          }
          // A block not on line-wide rows is declined, with nothing written.
          std::vector<fx::Q32> before(ps);
          EXPECT_FALSE(op->apply_three_term(xv.data(), count, ps.data(), count, 0.8125, -1.0625, gamma, parallel));
          EXPECT_EQ(ps, before);
          // Below the default size the rows leave the step to the solver.
          op->rows = rows_factory(Simd::kAvx512Ifma, parallel)(*op);
          EXPECT_FALSE(op->apply_three_term(x, ld, p, count, 0.8125, -1.0625, gamma, parallel));
          EXPECT_EQ(ps, before);
        }
  }
}

TEST(CpuBlockRows, BelowIfmaTheSolversOwnRowsRun) {
  EXPECT_FALSE(static_cast<bool>(rows_factory(Simd::kPortable, true)));
  EXPECT_FALSE(static_cast<bool>(rows_factory(Simd::kAvx2, true)));
}

}  // namespace
}  // namespace r1::accel::cpu
