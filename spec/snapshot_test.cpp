// The 128-byte record layout and the snapshot digest (R1-IN-020..024, R1-IN-040).
#include "r1/spec/snapshot.hpp"
#include "r1/spec/status.hpp"

#include <gtest/gtest.h>

#include <cstring>

namespace {

r1::Snapshot two_links() {
  r1::Snapshot s;
  s.config.tokens[0] = {"w", 1000};
  s.particles = {r1::hemera::hash("a"), r1::hemera::hash("b")};
  s.neurons = {r1::hemera::hash("neuron")};
  r1::Link l;
  l.from = 0;
  l.to = 1;
  l.token = 7;
  l.amount = (static_cast<r1::u128>(0x0102030405060708ull) << 64) | 0x090a0b0c0d0e0f10ull;
  l.valence = -1;
  l.height = 0x1122334455667788ull;
  s.links.push_back(l);
  l.from = 1;
  l.to = 0;
  l.valence = 1;
  s.links.push_back(l);
  return s;
}

TEST(Record, LayoutIsLittleEndianAtDocumentedOffsets) {
  const auto s = two_links();
  std::uint8_t rec[r1::kRecordBytes];
  std::memset(rec, 0xEE, sizeof rec);
  r1::encode_record(s, s.links[0], rec);
  EXPECT_EQ(0, std::memcmp(rec, s.neurons[0].data(), 32));
  EXPECT_EQ(0, std::memcmp(rec + 32, s.particles[0].data(), 32));
  EXPECT_EQ(0, std::memcmp(rec + 64, s.particles[1].data(), 32));
  EXPECT_EQ(rec[96], 7);
  EXPECT_EQ(rec[99], 0);
  EXPECT_EQ(rec[100], 0x10);  // lowest byte of the amount first
  EXPECT_EQ(rec[115], 0x01);
  EXPECT_EQ(rec[116], 0xFF);  // valence -1 as i8
  EXPECT_EQ(rec[117], 0x88);
  EXPECT_EQ(rec[124], 0x11);
  EXPECT_EQ(rec[125] | rec[126] | rec[127], 0);
}

TEST(Record, DigestIsTreeHashOfRecordStream) {
  const auto s = two_links();
  std::vector<std::uint8_t> stream(2 * r1::kRecordBytes);
  r1::encode_record(s, s.links[0], stream.data());
  r1::encode_record(s, s.links[1], stream.data() + r1::kRecordBytes);
  EXPECT_EQ(r1::snapshot_digest(s), r1::hemera::root_hash(stream));
}

TEST(Record, DigestCoversManyChunks) {
  auto s = two_links();
  for (int i = 0; i < 200; ++i) s.links.push_back(s.links[static_cast<std::size_t>(i % 2)]);
  s.links.back().height = 5;
  std::vector<std::uint8_t> stream(s.links.size() * r1::kRecordBytes);
  for (std::size_t i = 0; i < s.links.size(); ++i) r1::encode_record(s, s.links[i], stream.data() + i * r1::kRecordBytes);
  EXPECT_EQ(r1::snapshot_digest(s), r1::hemera::root_hash(stream));
}

TEST(Anchor, FirstMinOf1024AndCount) {
  EXPECT_EQ(r1::anchor_count(0), 0u);
  EXPECT_EQ(r1::anchor_count(7), 7u);
  EXPECT_EQ(r1::anchor_count(1024), 1024u);
  EXPECT_EQ(r1::anchor_count(5040), 1024u);
}

TEST(StatusMessage, ControlBytesAreEscapedSoErrorsStayOneLine) {
  EXPECT_EQ(r1::Status::input("plain\tkey").message(), "plain\tkey");
  EXPECT_EQ(r1::Status::input("o.toml:1: unknown key 'a\nb'").message(), "o.toml:1: unknown key 'a\\x0ab'");
  EXPECT_EQ(r1::Status::output(std::string("\r\x7f", 2)).message(), "\\x0d\\x7f");
  const auto prefixed = r1::Status::input(std::string("x\0y", 3)).with_prefix("f\n: ");
  EXPECT_EQ(prefixed.message(), "f\\x0a: x\\x00y");
  EXPECT_EQ(prefixed.kind(), r1::ErrorKind::kInput);
}

}  // namespace

namespace {

// A Result's status read off a temporary, as R1_TRY(make().status()) does, is a value that
// outlives the temporary (it was once a dangling reference: the suite reader printed garbage).
r1::Result<int> failing() { return r1::Status::input("the message, long enough to live on the heap for sure"); }
r1::Status forward() {
  R1_TRY(failing().status());
  return r1::Status::ok();
}

TEST(ResultStatus, StatusOfATemporaryResultOutlivesIt) {
  const r1::Status s = forward();
  EXPECT_EQ(s.message(), "the message, long enough to live on the heap for sure");
  EXPECT_EQ(s.exit_code(), 2);
}

}  // namespace
