// The epoch directory: round trip, digests, atomic replacement, refusal to clobber, export
// (R1-EPO-010..020).
#include "r1/reference/epoch_io.hpp"
#include "r1/reference/hierarchy.hpp"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;
using r1::Q32;

// A small synthetic epoch with every array filled by a simple rule.
r1::Epoch synthetic(std::size_t n) {
  r1::Epoch e;
  e.source = "synthetic";
  e.snapshot_digest = r1::hemera::hash("snapshot");
  e.links = 3 * n;
  e.components = 1;
  for (std::size_t i = 0; i < n; ++i) {
    e.ids.push_back(r1::hemera::hash("p" + std::to_string(i)));
    e.titles.push_back(i % 3 == 0 ? "title\t" + std::to_string(i) : "");
    // phi raws sum to exactly 2^32 (the hierarchy check requires a focus distribution).
    const std::int64_t share = Q32::kOneRaw / static_cast<std::int64_t>(n);
    e.focus.phi.push_back(Q32::from_raw(i == 0 ? Q32::kOneRaw - share * static_cast<std::int64_t>(n - 1) : share));
    e.frame.position.push_back({Q32::from_int(static_cast<std::int64_t>(i)), Q32::from_raw(-5), Q32::from_decimal("0.25")});
    e.encoding.radius.push_back(Q32::from_raw(static_cast<std::int64_t>(7 * i)));
    e.encoding.luminosity.push_back(Q32::from_raw(static_cast<std::int64_t>(i + 1)));
    e.encoding.hue.push_back(Q32::from_decimal("0.5"));
    e.encoding.saturation.push_back(Q32::one());
    e.encoding.role.push_back(static_cast<r1::Role>(i % 4));
    e.encoding.shape.push_back(static_cast<r1::Shape>(i % 6));
    e.encoding.color.push_back({static_cast<std::uint8_t>(i), 2, 3});
  }
  for (std::size_t k = 0; k < 5; ++k)
    for (std::size_t i = 0; i < n; ++i) e.spectrum.u[k].push_back(Q32::from_raw(static_cast<std::int64_t>(k * 1000 + i) - 50));
  auto h = r1::build_hierarchy(e.frame.position, e.focus.phi, e.encoding.color, e.ids);
  EXPECT_TRUE(h.is_ok()) << h.status().message();
  if (h.is_ok()) e.hierarchy = *h;
  for (std::uint32_t i = 0; i + 1 < n; ++i) e.edges.push_back({i, i + 1, Q32::kOneRaw / (i + 1), i % 2 ? -1 : 0});
  for (std::size_t i = 0; i < n; ++i) e.out_rows.push_back(0x9e3779b97f4a7c15ULL * (i + 1));
  for (std::size_t i = 0; i < n; ++i) e.encoding.betweenness.push_back(0.1 * static_cast<double>(i) + 1.0 / 3.0);
  // The carried image and sums (R1-INC-038): negative numerators and every limb in use.
  e.spectrum.sums_shift = 2;
  for (std::size_t i = 0; i < 5 * n; ++i)
    e.spectrum.image.push_back((i % 2 ? -1 : 1) * ((r1::i128{1} << 90) / static_cast<r1::i128>(i + 1)) - static_cast<r1::i128>(3 * i));
  for (std::size_t c = 0; c < 5; ++c) {
    e.spectrum.sums[c][0].add_term(r1::i128{1} << 120);
    e.spectrum.sums[c][0].add_term(r1::i128{1} << 120);
    e.spectrum.sums[c][1].add_term(-static_cast<r1::i128>(c + 7));
    e.spectrum.sums[c][2].add_term(static_cast<r1::i128>(c));
  }
  e.focus.cyberank = {2, 1, 0};
  e.spectrum.eigenvalues = {0, 0.1, 0.2, 0.3, 0.4, 0.5};
  e.timings = {{"spectral", 1.5}};
  return e;
}

TEST(EpochIo, WriteReadRoundTrip) {
  r1::test::TempDir d;
  const auto e = synthetic(10);
  ASSERT_TRUE(r1::write_epoch(e, d / "ep").is_ok());
  auto back = r1::read_epoch(d / "ep");
  ASSERT_TRUE(back.is_ok()) << back.status().message();
  EXPECT_EQ(back->ids, e.ids);
  EXPECT_EQ(back->titles, e.titles);
  EXPECT_EQ(back->focus.phi, e.focus.phi);
  EXPECT_EQ(back->out_rows, e.out_rows);
  EXPECT_EQ(back->encoding.betweenness, e.encoding.betweenness);  // bit for bit
  EXPECT_EQ(back->frame.position, e.frame.position);
  EXPECT_EQ(back->spectrum.u, e.spectrum.u);
  EXPECT_EQ(back->encoding.role, e.encoding.role);
  EXPECT_EQ(back->encoding.color, e.encoding.color);
  EXPECT_EQ(back->hierarchy.cluster_of, e.hierarchy.cluster_of);
  EXPECT_EQ(r1::hierarchy_bytes(back->hierarchy), r1::hierarchy_bytes(e.hierarchy));
  EXPECT_EQ(back->hierarchy.tau0, e.hierarchy.tau0);
  EXPECT_EQ(back->edges, e.edges);
  EXPECT_EQ(back->spectrum.eigenvalues, e.spectrum.eigenvalues);
  EXPECT_TRUE(back->spectrum.image == e.spectrum.image);
  EXPECT_TRUE(back->spectrum.sums == e.spectrum.sums);
  EXPECT_EQ(back->spectrum.sums_shift, 2);
  // Rewriting what was read gives the same files.
  r1::EpochWriteOptions quiet;
  quiet.timings = false;
  ASSERT_TRUE(r1::write_epoch(*back, d / "again", quiet).is_ok());
  EXPECT_EQ(r1::test::read_file(d / "ep/positions.q32"), r1::test::read_file(d / "again/positions.q32"));
}

TEST(EpochIo, WithoutTimingsEveryByteIsReproducible) {
  r1::test::TempDir d;
  auto e = synthetic(5);
  r1::EpochWriteOptions quiet;
  quiet.timings = false;
  ASSERT_TRUE(r1::write_epoch(e, d / "a", quiet).is_ok());
  e.timings = {{"spectral", 99.0}};
  ASSERT_TRUE(r1::write_epoch(e, d / "b", quiet).is_ok());
  EXPECT_EQ(r1::test::read_file(d / "a/manifest.json"), r1::test::read_file(d / "b/manifest.json"));
  const auto m = nlohmann::json::parse(r1::test::read_file(d / "a/manifest.json"));
  EXPECT_FALSE(m.contains("timings_s"));
  EXPECT_EQ(m["files"]["focus.q32"]["bytes"], 5 * 8);
}

TEST(EpochIo, DigestsAgainstTheEpochBeforeAreTheWholeFilesDigests) {
  // R1-EPO-016: an epoch of 3000 particles (most files several chunks long), read back with its
  // leaves, then a next epoch with a few particles moved and one edge more, written with and
  // without the leaves: the same manifest. Then PREV's positions file is changed on disk after
  // reading: the comparison is with the bytes there, so the digests still hold.
  r1::test::TempDir d;
  r1::EpochWriteOptions quiet;
  quiet.timings = false;
  ASSERT_TRUE(r1::write_epoch(synthetic(3000), d / "prev", quiet).is_ok());
  r1::EpochLeaves leaves;
  auto prev = r1::read_epoch(d / "prev", &leaves);
  ASSERT_TRUE(prev.is_ok()) << prev.status().message();
  EXPECT_EQ(leaves.dir, d / "prev");
  EXPECT_EQ(leaves.leaves.at("positions.q32").size(), (3000u * 24 + 4095) / 4096);
  r1::Epoch next = *prev;
  for (std::size_t i : {5u, 6u, 2500u}) next.frame.position[i][1] = Q32::from_raw(12345);
  next.edges.insert(next.edges.begin() + 101, {100, 2000, Q32::kOneRaw, 0});  // after (100, 101)
  r1::EpochWriteOptions against = quiet;
  against.previous = &leaves;
  ASSERT_TRUE(r1::write_epoch(next, d / "whole", quiet).is_ok());
  ASSERT_TRUE(r1::write_epoch(next, d / "reused", against).is_ok());
  const std::string want = r1::test::read_file(d / "whole/manifest.json");
  EXPECT_EQ(r1::test::read_file(d / "reused/manifest.json"), want);
  std::string pos = r1::test::read_file(d / "prev/positions.q32");
  pos[8 * 24 + 3] ^= 1;
  r1::test::write_file(d / "prev/positions.q32", pos);
  fs::remove(d / "prev/focus.q32");
  ASSERT_TRUE(r1::write_epoch(next, d / "changed", against).is_ok());
  EXPECT_EQ(r1::test::read_file(d / "changed/manifest.json"), want);
}

// The chunk table (R1-EPO-018): a read through it gives every file's tree leaves as hashing every
// chunk does, and each chunk's SHA-256; a next epoch written against those is the same manifest;
// a changed byte anywhere (a file, the table) or a table whose leaves do not make the digest is
// refused, naming the file; a file replaced by add_epoch_file leaves the table's cover.
TEST(EpochIo, TheChunkTableChecksTheFilesAndGivesTheirLeaves) {
  r1::test::TempDir d;
  r1::EpochWriteOptions quiet;
  quiet.timings = false;
  const r1::Epoch prev_epoch = synthetic(3000);
  ASSERT_TRUE(r1::write_epoch(prev_epoch, d / "prev", quiet).is_ok());
  const auto m = nlohmann::json::parse(r1::test::read_file(d / "prev/manifest.json"));
  EXPECT_EQ(m.at("version"), 6);
  // Every file but the table and the manifest, in the table's row order, with its size.
  std::size_t rows = 0;
  for (const auto& entry : m.at("chunked")) {
    const std::string name = entry.at("file");
    EXPECT_NE(name, "files.chunks");
    EXPECT_EQ(entry.at("bytes"), m.at("files").at(name).at("bytes"));
    rows += r1::hemera::leaf_count(entry.at("bytes").get<std::uint64_t>());
  }
  EXPECT_EQ(m.at("chunked").size() + 1, m.at("files").size());
  const std::string table = r1::test::read_file(d / "prev/files.chunks");
  EXPECT_EQ(table.size(), rows * 64);

  r1::EpochLeaves whole, fast;
  ASSERT_TRUE(r1::read_epoch(d / "prev", &whole).is_ok());
  auto prev = r1::read_epoch(d / "prev", &fast, r1::DigestCheck::kChunkTable);
  ASSERT_TRUE(prev.is_ok()) << prev.status().message();
  EXPECT_TRUE(whole.sha.empty());
  EXPECT_EQ(fast.leaves, whole.leaves);
  // The SHA-256s are the chunks' (OpenSSL on each chunk of the file as written).
  const std::string pos = r1::test::read_file(d / "prev/positions.q32");
  ASSERT_EQ(fast.sha.at("positions.q32").size(), (pos.size() + 4095) / 4096);
  for (std::size_t i = 0; i * 4096 < pos.size(); ++i) {
    const auto* at = reinterpret_cast<const std::uint8_t*>(pos.data()) + i * 4096;
    EXPECT_EQ(fast.sha.at("positions.q32")[i], r1::sha256({at, std::min<std::size_t>(4096, pos.size() - i * 4096)})) << i;
  }
  EXPECT_EQ(fast.sha.size() + 1, m.at("files").size());  // the table itself is hashed whole

  // A next epoch against the table's SHA-256s: the manifest of hashing every file whole. PREV's
  // files are not read again: removing one changes nothing.
  r1::Epoch next = *prev;
  for (std::size_t i : {5u, 6u, 2500u}) next.frame.position[i][1] = Q32::from_raw(12345);
  next.edges.insert(next.edges.begin() + 101, {100, 2000, Q32::kOneRaw, 0});
  r1::EpochWriteOptions against = quiet;
  against.previous = &fast;
  fs::copy(d / "prev", d / "spare");
  fs::remove(d / "prev/positions.q32");
  ASSERT_TRUE(r1::write_epoch(next, d / "whole", quiet).is_ok());
  ASSERT_TRUE(r1::write_epoch(next, d / "reused", against).is_ok());
  EXPECT_EQ(r1::test::read_file(d / "reused/manifest.json"), r1::test::read_file(d / "whole/manifest.json"));
  EXPECT_EQ(r1::test::read_file(d / "reused/files.chunks"), r1::test::read_file(d / "whole/files.chunks"));
  fs::remove_all(d / "prev");
  fs::rename(d / "spare", d / "prev");

  auto refused = [&](const std::string& needle) {
    auto r = r1::read_epoch(d / "prev", nullptr, r1::DigestCheck::kChunkTable);
    EXPECT_FALSE(r.is_ok()) << needle;
    if (!r.is_ok()) {
      EXPECT_NE(r.status().message().find(needle), std::string::npos) << r.status().message();
    }
  };
  // A changed byte of a covered file: its chunk's SHA-256 differs.
  std::string changed = pos;
  changed[4096 + 7] ^= 1;
  r1::test::write_file(d / "prev/positions.q32", changed);
  refused("positions.q32: chunk 1 differs from its SHA-256 in files.chunks");
  r1::test::write_file(d / "prev/positions.q32", pos);
  // A changed byte of the table: the table's own digest.
  std::string t = table;
  t[100] ^= 1;
  r1::test::write_file(d / "prev/files.chunks", t);
  refused("files.chunks: Hemera digest differs from the manifest");
  // A table whose leaves are changed and which the manifest lists with its new digest: the leaves
  // no longer merge to the file's digest.
  std::size_t pos_row = 0;
  for (const auto& entry : m.at("chunked")) {
    if (entry.at("file") == "positions.q32") break;
    pos_row += r1::hemera::leaf_count(entry.at("bytes").get<std::uint64_t>());
  }
  t = table;
  t[pos_row * 64 + 32] ^= 1;
  r1::test::write_file(d / "prev/files.chunks", t);
  auto forged = m;
  forged["files"]["files.chunks"]["hemera"] =
      r1::hemera::to_hex(r1::hemera::root_hash({reinterpret_cast<const std::uint8_t*>(t.data()), t.size()}));
  r1::test::write_file(d / "prev/manifest.json", forged.dump(2) + "\n");
  refused("positions.q32: the leaves in files.chunks do not merge to its Hemera digest");
  // A cover list naming a file twice, or rows beyond the table.
  auto twice = forged;
  twice["files"]["files.chunks"]["hemera"] = m.at("files").at("files.chunks").at("hemera");
  twice["chunked"].push_back(twice["chunked"][0]);
  r1::test::write_file(d / "prev/files.chunks", table);
  r1::test::write_file(d / "prev/manifest.json", twice.dump(2) + "\n");
  refused("chunked: ");
  r1::test::write_file(d / "prev/manifest.json", m.dump(2) + "\n");
  ASSERT_TRUE(r1::read_epoch(d / "prev", nullptr, r1::DigestCheck::kChunkTable).is_ok());

  // Replacing a covered file: its entry loses its name and keeps its rows; the file is hashed whole.
  ASSERT_TRUE(r1::add_epoch_file(d / "prev", "radius.q32", r1::test::read_file(d / "prev/radius.q32")).is_ok());
  const auto after = nlohmann::json::parse(r1::test::read_file(d / "prev/manifest.json"));
  std::size_t unnamed = 0;
  for (const auto& entry : after.at("chunked")) unnamed += entry.at("file").is_null();
  EXPECT_EQ(unnamed, 1u);
  EXPECT_EQ(after.at("chunked").size(), m.at("chunked").size());
  r1::EpochLeaves again;
  ASSERT_TRUE(r1::read_epoch(d / "prev", &again, r1::DigestCheck::kChunkTable).is_ok());
  EXPECT_FALSE(again.sha.count("radius.q32"));
  EXPECT_TRUE(again.sha.count("positions.q32"));
  EXPECT_EQ(again.leaves, whole.leaves);
}

TEST(EpochIo, ModifiedOrTruncatedFilesAreRefused) {
  r1::test::TempDir d;
  ASSERT_TRUE(r1::write_epoch(synthetic(6), d / "ep").is_ok());
  std::string pos = r1::test::read_file(d / "ep/positions.q32");
  pos[3] ^= 1;
  r1::test::write_file(d / "ep/positions.q32", pos);
  auto r = r1::read_epoch(d / "ep");
  ASSERT_FALSE(r.is_ok());
  EXPECT_NE(r.status().message().find("positions.q32: Hemera digest differs"), std::string::npos) << r.status().message();
  r1::test::write_file(d / "ep/positions.q32", pos.substr(0, 10));
  r = r1::read_epoch(d / "ep");
  ASSERT_FALSE(r.is_ok());
  EXPECT_NE(r.status().message().find("truncated"), std::string::npos) << r.status().message();
  fs::remove(d / "ep/role.u8");
  EXPECT_FALSE(r1::read_epoch(d / "ep").is_ok());
  EXPECT_FALSE(r1::read_epoch(d / "nothing").is_ok());
}

// The carried sums live in the manifest: a malformed one is refused with the member named.
TEST(EpochIo, MalformedResidualSumsAreRefused) {
  r1::test::TempDir d;
  ASSERT_TRUE(r1::write_epoch(synthetic(6), d / "ep").is_ok());
  const std::string manifest = r1::test::read_file(d / "ep/manifest.json");
  auto m = nlohmann::json::parse(manifest);
  const auto refused = [&](const nlohmann::json& bad, const std::string& what) {
    r1::test::write_file(d / "ep/manifest.json", bad.dump(2));
    auto r = r1::read_epoch(d / "ep");
    ASSERT_FALSE(r.is_ok()) << what;
    EXPECT_NE(r.status().message().find("manifest.json: residual_sums: " + what), std::string::npos) << r.status().message();
  };
  auto bad = m;
  bad["residual_sums"]["sums"][1][2] = "xyz";
  refused(bad, "vector 3: not 48 lower-case hex digits");
  bad = m;
  bad["residual_sums"]["sums"][0][0] = "f" + std::string(47, '0');  // a negative sum of squares
  refused(bad, "vector 2: a negative sum of squares");
  bad = m;
  bad["residual_sums"]["shift"] = 40;
  refused(bad, "a shift of 0..16 and five vectors expected");
  bad = m;
  bad["residual_sums"]["sums"].erase(4);
  refused(bad, "a shift of 0..16 and five vectors expected");
  // The carried sum of phi ln phi (R1-INC-054): 48 hex digits of a sum at most 0.
  const auto plogp = [&](const std::string& hex) {
    auto with = m;
    with["focus"]["plogp"] = hex;
    r1::test::write_file(d / "ep/manifest.json", with.dump(2));
    return r1::read_epoch(d / "ep");
  };
  for (const std::string& hex : {std::string(47, '0') + "1", std::string("xyz"), std::string(48, 'F')}) {
    const auto r = plogp(hex);
    ASSERT_FALSE(r.is_ok()) << hex;
    EXPECT_NE(r.status().message().find("manifest.json: focus.plogp: "), std::string::npos) << r.status().message();
  }
  const auto minus_one = plogp(std::string(48, 'f'));
  ASSERT_TRUE(minus_one.is_ok()) << minus_one.status().message();
  EXPECT_EQ(minus_one->focus.plogp, std::optional<r1::fx::ExactSum>(r1::fx::ExactSum::from_limbs({~0ull, ~0ull, ~0ull})));
  r1::test::write_file(d / "ep/manifest.json", manifest);
  EXPECT_TRUE(r1::read_epoch(d / "ep").is_ok());
}

// A writer that gets the digests right but the content wrong: the semantic checks still refuse it.
TEST(EpochIo, ConsistentDigestsDoNotHideBadEdgesOrHierarchy) {
  r1::test::TempDir d;
  auto e = synthetic(8);
  std::swap(e.edges[0], e.edges[1]);  // out of (p, q) order
  ASSERT_TRUE(r1::write_epoch(e, d / "a").is_ok());
  auto r = r1::read_epoch(d / "a");
  ASSERT_FALSE(r.is_ok());
  EXPECT_NE(r.status().message().find("edges.bin: byte 24: layout edge out of order"), std::string::npos) << r.status().message();

  e = synthetic(8);
  e.spectrum.image[7] = r1::i128{1} << 100;  // no image r1 computes reaches 2^94
  ASSERT_TRUE(r1::write_epoch(e, d / "c").is_ok());
  r = r1::read_epoch(d / "c");
  ASSERT_FALSE(r.is_ok());
  EXPECT_NE(r.status().message().find("image.i128: byte 112: a numerator beyond 2^94"), std::string::npos) << r.status().message();

  e = synthetic(8);
  e.spectrum.u[2][3] = Q32::from_int(3);  // no unit vector has an entry beyond 2
  ASSERT_TRUE(r1::write_epoch(e, d / "d").is_ok());
  r = r1::read_epoch(d / "d");
  ASSERT_FALSE(r.is_ok());
  EXPECT_NE(r.status().message().find("spectral.q32: byte 136: u_4 has an entry beyond 2 (not a unit vector)"), std::string::npos)
      << r.status().message();

  e = synthetic(8);
  e.hierarchy.levels[0][0].hi[0] = Q32::from_int(-100);  // a box that no longer holds its particles
  ASSERT_TRUE(r1::write_epoch(e, d / "b").is_ok());
  r = r1::read_epoch(d / "b");
  ASSERT_FALSE(r.is_ok());
  EXPECT_NE(r.status().message().find("hierarchy.bin: "), std::string::npos) << r.status().message();
}

// records.chunks (R1-EPO-017): read back as written, its leaves bound to the snapshot digest; an
// epoch of version 4 (without it) is read as well.
TEST(EpochIo, RecordChunksAreReadBackAndBoundToTheSnapshotDigest) {
  r1::test::TempDir d;
  auto e = synthetic(6);
  e.links = 100;  // 12,800 bytes of records: four chunks
  for (std::size_t i = 0; i < 4; ++i) {
    e.record_chunks.sha.push_back(r1::sha256(std::span(e.ids[i])));
    e.record_chunks.leaves.push_back(r1::hemera::hash("leaf " + std::to_string(i)));
  }
  e.snapshot_digest = r1::hemera::root_of_leaves(e.record_chunks.leaves);
  ASSERT_TRUE(r1::write_epoch(e, d / "a").is_ok());
  auto r = r1::read_epoch(d / "a");
  ASSERT_TRUE(r.is_ok()) << r.status().message();
  EXPECT_EQ(r->record_chunks.sha, e.record_chunks.sha);
  EXPECT_EQ(r->record_chunks.leaves, e.record_chunks.leaves);
  EXPECT_EQ(r1::test::read_file(d / "a/records.chunks").size(), 4u * 64);
  // Read by themselves (R1-EPO-019): the same rows; none from a directory without the file or
  // with a file that is not whole rows.
  const r1::RecordChunks peeked = r1::peek_record_chunks(d / "a");
  EXPECT_EQ(peeked.sha, e.record_chunks.sha);
  EXPECT_EQ(peeked.leaves, e.record_chunks.leaves);
  EXPECT_TRUE(r1::peek_record_chunks(d / "nothing here").leaves.empty());
  fs::create_directories(d / "cut");
  fs::copy_file(d / "a/manifest.json", d / "cut/manifest.json");
  r1::test::write_file(d / "cut/records.chunks", r1::test::read_file(d / "a/records.chunks").substr(0, 3 * 64 + 5));
  EXPECT_TRUE(r1::peek_record_chunks(d / "cut").leaves.empty());
  EXPECT_TRUE(r1::peek_record_chunks(d / "cut").sha.empty());
  // A whole file the manifest does not list (read_epoch would not read it) gives no rows either.
  r1::test::write_file(d / "cut/records.chunks", r1::test::read_file(d / "a/records.chunks"));
  EXPECT_EQ(r1::peek_record_chunks(d / "cut").leaves, e.record_chunks.leaves);
  auto listed = nlohmann::json::parse(r1::test::read_file(d / "cut/manifest.json"));
  listed["files"].erase("records.chunks");
  r1::test::write_file(d / "cut/manifest.json", listed.dump(2));
  EXPECT_TRUE(r1::peek_record_chunks(d / "cut").leaves.empty());
  r1::test::write_file(d / "cut/manifest.json", "{ not json");
  EXPECT_TRUE(r1::peek_record_chunks(d / "cut").leaves.empty());

  auto other = e;
  other.snapshot_digest = r1::hemera::hash("another snapshot");
  ASSERT_TRUE(r1::write_epoch(other, d / "b").is_ok());
  r = r1::read_epoch(d / "b");
  ASSERT_FALSE(r.is_ok());
  EXPECT_NE(r.status().message().find("records.chunks: its leaves do not combine to the snapshot digest"), std::string::npos)
      << r.status().message();

  other = e;
  other.links = 200;  // seven chunks
  const auto w = r1::write_epoch(other, d / "c");
  ASSERT_FALSE(w.is_ok());
  EXPECT_NE(w.message().find("4 record chunks for 200 links"), std::string::npos) << w.message();

  // Versions 4 and 5: no files.chunks (R1-EPO-018), every file hashed even where the table
  // would be used; version 4 without records.chunks as well. Version 3 is refused.
  ASSERT_TRUE(r1::write_epoch(synthetic(6), d / "v4").is_ok());
  EXPECT_FALSE(fs::exists(d / "v4/records.chunks"));
  auto m = nlohmann::json::parse(r1::test::read_file(d / "v4/manifest.json"));
  EXPECT_EQ(m["version"], 6);
  m["files"].erase("files.chunks");
  m.erase("chunked");
  fs::remove(d / "v4/files.chunks");
  for (const int version : {5, 4}) {
    m["version"] = version;
    r1::test::write_file(d / "v4/manifest.json", m.dump(2));
    r1::EpochLeaves leaves;
    r = r1::read_epoch(d / "v4", &leaves, r1::DigestCheck::kChunkTable);
    ASSERT_TRUE(r.is_ok()) << r.status().message();
    EXPECT_TRUE(r->record_chunks.leaves.empty());
    EXPECT_TRUE(leaves.sha.empty());
    EXPECT_EQ(leaves.leaves.size(), m["files"].size());
  }
  m["version"] = 3;
  r1::test::write_file(d / "v4/manifest.json", m.dump(2));
  r = r1::read_epoch(d / "v4");
  ASSERT_FALSE(r.is_ok());
  EXPECT_NE(r.status().message().find("epoch version 3 is not supported (r1 reads versions 4 to 6)"), std::string::npos)
      << r.status().message();
}

TEST(EpochIo, ReplacesAnEpochButNeverOtherDirectories) {
  r1::test::TempDir d;
  ASSERT_TRUE(r1::write_epoch(synthetic(4), d / "ep").is_ok());
  ASSERT_TRUE(r1::write_epoch(synthetic(8), d / "ep").is_ok());  // atomic exchange
  auto r = r1::read_epoch(d / "ep");
  ASSERT_TRUE(r.is_ok());
  EXPECT_EQ(r->ids.size(), 8u);
  fs::create_directory(d / "mine");
  r1::test::write_file(d / "mine/notes.txt", "precious");
  const auto s = r1::write_epoch(synthetic(4), d / "mine");
  EXPECT_EQ(s.kind(), r1::ErrorKind::kOutput);
  EXPECT_EQ(r1::test::read_file(d / "mine/notes.txt"), "precious");
  // No temporaries left beside the targets.
  for (const auto& entry : fs::directory_iterator(d.path())) EXPECT_NE(entry.path().filename().string()[0], '.');
}

TEST(EpochIo, ExportHasTheDocumentedColumns) {
  const auto e = synthetic(3);
  const std::string tsv = r1::export_tsv(e);
  EXPECT_EQ(tsv.substr(0, tsv.find('\n')),
            "particle\ttitle\tx\ty\tz\tu5\tu6\tfocus\tradius\tluminosity\thue\tsaturation\trole\tcluster0\tcluster1\tcluster2\tcluster3");
  const std::string row0 = tsv.substr(tsv.find('\n') + 1, tsv.find('\n', tsv.find('\n') + 1) - tsv.find('\n') - 1);
  EXPECT_EQ(row0.rfind(r1::hemera::to_hex(e.ids[0]) + "\ttitle\\t0\t0\t", 0), 0u) << row0;
  EXPECT_NE(row0.find("\tnone\t0\t0\t0\t0"), std::string::npos) << row0;
}

}  // namespace
