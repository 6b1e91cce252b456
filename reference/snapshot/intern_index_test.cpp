// Interning by first appearance: numbers are stable through growth; find agrees with intern.
#include "r1/reference/intern_index.hpp"

#include <gtest/gtest.h>

#include <map>

#include "r1/fixedpoint/hemera.hpp"

namespace {

TEST(InternIndex, NamesNumberedByFirstAppearanceThroughGrowth) {
  r1::NameIndex idx;
  std::vector<std::string> table;
  std::map<std::string, std::uint32_t> reference;
  // 5000 distinct names seen in a scrambled order, each several times: forces several rebuilds.
  for (std::uint32_t round = 0; round < 3; ++round)
    for (std::uint32_t i = 0; i < 5000; ++i) {
      const std::string name = "n" + std::to_string((i * 7919u) % 5000u);
      const auto [it, inserted] = reference.try_emplace(name, static_cast<std::uint32_t>(reference.size()));
      ASSERT_EQ(idx.intern(name, table), it->second);
    }
  ASSERT_EQ(table.size(), 5000u);
  for (const auto& [name, n] : reference) {
    EXPECT_EQ(table[n], name);
    EXPECT_EQ(idx.find(name, table), static_cast<std::int64_t>(n));
  }
  EXPECT_EQ(idx.find("absent", table), -1);
  const auto rebuilt = r1::NameIndex::over(table);
  EXPECT_EQ(rebuilt.find("n17", table), idx.find("n17", table));
}

TEST(InternIndex, DigestsWithSharedPrefixesStayDistinct) {
  // Ids that agree in their first 8 bytes (the hash) and differ later must not merge.
  r1::IdIndex idx;
  std::vector<r1::IdIndex::key_type> table;
  std::vector<std::array<std::uint8_t, 32>> ids;
  for (std::uint8_t i = 0; i < 200; ++i) {
    std::array<std::uint8_t, 32> id{};
    id[31] = i;
    ids.push_back(id);
    ids.push_back(r1::hemera::hash(std::to_string(i)));
  }
  for (std::size_t k = 0; k < ids.size(); ++k) EXPECT_EQ(idx.intern(ids[k], table), k);
  for (std::size_t k = 0; k < ids.size(); ++k) EXPECT_EQ(idx.intern(ids[k], table), k);
  EXPECT_EQ(table.size(), ids.size());
}

}  // namespace
