// Every committed fuzz corpus replays as an ordinary test (R1-TEST-011): each file of
// fuzz/corpus/<target>/ goes through its target, which aborts on a broken property.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

#include "fuzz_target.hpp"
#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;

class Replay : public testing::TestWithParam<r1::fuzz::Target> {};

TEST_P(Replay, CorpusPasses) {
  const auto target = GetParam();
  const fs::path dir = r1::test::source_dir() / "fuzz" / "corpus" / target.name;
  ASSERT_TRUE(fs::is_directory(dir)) << "no committed corpus for fuzz target " << target.name << " at " << dir;
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.is_regular_file()) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  ASSERT_FALSE(files.empty()) << dir << " is empty";
  for (const auto& f : files) {
    SCOPED_TRACE(f.string());
    const auto bytes = r1::test::read_bytes(f);
    target.fn(bytes.data(), bytes.size());
  }
}

std::string name_of(const testing::TestParamInfo<r1::fuzz::Target>& info) { return info.param.name; }

INSTANTIATE_TEST_SUITE_P(Fuzz, Replay, testing::ValuesIn(r1::fuzz::registry()), name_of);

}  // namespace
