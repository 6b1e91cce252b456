// The spectral solver's kernels on a Vulkan device against the portable ones (R1-BKD-069): the
// inner products and combinations bit for bit on entries of every magnitude up to 63 bits (sums
// beyond 128 bits), ragged row counts, gathered column lists, outputs that are also terms, and
// the same refusals (a bad coefficient, a result outside int64). Skips without a device unless
// R1_REQUIRE_VULKAN is set.
#include "r1/accel/vulkan_panel.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cstdlib>
#include <numeric>

#include "device_test_support.hpp"
#include "panel_cases.hpp"

namespace r1::vk {
namespace {

using spectral::Panel;
using spectral::PanelOps;

Panel<fx::Q32> make_panel(std::size_t n, const std::vector<int>& bits, std::uint64_t seed) { return test::random_panel(n, bits, seed); }

std::vector<std::uint64_t> dots_bits(const PanelOps<fx::Q32>& ops, const Panel<fx::Q32>& p, const std::vector<std::uint32_t>& qs,
                                     const std::vector<std::uint32_t>& ws) {
  std::vector<double> out(qs.size() * ws.size());
  ops.dots(p, qs, ws, out);
  std::vector<std::uint64_t> b;
  for (double d : out) b.push_back(std::bit_cast<std::uint64_t>(d));
  return b;
}

TEST(VulkanPanelKernels, DotsAreThePortableOnesBitForBit) {
  R1_NEED_DEVICE(ctx);
  auto factory = panel_kernel_factory(ctx);
  ASSERT_TRUE(factory.is_ok()) << factory.status().message();
  for (const std::size_t n : {std::size_t{1}, std::size_t{100}, std::size_t{3 * 4096 + 37}}) {
    // Typical basis entries (48-50 bits), wider ones, and 63-bit entries whose sums pass 2^128.
    const std::vector<int> bits = {48, 49, 50, 51, 52, 57, 60, 63, 30, 48, 63};
    const Panel<fx::Q32> p = make_panel(n, bits, 0x5eed + n);
    std::vector<std::uint32_t> all(bits.size());
    std::iota(all.begin(), all.end(), 0u);
    const std::vector<std::uint32_t> block = {0, 1, 2, 9, 10, 4, 3};
    const PanelOps<fx::Q32> portable(n, 20, false, 48);
    const auto ops = (*factory)(n, 20, false, 48);
    SCOPED_TRACE("n = " + std::to_string(n));
    EXPECT_EQ(dots_bits(*ops, p, all, block), dots_bits(portable, p, all, block));
    EXPECT_EQ(dots_bits(*ops, p, {7}, {7, 10}), dots_bits(portable, p, {7}, {7, 10}));
    EXPECT_EQ(dots_bits(*ops, p, block, all), dots_bits(portable, p, block, all));
  }
  Panel<fx::Q32> p(10, 2);
  std::vector<double> out(1);
  EXPECT_THROW((*factory)(9, 4, false, 48)->dots(p, std::vector<std::uint32_t>{0}, std::vector<std::uint32_t>{1}, out),
               std::invalid_argument);
}

TEST(VulkanPanelKernels, CombinationsAreThePortableOnesBitForBit) {
  R1_NEED_DEVICE(ctx);
  auto factory = panel_kernel_factory(ctx);
  ASSERT_TRUE(factory.is_ok()) << factory.status().message();
  for (const std::size_t n : {std::size_t{203}, std::size_t{3 * 4096 + 37}}) {
    std::vector<int> bits(200, 48);
    bits[3] = 51, bits[4] = 50, bits[5] = 60, bits[6] = 30;
    const Panel<fx::Q32> start = make_panel(n, bits, 0xc0ffee + n);
    struct Case {
      std::vector<std::uint32_t> outs, bases, terms;
    };
    std::vector<std::uint32_t> many(189), seventy(70);
    std::iota(many.begin(), many.end(), 7u);
    std::iota(seventy.begin(), seventy.end(), 0u);
    const std::vector<Case> cases = {
        {{0, 1, 2, 3, 4, 5, 6}, {0, 1, 2, 3, 4, 5, 6}, {7, 8, 9, 10, 11, 12, 13, 14, 15, 16}},  // a Gram-Schmidt pass
        {{190, 191, 192}, {}, {0, 1, 2, 3, 4}},                                                  // no bases
        {seventy, {}, many},                                                                     // a thick restart
        {{9, 10}, {11, 12}, {9, 10, 5}},                                                         // outputs are terms
    };
    for (std::size_t ci = 0; ci < cases.size(); ++ci) {
      const Case& k = cases[ci];
      const std::vector<double> coef = test::combine_coefficients(ci, k.terms.size() * k.outs.size());
      Panel<fx::Q32> want = start, got = start;
      PanelOps<fx::Q32>(n, 20, false, 48).combine(want, k.outs, k.bases, k.terms, coef);
      (*factory)(n, 20, false, 48)->combine(got, k.outs, k.bases, k.terms, coef);
      SCOPED_TRACE("n = " + std::to_string(n) + ", case " + std::to_string(ci));
      std::size_t differ = 0;
      for (std::size_t i = 0; i < n; ++i)
        for (std::size_t c = 0; c < got.cols(); ++c) differ += got.at(i, c).raw != want.at(i, c).raw;
      EXPECT_EQ(differ, 0u);
    }
  }
}

// Coefficients of a half and three halves put the remainder exactly on the tie for every odd
// entry: both signs must round to even as the portable kernel does.
TEST(VulkanPanelKernels, ExactTiesRoundToEven) {
  R1_NEED_DEVICE(ctx);
  auto factory = panel_kernel_factory(ctx);
  ASSERT_TRUE(factory.is_ok());
  const Panel<fx::Q32> start = make_panel(1000, {30, 48, 48, 48}, 17);
  const std::vector<std::uint32_t> outs = {1, 2, 3}, bases = {1, 2, 3}, terms = {0};
  for (const bool with_bases : {false, true}) {
    const std::vector<double> coef = {0.5, -1.5, -0.5};
    Panel<fx::Q32> want = start, got = start;
    const std::vector<std::uint32_t> b = with_bases ? bases : std::vector<std::uint32_t>{};
    PanelOps<fx::Q32>(1000, 10, false, 48).combine(want, outs, b, terms, coef);
    (*factory)(1000, 10, false, 48)->combine(got, outs, b, terms, coef);
    std::size_t differ = 0, odd = 0;
    for (std::size_t i = 0; i < 1000; ++i) {
      odd += (start.at(i, 0).raw & 1) != 0;
      for (std::size_t c = 1; c < 4; ++c) differ += got.at(i, c).raw != want.at(i, c).raw;
    }
    EXPECT_EQ(differ, 0u) << (with_bases ? "with bases" : "without bases");
    EXPECT_GT(odd, 400u);  // the ties are there
  }
}

TEST(VulkanPanelKernels, RefusesWhatThePortableKernelsRefuse) {
  R1_NEED_DEVICE(ctx);
  auto factory = panel_kernel_factory(ctx);
  ASSERT_TRUE(factory.is_ok());
  Panel<fx::Q32> p = make_panel(64, {48, 48}, 3);
  const std::vector<std::uint32_t> out = {0}, term = {1};
  EXPECT_THROW((*factory)(64, 6, false, 48)->combine(p, out, out, term, std::vector<double>{8.0}), fx::OverflowError);
  // A combination whose result leaves int64: 7.5 x (2^62 - 1) plus a base near 2^62.
  Panel<fx::Q32> big(3, 2);
  for (std::size_t i = 0; i < 3; ++i) big.at(i, 0) = big.at(i, 1) = fx::Q32::from_raw((std::int64_t{1} << 62) - 1);
  Panel<fx::Q32> portable_big = big;
  EXPECT_THROW(PanelOps<fx::Q32>(3, 2, false, 48).combine(portable_big, out, out, term, std::vector<double>{7.5}),
               fx::OverflowError);
  EXPECT_THROW((*factory)(3, 2, false, 48)->combine(big, out, out, term, std::vector<double>{7.5}), fx::OverflowError);
}

}  // namespace
}  // namespace r1::vk
