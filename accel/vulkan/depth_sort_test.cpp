// The splats' depth sort on a Vulkan device against std::stable_sort (R1-BKD-072): sizes around
// the 256-key blocks, many equal depths (which must stay in index order), depths spread over every
// exponent (every byte of the keys varies) and nearly equal ones (only the low bytes vary), and
// the refusal of a depth that is not positive and finite. Skips without a device unless
// R1_REQUIRE_VULKAN is set.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <limits>
#include <numeric>
#include <random>

#include "device_test_support.hpp"
#include "r1/accel/vulkan.hpp"

namespace r1::vk {
namespace {

std::vector<std::uint32_t> stable_order(const std::vector<double>& d) {
  std::vector<std::uint32_t> o(d.size());
  std::iota(o.begin(), o.end(), 0u);
  std::stable_sort(o.begin(), o.end(), [&d](std::uint32_t a, std::uint32_t b) { return d[a] < d[b]; });
  return o;
}

TEST(VulkanDepthSort, TheDevicesOrderIsTheStableSortOfTheDepths) {
  R1_NEED_DEVICE(ctx);
  auto sort = DepthSort::build(*ctx);
  ASSERT_TRUE(sort.is_ok()) << sort.status().message();
  std::mt19937_64 rng(7);
  for (const std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{2}, std::size_t{255}, std::size_t{256},
                              std::size_t{257}, std::size_t{5000}, std::size_t{65536}, std::size_t{70001}}) {
    for (int kind = 0; kind < 3; ++kind) {
      std::vector<double> d(n);
      for (auto& v : d) {
        if (kind == 0) v = static_cast<double>(1 + rng() % 17);  // many ties
        else if (kind == 1) v = std::ldexp(1.0 + static_cast<double>(rng() % 1000) / 1000, static_cast<int>(rng() % 2000) - 1000);
        else v = 1000.0 + static_cast<double>(rng() % 4096) * 1e-12;  // only the low bytes vary
      }
      auto got = sort->order(d);
      ASSERT_TRUE(got.is_ok()) << got.status().message();
      ASSERT_EQ(*got, stable_order(d)) << n << " depths, kind " << kind;
    }
  }
  for (const double bad : {0.0, -1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    const std::vector<double> d = {1.0, bad, 2.0};
    auto got = sort->order(d);
    ASSERT_FALSE(got.is_ok());
    EXPECT_EQ(got.status().message(), "depth sort: depth 1 is not a positive finite number");
  }
}

}  // namespace
}  // namespace r1::vk
