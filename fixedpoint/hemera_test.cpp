// Hemera v2: published vectors, streaming equivalence, tree shape and domain separation
// (R1-HASH-001..012).
#include "r1/fixedpoint/hemera.hpp"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "test_support.hpp"

namespace {

namespace hm = r1::hemera;
using Bytes = std::vector<std::uint8_t>;

std::span<const std::uint8_t> span_of(const std::string& s) {
  return {reinterpret_cast<const std::uint8_t*>(s.data()), s.size()};
}

nlohmann::json vectors() {
  return nlohmann::json::parse(r1::test::read_file(r1::test::source_dir() / "tests/data/hemera_vectors.json"));
}

TEST(Hemera, PublishedPlainVectors) {
  const auto v = vectors();
  EXPECT_EQ(hm::to_hex(hm::hash("")), v["hash"]["empty"]);
  EXPECT_EQ(hm::to_hex(hm::hash("hello")), v["hash"]["hello"]);
  EXPECT_EQ(hm::to_hex(hm::hash("hemera")), v["hash"]["hemera"]);
}

TEST(Hemera, PublishedTreeVectors) {
  const auto v = vectors();
  EXPECT_EQ(hm::to_hex(hm::root_hash(span_of(""))), v["tree"]["empty"]);
  EXPECT_EQ(hm::to_hex(hm::root_hash(span_of("hello"))), v["tree"]["hello"]);
  const Bytes zeros(4096, 0);
  EXPECT_EQ(hm::to_hex(hm::root_hash(zeros)), v["tree"]["4k_zeros"]);
}

TEST(Hemera, PublishedDeriveKeyVector) {
  const auto v = vectors();
  EXPECT_EQ(hm::to_hex(hm::derive_key("test context", span_of("test material"))), v["derive_key"]["test"]);
}

TEST(Hemera, CommittedVectorsMatchSharedCopy) {
  const auto shared = r1::test::shared_data_dir();
  if (shared.empty()) GTEST_SKIP() << "../shared/data is not beside this checkout";
  EXPECT_EQ(nlohmann::json::parse(r1::test::read_file(shared / "hemera_vectors.json")), vectors());
}

TEST(Hemera, ConstantsMatchSharedTable) {
  const auto shared = r1::test::shared_data_dir();
  if (shared.empty()) GTEST_SKIP() << "../shared/data is not beside this checkout";
  // Regenerating the include from the shared table must give the committed file.
  const std::string cmd = "python3 " + (r1::test::source_dir() / "scripts/gen-hemera-constants.py").string() + " " +
                          (shared / "hemera_constants.tsv").string();
  FILE* p = ::popen(cmd.c_str(), "r");
  ASSERT_NE(p, nullptr);
  std::string out;
  char buf[4096];
  while (std::size_t n = std::fread(buf, 1, sizeof buf, p)) out.append(buf, n);
  ASSERT_EQ(::pclose(p), 0);
  EXPECT_EQ(out, r1::test::read_file(r1::test::source_dir() / "fixedpoint/hemera_constants.inc"));
}

RC_GTEST_PROP(Hemera, StreamingEqualsOneShot, (const Bytes& data)) {
  const std::size_t cut1 = *rc::gen::inRange<std::size_t>(0, data.size() + 1);
  const std::size_t cut2 = *rc::gen::inRange<std::size_t>(cut1, data.size() + 1);
  hm::Hasher h;
  h.update(std::span(data).subspan(0, cut1));
  h.update(std::span(data).subspan(cut1, cut2 - cut1));
  h.update(std::span(data).subspan(cut2));
  RC_ASSERT(h.finalize() == hm::hash(data));
}

TEST(Hemera, PaddingBoundariesAllDiffer) {
  // Lengths around the 56-byte rate and trailing zeros: all digests distinct.
  std::vector<hm::Digest> seen;
  for (std::size_t n : {0, 1, 55, 56, 57, 111, 112, 113}) {
    const Bytes zeros(n, 0);
    seen.push_back(hm::hash(zeros));
  }
  for (std::size_t i = 0; i < seen.size(); ++i)
    for (std::size_t j = i + 1; j < seen.size(); ++j) EXPECT_NE(seen[i], seen[j]) << i << " " << j;
}

TEST(Hemera, DomainsSeparate) {
  const std::string msg = "test data";
  const hm::Digest key{};
  EXPECT_NE(hm::hash(msg), hm::keyed_hash(key, span_of(msg)));
  hm::Digest key2{};
  key2[0] = 1;
  EXPECT_NE(hm::keyed_hash(key, span_of(msg)), hm::keyed_hash(key2, span_of(msg)));
  EXPECT_NE(hm::derive_key("a", span_of(msg)), hm::derive_key("b", span_of(msg)));
  // A single-chunk tree hash is the leaf with the ROOT flag, not the plain hash.
  EXPECT_NE(hm::root_hash(span_of(msg)), hm::hash(msg));
  EXPECT_EQ(hm::root_hash(span_of(msg)), hm::hash_leaf(span_of(msg), 0, true));
}

TEST(Hemera, TreeShapeIsLeftBalanced) {
  // 3 chunks: root = node(node(L0, L1), L2) with ROOT only at the top (tree.md example).
  Bytes data(3 * 4096);
  for (std::size_t i = 0; i < data.size(); ++i) data[i] = static_cast<std::uint8_t>(i * 31 + 7);
  const auto sp = std::span<const std::uint8_t>(data);
  const auto l0 = hm::hash_leaf(sp.subspan(0, 4096), 0, false);
  const auto l1 = hm::hash_leaf(sp.subspan(4096, 4096), 1, false);
  const auto l2 = hm::hash_leaf(sp.subspan(8192, 4096), 2, false);
  EXPECT_EQ(hm::root_hash(sp), hm::hash_node(hm::hash_node(l0, l1, false), l2, true));
  // 5 chunks plus one byte: left subtree holds 4 leaves, the right one the remaining 2.
  Bytes d6(5 * 4096 + 1, 0xAB);
  const auto s6 = std::span<const std::uint8_t>(d6);
  std::vector<hm::Digest> L;
  for (std::size_t i = 0; i < 6; ++i) L.push_back(hm::hash_leaf(s6.subspan(i * 4096, std::min<std::size_t>(4096, d6.size() - i * 4096)), i, false));
  const auto left = hm::hash_node(hm::hash_node(L[0], L[1], false), hm::hash_node(L[2], L[3], false), false);
  EXPECT_EQ(hm::root_hash(s6), hm::hash_node(left, hm::hash_node(L[4], L[5], false), true));
}

TEST(Hemera, TreeHashIndependentOfParallelism) {
  Bytes data(37 * 4096 + 123);
  for (std::size_t i = 0; i < data.size(); ++i) data[i] = static_cast<std::uint8_t>((i * 2654435761u) >> 13);
  EXPECT_EQ(hm::root_hash(data, true), hm::root_hash(data, false));
}

TEST(Hemera, HexRoundTrip) {
  const auto d = hm::hash("hello");
  hm::Digest back{};
  ASSERT_TRUE(hm::from_hex(hm::to_hex(d), back));
  EXPECT_EQ(back, d);
  EXPECT_FALSE(hm::from_hex("zz", back));
  EXPECT_FALSE(hm::from_hex(std::string(64, 'g'), back));
}

}  // namespace
