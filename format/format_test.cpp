// Tests of the format library (R1-FMT-001..020): the little-endian codec against hand-written
// bytes, the bounds-checked reader's errors, and round trips of the arrays and golden files.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "r1/format/arrays.hpp"
#include "r1/format/bytes.hpp"
#include "r1/format/golden.hpp"
#include "r1/format/hierarchy.hpp"

namespace {

using r1::fx::Q32;
namespace format = r1::format;

TEST(Bytes, IntegersAreLittleEndianTwosComplement) {
  std::string s;
  format::put_u32(s, 0x04030201u);
  format::put_i64(s, -2);
  format::put_u8(s, 0xAB);
  const std::string want("\x01\x02\x03\x04\xfe\xff\xff\xff\xff\xff\xff\xff\xab", 13);
  EXPECT_EQ(s, want);
  EXPECT_EQ(format::load_u32(s.data()), 0x04030201u);
  EXPECT_EQ(format::load_i64(s.data() + 4), -2);
}

TEST(Bytes, DoublesKeepEveryBit) {
  for (double v : {0.0, -0.0, 1.0 / 3.0, std::numeric_limits<double>::denorm_min(), -1e308}) {
    std::string s;
    format::put_f64(s, v);
    ASSERT_EQ(s.size(), 8u);
    const double back = format::load_f64(s.data());
    EXPECT_EQ(std::signbit(back), std::signbit(v));
    EXPECT_EQ(back, v);
  }
}

TEST(Bytes, TheReaderStopsAtTheEndAndNamesTheOffset) {
  std::string s;
  format::put_u32(s, 7);
  s.push_back('x');
  format::ByteReader r(s, "f.bin", 100);
  std::uint32_t v = 0;
  ASSERT_TRUE(r.u32(v));
  EXPECT_EQ(v, 7u);
  EXPECT_FALSE(r.u32(v));  // one byte left
  EXPECT_EQ(v, 7u);
  EXPECT_EQ(r.offset(), 104u);
  EXPECT_EQ(r.error("truncated").message(), "f.bin: byte 104: truncated");
}

TEST(Arrays, ColumnsRowsAndEdgesRoundTrip) {
  const std::vector<Q32> a = {Q32::from_raw(1), Q32::from_raw(-5), Q32::from_raw(std::int64_t{1} << 40)};
  const std::vector<Q32> b = {Q32::from_raw(2), Q32::from_raw(3), Q32::from_raw(4)};
  EXPECT_EQ(format::read_q32_column(format::q32_column(a), 3), a);
  const std::vector<std::vector<Q32>> cols = {a, b};
  const std::string rows = format::q32_rows(cols, 3);
  EXPECT_EQ(format::read_q32_column(rows, 3, 2, 0), a);
  EXPECT_EQ(format::read_q32_column(rows, 3, 2, 1), b);
  const std::vector<std::vector<std::uint32_t>> u = {{1, 2}, {3, 4}};
  EXPECT_EQ(format::read_u32_column(format::u32_rows(u, 2), 2, 2, 1), (std::vector<std::uint32_t>{3, 4}));
  const std::vector<r1::LayoutEdge> edges = {{0, 1, 5, -5}, {1, 7, 1LL << 32, 0}};
  const std::string eb = format::edge_rows(edges);
  ASSERT_EQ(eb.size(), 2 * format::kEdgeBytes);
  EXPECT_EQ(format::edge_at(eb, 1), edges[1]);
}

TEST(Arrays, Bytes32RowsAreRowMajorAndRoundTrip) {
  std::vector<r1::format::Bytes32> a(3), b(3);
  for (std::size_t i = 0; i < 3; ++i) {
    a[i].fill(static_cast<std::uint8_t>(i));
    b[i].fill(static_cast<std::uint8_t>(0x80 + i));
  }
  const std::span<const r1::format::Bytes32> columns[] = {a, b};
  const std::string bytes = r1::format::bytes32_rows(columns, 3);
  ASSERT_EQ(bytes.size(), 3u * 64);
  EXPECT_EQ(static_cast<std::uint8_t>(bytes[32]), 0x80);  // row 0: a[0], then b[0]
  EXPECT_EQ(static_cast<std::uint8_t>(bytes[64]), 1);
  EXPECT_EQ(r1::format::read_bytes32_column(bytes, 3, 2, 0), a);
  EXPECT_EQ(r1::format::read_bytes32_column(bytes, 3, 2, 1), b);
}

TEST(Golden, PositionBytesRoundTripAndRejectAWrongCount) {
  const std::vector<std::array<Q32, 3>> pos = {{Q32::from_raw(1), Q32::from_raw(-2), Q32::from_raw(3)}};
  const std::string b = format::position_bytes(pos);
  auto back = format::parse_position_bytes(b, "p.bin");
  ASSERT_TRUE(back.is_ok());
  EXPECT_EQ(*back, pos);
  auto bad = format::parse_position_bytes(b.substr(0, b.size() - 1), "p.bin");
  ASSERT_FALSE(bad.is_ok());
  EXPECT_NE(bad.status().message().find("p.bin: byte 0:"), std::string::npos);
}

TEST(Golden, TopologyBytesRoundTripAndNameTheTruncation) {
  r1::Hierarchy h;
  for (int l = 0; l < r1::kLevels; ++l) {
    r1::ClusterNode node;
    node.level = static_cast<std::uint32_t>(l);
    node.children = {0, 1};
    h.levels[l].push_back(node);
    h.cluster_of[l] = {0, 0};
  }
  const std::string b = format::topology_bytes(h);
  auto back = format::parse_topology_bytes(b, "t.bin");
  ASSERT_TRUE(back.is_ok()) << back.status().message();
  EXPECT_EQ(format::topology_bytes(*back), b);
  auto cut = format::parse_topology_bytes(b.substr(0, b.size() - 2), "t.bin");
  ASSERT_FALSE(cut.is_ok());
  EXPECT_NE(cut.status().message().find("truncated topology"), std::string::npos) << cut.status().message();
}

// A hierarchy cut short names the byte where reading stopped, not the start of the file.
TEST(Hierarchy, BytesRoundTripAndTheTruncationNamesItsOffset) {
  r1::Hierarchy h;
  for (int l = 0; l < r1::kLevels; ++l) {
    r1::ClusterNode node;
    node.level = static_cast<std::uint32_t>(l);
    node.children = {0};
    h.levels[l].push_back(node);
    h.cluster_of[l] = {0};
  }
  const std::string b = r1::hierarchy_bytes(h);
  auto back = r1::parse_hierarchy_bytes(b, "h.bin");
  ASSERT_TRUE(back.is_ok()) << back.status().message();
  EXPECT_EQ(r1::hierarchy_bytes(*back), b);
  // 20 bytes: the magic, n, the level count and 4 of level 0's radius; reading stops at byte 16.
  auto cut = r1::parse_hierarchy_bytes(b.substr(0, 20), "h.bin");
  ASSERT_FALSE(cut.is_ok());
  EXPECT_EQ(cut.status().message(), "h.bin: byte 16: truncated hierarchy");
  std::string three = b;
  three[12] = 3;  // the level count, little-endian at bytes 12..15
  auto bad = r1::parse_hierarchy_bytes(three, "h.bin");
  ASSERT_FALSE(bad.is_ok());
  EXPECT_EQ(bad.status().message(), "h.bin: byte 12: hierarchy has 3 levels, r1 reads 4");
}

}  // namespace
