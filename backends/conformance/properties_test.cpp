// Tests of the property library (R1-TEST-050..053): the reference and cpu backends pass
// every property, null fails every one, each self-test backend fails the property that holds
// the contract it breaks, and the library is quiet and reproducible.
#include "r1/conformance/properties.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "r1/backends/registry.hpp"
#include "test_support.hpp"

namespace {

using namespace r1;
using conformance::PropertyOptions;
using conformance::PropertyResult;

std::unique_ptr<backends::Backend> make(const char* name) {
  auto b = backends::make_backend(name);
  EXPECT_TRUE(b.is_ok()) << b.status().message();
  return b.is_ok() ? std::move(*b) : nullptr;
}

const PropertyResult* find(const std::vector<PropertyResult>& results, std::string_view name) {
  for (const auto& r : results)
    if (r.name == name) return &r;
  return nullptr;
}

std::string describe(const std::vector<PropertyResult>& results) {
  std::string s;
  for (const auto& r : results) s += (r.passed ? "PASS " : "FAIL ") + r.name + ": " + r.message + "\n";
  return s;
}

// A failing backend needs few cases: a property stops at its first counterexample.
PropertyOptions few_cases() {
  PropertyOptions o;
  o.tests = 5;
  return o;
}

TEST(ConformanceProperties, ReferencePassesAllQuietly) {
  auto b = make("reference");
  ASSERT_TRUE(b);
  testing::internal::CaptureStdout();
  testing::internal::CaptureStderr();
  const auto results = conformance::check_backend(*b);
  const std::string out = testing::internal::GetCapturedStdout();
  const std::string err = testing::internal::GetCapturedStderr();
  ASSERT_EQ(results.size(), 6u);
  const std::string_view order[] = {conformance::kTopologyProperty, conformance::kPositionsProperty,
                                    conformance::kFocusProperty,    conformance::kLabelsProperty,
                                    conformance::kNestingProperty,  conformance::kPixelProperty};
  for (std::size_t i = 0; i < results.size(); ++i) {
    EXPECT_EQ(results[i].name, order[i]);
    EXPECT_TRUE(results[i].passed) << results[i].name << ": " << results[i].message;
    EXPECT_NE(results[i].message.find("25 cases passed"), std::string::npos) << results[i].message;
  }
  // The reference against itself: bit-exact positions and focus, identical pixels.
  EXPECT_NE(find(results, conformance::kPositionsProperty)->message.find("bit-exact; max deviation 0 R_scene"),
            std::string::npos);
  EXPECT_NE(find(results, conformance::kPixelProperty)->message.find("max mean CIEDE2000 0 "), std::string::npos);
  EXPECT_EQ(out, "");
  EXPECT_EQ(err, "");
}

TEST(ConformanceProperties, CpuPassesAll) {
  auto b = make("cpu");
  ASSERT_TRUE(b);
  const auto results = conformance::check_backend(*b);
  ASSERT_EQ(results.size(), 6u);
  for (const auto& r : results) EXPECT_TRUE(r.passed) << r.name << ": " << r.message;
  // The properties ran the candidate, not only the reference beside it.
  EXPECT_GT(b->calls()[Stage::kHierarchy], 0u);
  EXPECT_GT(b->calls()[Stage::kRender], 0u);
}

TEST(ConformanceProperties, NullFailsEveryProperty) {
  auto b = make("null");
  ASSERT_TRUE(b);
  const auto results = conformance::check_backend(*b, few_cases());
  ASSERT_EQ(results.size(), 6u) << describe(results);
  for (const auto& r : results) {
    EXPECT_FALSE(r.passed) << r.name << ": " << r.message;
    // RapidCheck's counterexample names the graph as the command that makes it.
    EXPECT_NE(r.message.find("r1 gen "), std::string::npos) << r.message;
  }
}

TEST(ConformanceProperties, SelfTestPositionFailsPositions) {
  auto b = make("selftest-position");
  ASSERT_TRUE(b);
  const auto results = conformance::check_backend(*b, few_cases());
  const PropertyResult* r = find(results, conformance::kPositionsProperty);
  ASSERT_NE(r, nullptr);
  EXPECT_FALSE(r->passed) << describe(results);
  EXPECT_NE(r->message.find("positions"), std::string::npos) << r->message;
  // Every position moved by 2e-3 R_scene along +x: that is the deviation reported.
  EXPECT_NE(r->message.find("max deviation 0.002 R_scene"), std::string::npos) << r->message;
}

TEST(ConformanceProperties, SelfTestTopologyFailsTopologyOrLabels) {
  auto b = make("selftest-topology");
  ASSERT_TRUE(b);
  const auto results = conformance::check_backend(*b, few_cases());
  const PropertyResult* topo = find(results, conformance::kTopologyProperty);
  const PropertyResult* labels = find(results, conformance::kLabelsProperty);
  ASSERT_TRUE(topo && labels);
  EXPECT_TRUE(!topo->passed || !labels->passed) << describe(results);
  // The swap keeps positions and focus: those properties still hold.
  EXPECT_TRUE(find(results, conformance::kPositionsProperty)->passed) << describe(results);
  EXPECT_TRUE(find(results, conformance::kFocusProperty)->passed) << describe(results);
}

TEST(ConformanceProperties, SelfTestHueFailsPixels) {
  auto b = make("selftest-hue");
  ASSERT_TRUE(b);
  const auto results = conformance::check_backend(*b, few_cases());
  ASSERT_EQ(results.size(), 6u);
  for (const auto& r : results) {
    if (r.name == conformance::kPixelProperty) {
      EXPECT_FALSE(r.passed) << r.message;
      EXPECT_NE(r.message.find("mean CIEDE2000"), std::string::npos) << r.message;
    } else {
      EXPECT_TRUE(r.passed) << r.name << ": " << r.message;  // the epoch is the reference's
    }
  }
}

// The seed decides the cases: the options' seed, else RC_PARAMS's, else a fixed default. The
// same seed gives the same results; every message names its seed.
TEST(ConformanceProperties, SeedIsFixedByDefaultAndTakenFromOptionsOrRcParams) {
  auto b = make("null");
  ASSERT_TRUE(b);
  PropertyOptions o = few_cases();
  o.pixels = false;
  const auto first = conformance::check_backend(*b, o);
  const auto again = conformance::check_backend(*b, o);
  ASSERT_EQ(first.size(), 5u);
  for (std::size_t i = 0; i < first.size(); ++i) EXPECT_EQ(first[i].message, again[i].message);
  {
    r1::test::ScopedEnv env("RC_PARAMS", "seed=42");
    for (const auto& r : conformance::check_backend(*b, o))
      EXPECT_NE(r.message.find("(seed 42)"), std::string::npos) << r.message;
    o.seed = 7;
    for (const auto& r : conformance::check_backend(*b, o))
      EXPECT_NE(r.message.find("(seed 7)"), std::string::npos) << r.message;
  }
  {
    r1::test::ScopedEnv env("RC_PARAMS", "seed=notanumber");
    o.seed = 0;
    for (const auto& r : conformance::check_backend(*b, o)) {
      EXPECT_FALSE(r.passed);
      EXPECT_NE(r.message.find("RC_PARAMS"), std::string::npos) << r.message;
    }
  }
}

TEST(ConformanceProperties, InvalidOptionsFailEveryPropertyWithAReason) {
  auto b = make("reference");
  ASSERT_TRUE(b);
  PropertyOptions o;
  o.tests = 0;
  const auto results = conformance::check_backend(*b, o);
  ASSERT_EQ(results.size(), 6u);
  for (const auto& r : results) {
    EXPECT_FALSE(r.passed);
    EXPECT_NE(r.message.find("tests"), std::string::npos) << r.message;
  }
  EXPECT_EQ(b->calls().total(), 0u);
}

}  // namespace
