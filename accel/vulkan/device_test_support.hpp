// What accel/vulkan's tests share: the context, or a skip with the reason there is none (a
// failure instead when R1_REQUIRE_VULKAN is set, as `make test` sets it).
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <memory>
#include <string>

#include "r1/accel/vulkan.hpp"

namespace r1::vk::device_test {

inline std::shared_ptr<Context> context_or_skip(std::string& reason) {
  auto ctx = Context::create();
  if (ctx.is_ok()) return std::shared_ptr<Context>(std::move(ctx).value());
  reason = ctx.status().message();
  return nullptr;
}

}  // namespace r1::vk::device_test

// Declares `ctx`, the device's context, or ends the test: skipped with the reason, or failed when
// R1_REQUIRE_VULKAN is set.
#define R1_NEED_DEVICE(ctx)                                                                                     \
  std::string ctx##_reason;                                                                                     \
  auto ctx = ::r1::vk::device_test::context_or_skip(ctx##_reason);                                                     \
  if (!ctx) {                                                                                                   \
    if (std::getenv("R1_REQUIRE_VULKAN") != nullptr) FAIL() << "R1_REQUIRE_VULKAN is set and " << ctx##_reason; \
    GTEST_SKIP() << ctx##_reason;                                                                               \
  }
