// The anchor file: exact layout, round trip, digest, and every malformed case with its byte offset (R1-FRM-020..023).
#include <gtest/gtest.h>

#include <cstring>

#include "r1/reference/frame.hpp"
#include "test_support.hpp"

namespace {

using r1::Q32;

r1::Anchor sample(std::size_t count) {
  r1::Anchor a;
  for (std::size_t i = 0; i < count; ++i) {
    r1::AnchorEntry e;
    e.id = r1::hemera::hash("particle " + std::to_string(i));
    e.position = {Q32::from_raw(static_cast<std::int64_t>(i) * 12345 - 7), Q32::from_int(-1000), Q32::from_raw(-1)};
    a.entries.push_back(e);
  }
  return a;
}

std::vector<std::uint8_t> bytes_of(const std::string& s) { return {s.begin(), s.end()}; }

std::string parse_error(const std::vector<std::uint8_t>& b) {
  auto r = r1::parse_anchor(b, "a.anchor");
  EXPECT_FALSE(r.is_ok());
  EXPECT_EQ(r.status().kind(), r1::ErrorKind::kInput);
  return r.status().message();
}

TEST(AnchorFile, ExactLayout) {
  const auto a = sample(2);
  auto b = r1::anchor_bytes(a);
  ASSERT_TRUE(b.is_ok()) << b.status().message();
  ASSERT_EQ(b->size(), 16u + 2 * 56u);
  EXPECT_EQ(b->substr(0, 8), "R1ANCHOR");
  const auto* u = reinterpret_cast<const std::uint8_t*>(b->data());
  EXPECT_EQ(u[8], 1);  // version 1, little-endian
  EXPECT_EQ(u[9] | u[10] | u[11], 0);
  EXPECT_EQ(u[12], 2);  // count
  EXPECT_EQ(std::memcmp(u + 16, a.entries[0].id.data(), 32), 0);
  // Entry 0, y = -1000: raw -1000 * 2^32 as i64 little-endian.
  std::int64_t y = 0;
  std::memcpy(&y, u + 16 + 32 + 8, 8);
  EXPECT_EQ(y, -1000 * Q32::kOneRaw);
  // Entry 1, z = raw -1: eight 0xFF bytes.
  for (int k = 0; k < 8; ++k) EXPECT_EQ(u[16 + 56 + 48 + k], 0xFF);
}

TEST(AnchorFile, RoundTripAndDigest) {
  for (std::size_t count : {std::size_t{1}, std::size_t{5}, std::size_t{1024}}) {
    const auto a = sample(count);
    const auto b = r1::anchor_bytes(a);
    ASSERT_TRUE(b.is_ok());
    auto back = r1::parse_anchor(bytes_of(*b), "x");
    ASSERT_TRUE(back.is_ok()) << back.status().message();
    EXPECT_EQ(*back, a);
    const auto d = r1::anchor_digest(a);
    ASSERT_TRUE(d.is_ok());
    EXPECT_EQ(*d, r1::hemera::root_hash(bytes_of(*b)));
  }
}

TEST(AnchorFile, WriteReadThroughFiles) {
  r1::test::TempDir dir;
  const auto a = sample(7);
  const auto path = (dir / "g.anchor").string();
  auto d = r1::write_anchor(a, path);
  ASSERT_TRUE(d.is_ok()) << d.status().message();
  EXPECT_EQ(*d, r1::hemera::root_hash(r1::test::read_bytes(path)));
  auto back = r1::read_anchor(path);
  ASSERT_TRUE(back.is_ok()) << back.status().message();
  EXPECT_EQ(*back, a);
  auto missing = r1::read_anchor((dir / "none.anchor").string());
  EXPECT_FALSE(missing.is_ok());
}

TEST(AnchorFile, MalformedCasesNameFileAndOffset) {
  const auto good = bytes_of(*r1::anchor_bytes(sample(3)));
  {
    auto b = good;
    b.resize(10);
    EXPECT_NE(parse_error(b).find("a.anchor: byte 10: truncated anchor header"), std::string::npos);
  }
  {
    auto b = good;
    b[3] = 'x';
    EXPECT_NE(parse_error(b).find("a.anchor: byte 0: not an r1 anchor file"), std::string::npos);
  }
  {
    auto b = good;
    b[8] = 2;
    EXPECT_NE(parse_error(b).find("byte 8: unsupported anchor version 2"), std::string::npos);
  }
  {
    auto b = good;
    b[12] = 0;
    EXPECT_NE(parse_error(b).find("byte 12: anchor count 0"), std::string::npos);
    b[12] = 1;
    b[13] = 4;  // 1025
    EXPECT_NE(parse_error(b).find("byte 12: anchor count 1025"), std::string::npos);
  }
  {
    auto b = good;
    b.resize(good.size() - 1);
    EXPECT_NE(parse_error(b).find("byte " + std::to_string(good.size() - 1) + ": truncated: entry 2 of 3"), std::string::npos);
  }
  {
    auto b = good;
    b.push_back(0);
    b.push_back(0);
    EXPECT_NE(parse_error(b).find("byte " + std::to_string(16 + 3 * 56) + ": 2 trailing bytes"), std::string::npos);
  }
  {
    auto b = good;
    const std::size_t off = 16 + 56 + 32 + 16;  // entry 1, z
    const std::int64_t big = (std::int64_t{1} << 52) + 1;
    std::memcpy(b.data() + off, &big, 8);
    EXPECT_NE(parse_error(b).find("byte " + std::to_string(off) + ": anchor coordinate beyond"), std::string::npos);
    const std::int64_t edge = std::int64_t{1} << 52;  // the bound itself is allowed
    std::memcpy(b.data() + off, &edge, 8);
    EXPECT_TRUE(r1::parse_anchor(b, "a").is_ok());
  }
  {
    auto b = good;
    std::memcpy(b.data() + 16 + 2 * 56, b.data() + 16, 32);  // entry 2 repeats entry 0
    EXPECT_NE(parse_error(b).find("byte " + std::to_string(16 + 2 * 56) + ": entry 2 repeats particle id"), std::string::npos);
  }
  // Each message is one line.
  auto b = good;
  b[0] = 0;
  EXPECT_EQ(parse_error(b).find('\n'), std::string::npos);
}

TEST(AnchorFile, WriterRefusesWhatTheReaderWouldRefuse) {
  EXPECT_FALSE(r1::anchor_bytes(r1::Anchor{}).is_ok());
  EXPECT_FALSE(r1::anchor_bytes(sample(1025)).is_ok());
  auto dup = sample(3);
  dup.entries[2].id = dup.entries[1].id;
  EXPECT_FALSE(r1::anchor_bytes(dup).is_ok());
  auto far = sample(3);
  far.entries[0].position[1] = Q32::from_int(1 << 21);
  EXPECT_FALSE(r1::anchor_bytes(far).is_ok());
}

TEST(AnchorFile, MakeAnchorTakesTheFirstParticles) {
  r1::Snapshot s;
  r1::Frame f;
  for (int i = 0; i < 1500; ++i) {
    s.particles.push_back(r1::hemera::hash("p" + std::to_string(i)));
    f.position.push_back({Q32::from_int(i), Q32::from_int(-i), Q32::zero()});
  }
  const auto a = r1::make_anchor(s, f);
  ASSERT_EQ(a.entries.size(), 1024u);
  EXPECT_EQ(a.entries[1023].id, s.particles[1023]);
  EXPECT_EQ(a.entries[1023].position[0], Q32::from_int(1023));
  s.particles.resize(3);
  EXPECT_EQ(r1::make_anchor(s, f).entries.size(), 3u);
}

}  // namespace
