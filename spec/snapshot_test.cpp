// The 128-byte record layout and the snapshot digest (R1-IN-020..024, R1-IN-040).
#include "r1/spec/snapshot.hpp"
#include "r1/spec/status.hpp"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <algorithm>
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

TEST(Sha256, KnownAnswers) {
  // FIPS 180-4's examples (one block, two blocks) and the empty string.
  const auto hex = [](std::string_view t) {
    return r1::hemera::to_hex(r1::sha256(std::span(reinterpret_cast<const std::uint8_t*>(t.data()), t.size())));
  };
  EXPECT_EQ(hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  EXPECT_EQ(hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
}

// A snapshot of `count` links among 50 particles, the fields drawn from `seed` (0 < count).
r1::Snapshot drawn(std::size_t count, std::uint64_t seed) {
  r1::Snapshot s;
  s.config.tokens[0] = {"w", 1000};
  for (int i = 0; i < 50; ++i) s.particles.push_back(r1::hemera::hash("p" + std::to_string(i)));
  s.neurons = {r1::hemera::hash("n0"), r1::hemera::hash("n1")};
  std::uint64_t x = seed;
  const auto next = [&x] {  // splitmix64
    x += 0x9e3779b97f4a7c15ull;
    std::uint64_t z = x;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  };
  for (std::size_t i = 0; i < count; ++i) {
    r1::Link l;
    l.from = static_cast<std::uint32_t>(next() % 50);
    l.to = static_cast<std::uint32_t>(next() % 50);
    l.neuron = static_cast<std::uint32_t>(next() % 2);
    l.amount = next();
    l.height = next() % 1000;
    s.links.push_back(l);
  }
  return s;
}

std::vector<std::uint8_t> stream_of(const r1::Snapshot& s) {
  std::vector<std::uint8_t> stream(s.links.size() * r1::kRecordBytes);
  for (std::size_t i = 0; i < s.links.size(); ++i) r1::encode_record(s, s.links[i], stream.data() + i * r1::kRecordBytes);
  return stream;
}

TEST(RecordChunks, AreEachChunksSha256AndTreeLeaf) {
  for (const std::size_t count : {1u, 32u, 33u, 202u}) {
    const r1::Snapshot s = drawn(count, count);
    const std::vector<std::uint8_t> stream = stream_of(s);
    r1::RecordChunks c;
    EXPECT_EQ(r1::snapshot_digest(s, c), r1::snapshot_digest(s));
    EXPECT_EQ(c.leaves, r1::hemera::tree_leaves(stream));
    ASSERT_EQ(c.sha.size(), c.leaves.size());
    for (std::size_t i = 0; i < c.sha.size(); ++i) {
      const std::size_t off = i * r1::hemera::CHUNK_BYTES;
      EXPECT_EQ(c.sha[i], r1::sha256(std::span(stream).subspan(off, std::min(r1::hemera::CHUNK_BYTES, stream.size() - off))))
          << count << " links, chunk " << i;
    }
  }
}

// The next version of a record stream: links appended (as r1 edit adds them), one removed (every
// later record moves), one changed in place, or the stream cut short.
RC_GTEST_PROP(RecordChunks, DigestFromAnEarlierVersionsChunksIsTheDigest, ()) {
  const std::size_t count = *rc::gen::inRange<std::size_t>(1, 400);
  const r1::Snapshot before = drawn(count, *rc::gen::arbitrary<std::uint64_t>());
  r1::Snapshot now = before;
  const std::size_t at = *rc::gen::inRange<std::size_t>(0, count);
  switch (*rc::gen::inRange(0, 4)) {
    case 0: {
      const r1::Snapshot more = drawn(*rc::gen::inRange<std::size_t>(1, 80), *rc::gen::arbitrary<std::uint64_t>());
      now.links.insert(now.links.end(), more.links.begin(), more.links.end());
      break;
    }
    case 1:
      if (count > 1) now.links.erase(now.links.begin() + static_cast<std::ptrdiff_t>(at));
      break;
    case 2:
      now.links[at].height += 1;
      break;
    default:
      now.links.resize(std::max<std::size_t>(1, at));
  }
  r1::RecordChunks prev, got, own;
  RC_ASSERT(r1::snapshot_digest(before, prev) == r1::snapshot_digest(before));
  const r1::hemera::Digest want = r1::snapshot_digest(now, own);
  RC_ASSERT(r1::snapshot_digest(now, got, &prev) == want);
  RC_ASSERT(want == r1::snapshot_digest(now));
  RC_ASSERT(got.leaves == own.leaves);
  RC_ASSERT(got.sha == own.sha);
}

TEST(RecordChunks, LeavesAreTakenOnlyWhereTheChunksSha256IsTheEarlierOnes) {
  // Stand-in leaves show which were taken: 202 links (7 chunks, the last of 10 records), then 40
  // more (chunk 6 changes, 7 is new) and chunk 2's recorded SHA-256 altered.
  const r1::Snapshot before = drawn(202, 1);
  r1::RecordChunks prev;
  r1::snapshot_digest(before, prev);
  for (std::size_t i = 0; i < prev.leaves.size(); ++i) prev.leaves[i] = r1::hemera::hash("stand-in " + std::to_string(i));
  prev.sha[2][0] ^= 1;
  r1::Snapshot now = before;
  const r1::Snapshot more = drawn(40, 2);
  now.links.insert(now.links.end(), more.links.begin(), more.links.end());
  r1::RecordChunks got, own;
  r1::snapshot_digest(now, got, &prev);
  r1::snapshot_digest(now, own);
  ASSERT_EQ(got.leaves.size(), 8u);
  for (std::size_t i = 0; i < 8; ++i) {
    const bool taken = i < 6 && i != 2;
    EXPECT_EQ(got.leaves[i], taken ? prev.leaves[i] : own.leaves[i]) << "chunk " << i;
  }
  EXPECT_EQ(got.sha, own.sha);
  EXPECT_EQ(got.hashed, 3u);
  EXPECT_EQ(own.hashed, 8u);
  // One chunk on either side: its leaf is the root's and binds that, so it is never taken.
  const r1::Snapshot small = drawn(3, 3);
  r1::RecordChunks one, again;
  r1::snapshot_digest(small, one);
  one.leaves[0] = r1::hemera::hash("stand-in");
  EXPECT_EQ(r1::snapshot_digest(small, again, &one), r1::snapshot_digest(small));
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
