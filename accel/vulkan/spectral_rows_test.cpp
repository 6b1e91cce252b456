// The spectral operator's rows on a Vulkan device against the host's (R1-SPEC-073, R1-BKD-071):
// SpectralOperator<Q32>::apply_block with and without the device's rows, bit for bit, on a graph
// with rho = 0 and one with rho > 0 (the rank-one term), blocks of 1, 7 and 11 columns, entries of
// every magnitude up to 58 bits (row sums past 2^128), exact ties of both parities, the same
// refusal of a row outside Q32, and a hub too long for a lavapipe loop declined. Skips without a
// device unless R1_REQUIRE_VULKAN is set.
#include "r1/accel/vulkan_panel.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <random>

#include "device_test_support.hpp"
#include "r1/reference/generate.hpp"
#include "r1/reference/graph_build.hpp"

namespace r1::vk {
namespace {

Graph graph_of(GenKind kind, std::int64_t n) {
  GenParams p;
  p.kind = kind;
  p.n = n;
  auto s = generate(p);
  EXPECT_TRUE(s.is_ok()) << s.status().message();
  auto g = build_graph(*s);
  EXPECT_TRUE(g.is_ok()) << g.status().message();
  return std::move(g).value();
}

// n x count raws, each of a random width up to `bits` and a random sign.
std::vector<fx::Q32> block(std::size_t n, std::size_t count, int bits, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<fx::Q32> x(n * count);
  for (auto& v : x) {
    const int w = static_cast<int>(rng() % static_cast<std::uint64_t>(bits)) + 1;
    const auto mag = static_cast<std::int64_t>(rng() >> (64 - w));
    v = fx::Q32::from_raw((rng() & 1) != 0 ? -mag : mag);
  }
  return x;
}

TEST(VulkanSpectralRows, TheDevicesRowsAreTheHostsBitForBit) {
  R1_NEED_DEVICE(ctx);
  auto factory = rows_factory(ctx);
  ASSERT_TRUE(factory.is_ok()) << factory.status().message();
  for (const auto& [kind, size] : {std::pair{GenKind::kBa, std::int64_t{700}}, std::pair{GenKind::kRmat, std::int64_t{512}}}) {
    const Graph g = graph_of(kind, size);
    SpectralParams params;
    if (kind == GenKind::kRmat) params.rho = 0.75;  // the rank-one term of a regularised operator
    auto host = spectral_operator_q32(g, params);
    ASSERT_TRUE(host.is_ok()) << host.status().message();
    SpectralOperator<fx::Q32> device = *host;
    device.rows = (*factory)(device);
    ASSERT_TRUE(device.rows != nullptr);
    EXPECT_EQ(kind == GenKind::kRmat, !host->g.empty());
    for (const std::size_t count : {std::size_t{1}, std::size_t{7}, std::size_t{11}}) {
      for (const int bits : {50, 58}) {
        const auto x = block(g.n, count, bits, count * 131 + static_cast<std::uint64_t>(bits));
        std::vector<fx::Q32> want(x.size()), got(x.size());
        host->apply_block(x.data(), count, want.data(), count, count);
        device.apply_block(x.data(), count, got.data(), count, count);
        ASSERT_EQ(got, want) << "graph of " << g.n << ", " << count << " columns, " << bits << " bits";
      }
    }
    // Exact ties: one particle's entries odd multiples of 2^31, the rest multiples of 2^32, so
    // every row with an odd M entry in that column sums to 2^31 mod 2^32 and rounds half to
    // even, both ways (the multiples vary the quotient's parity).
    {
      const std::size_t count = 3;
      std::vector<fx::Q32> x(g.n * count), want(x.size()), got(x.size());
      std::mt19937_64 rng(99);
      for (auto& v : x) v = fx::Q32::from_raw(static_cast<std::int64_t>(rng() % 2001) * (std::int64_t{1} << 32) - (std::int64_t{1000} << 32));
      for (std::size_t c = 0; c < count; ++c) x[5 * count + c] = fx::Q32::from_raw(static_cast<std::int64_t>(2 * c + 1) << 31);
      std::size_t ties = 0;
      for (std::uint64_t k = 0; k < g.col.size(); ++k) ties += g.col[k] == 5 && (host->m[k].raw & 1) != 0;
      EXPECT_GT(ties, 0u);
      host->apply_block(x.data(), count, want.data(), count, count);
      device.apply_block(x.data(), count, got.data(), count, count);
      ASSERT_EQ(got, want) << "ties, graph of " << g.n;
    }
    // A row whose result leaves Q32: refused on both.
    std::vector<fx::Q32> x(g.n * 2, fx::Q32::from_raw(std::int64_t{1} << 62)), y(x.size());
    for (std::size_t i = 0; i < x.size(); i += 2) x[i] = fx::Q32::from_raw(-(std::int64_t{1} << 62));
    EXPECT_THROW(host->apply_block(x.data(), 2, y.data(), 2, 2), fx::OverflowError);
    EXPECT_THROW(device.apply_block(x.data(), 2, y.data(), 2, 2), fx::OverflowError);
  }
  // A row longer than a lavapipe loop may run: declined, so the host's rows run that operator.
  const Graph star = graph_of(GenKind::kStar, 70000);
  auto op = spectral_operator_q32(star, SpectralParams{});
  ASSERT_TRUE(op.is_ok());
  EXPECT_EQ((*factory)(*op), nullptr);
}

}  // namespace
}  // namespace r1::vk
