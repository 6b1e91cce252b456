// Snapshot readers and writers: canonical order, exact weights, round trips (R1-IN-001..024).
#include "r1/reference/snapshot_io.hpp"

#include <cstring>
#include <set>

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <boost/multiprecision/cpp_int.hpp>

#include "r1/reference/graph_container.hpp"
#include "r1/reference/snapshot_builder.hpp"
#include "test_support.hpp"
#include "text_util.hpp"

namespace {

namespace fs = std::filesystem;
using r1::u128;

r1::Snapshot read_text(const std::string& text, const std::string& name) {
  r1::test::TempDir d;
  r1::test::write_file(d / name, text);
  auto r = r1::read_snapshot((d / name).string());
  EXPECT_TRUE(r.is_ok()) << r.status().message();
  return r.is_ok() ? std::move(r).value() : r1::Snapshot{};
}

TEST(EdgeList, CanonicalOrderIsFirstAppearanceSourceBeforeTarget) {
  const auto s = read_text("c\tb\nb\ta\nd\tc\n", "x.tsv");
  ASSERT_EQ(s.names, (std::vector<std::string>{"c", "b", "a", "d"}));
  EXPECT_EQ(s.particles[0], r1::hemera::hash("c"));
  EXPECT_EQ(s.particles[3], r1::hemera::hash("d"));
  EXPECT_EQ(s.links[2].from, 3u);
  EXPECT_EQ(s.links[2].to, 0u);
}

TEST(EdgeList, NamesKeepSpacesAndWeightsAreExact) {
  const auto s = read_text(" a b \tc\t0.5\t-1\nc\t a b \n", "x.tsv");
  ASSERT_EQ(s.names[0], " a b ");
  EXPECT_EQ(s.links[0].amount, u128{1} << 31);
  EXPECT_EQ(s.links[0].valence, -1);
  EXPECT_EQ(s.links[1].amount, u128{1} << 32);  // default weight 1
  EXPECT_EQ(s.links[1].valence, 0);             // no valence data: A2 stays zero
  EXPECT_EQ(s.links[1].to, 0u);
}

TEST(EdgeList, CsvQuotingFollowsRfc4180) {
  const auto s = read_text("\"x, y\",\"say \"\"hi\"\"\"\r\n\"multi\nline\",z,2\n", "q.csv");
  ASSERT_EQ(s.names.size(), 4u);
  EXPECT_EQ(s.names[0], "x, y");
  EXPECT_EQ(s.names[1], "say \"hi\"");
  EXPECT_EQ(s.names[2], "multi\nline");
  EXPECT_EQ(s.links[1].amount, u128{2} << 32);
}

TEST(EdgeList, HeaderOnlyOnTheFirstDataRow) {
  const auto s = read_text("# c\nFrom\tTo\tWeight\nfrom\tto\n", "h.tsv");
  ASSERT_EQ(s.links.size(), 1u);
  EXPECT_EQ(s.names, (std::vector<std::string>{"from", "to"}));
}

TEST(MatrixMarket, SymmetricEntriesGiveBothDirections) {
  const auto s = read_text("%%MatrixMarket matrix coordinate integer symmetric\n3 3 2\n2 1 4\n003 3 1\n", "m.mtx");
  ASSERT_EQ(s.links.size(), 3u);  // 2->1, 1->2, 3->3
  EXPECT_EQ(s.names, (std::vector<std::string>{"2", "1", "3"}));
  EXPECT_EQ(s.links[1].from, 1u);
  EXPECT_EQ(s.links[1].to, 0u);
  EXPECT_EQ(s.links[0].amount, u128{4} << 32);
}

TEST(Weights, ParseExamples) {
  using r1::text::parse_weight;
  EXPECT_EQ(parse_weight("1").amount, u128{1} << 32);
  EXPECT_EQ(parse_weight("+2.5e0").amount, u128{5} << 31);
  EXPECT_EQ(parse_weight(".25").amount, u128{1} << 30);
  EXPECT_EQ(parse_weight("1e2").amount, u128{100} << 32);
  EXPECT_EQ(parse_weight("1E-1").amount, 429496730u);  // 429496729.6 rounds up
  // Exactly half a unit rounds to even: 2^-33 -> 0 (an error), 3 * 2^-33 -> 2 units.
  EXPECT_FALSE(parse_weight("0.00000000011641532182693481445312").error.empty());
  EXPECT_EQ(parse_weight("0.00000000034924596548080444335937").amount, 1u);  // just below 1.5 units
  EXPECT_EQ(parse_weight("0.000000000349245965480804443359375").amount, 2u);  // exactly 1.5 units: even
  EXPECT_EQ(parse_weight("79228162514264337593543950335").amount, ~u128{0} - 0xFFFFFFFFu);  // 2^96 - 1
  EXPECT_NE(parse_weight("79228162514264337593543950336").error, "");                       // 2^96
  for (const char* badw : {"", "-1", "0", "0e5", "nan", "Inf", "1e", "1.2.3", "1,5", "0x1p3", " 1", "1 "})
    EXPECT_FALSE(parse_weight(badw).error.empty()) << badw;
}

RC_GTEST_PROP(Weights, FormatThenParseIsIdentity, ()) {
  const std::uint64_t hi = *rc::gen::inRange<std::uint64_t>(0, std::uint64_t{1} << 32);
  const std::uint64_t lo = *rc::gen::arbitrary<std::uint64_t>();
  const u128 amount = (static_cast<u128>(hi) << 64) | lo;
  RC_PRE(amount > 0);
  const std::string text = r1::text::format_weight(amount);
  const auto back = r1::text::parse_weight(text);
  RC_ASSERT(back.error.empty());
  RC_ASSERT(back.amount == amount);
}

RC_GTEST_PROP(Weights, ParseMatchesCppIntRounding, ()) {
  // value = m / 10^k; amount = round_half_even(m * 2^32 / 10^k), checked independently.
  using boost::multiprecision::cpp_int;
  const std::uint64_t m = *rc::gen::inRange<std::uint64_t>(1, ~std::uint64_t{0} >> 8);
  const int k = *rc::gen::inRange(0, 24);
  std::string digits = std::to_string(m);
  std::string text = k == 0 ? digits : (digits + "e-" + std::to_string(k));
  const cpp_int num = cpp_int(m) << 32, den = boost::multiprecision::pow(cpp_int(10), static_cast<unsigned>(k));
  cpp_int q = num / den;
  const cpp_int r = num - q * den;
  if (r * 2 > den || (r * 2 == den && (q & 1) != 0)) ++q;
  const auto got = r1::text::parse_weight(text);
  if (q == 0) {
    RC_ASSERT(!got.error.empty());
  } else {
    RC_ASSERT(got.error.empty());
    RC_ASSERT(cpp_int(static_cast<std::uint64_t>(got.amount >> 64)) * (cpp_int(1) << 64) +
                  cpp_int(static_cast<std::uint64_t>(got.amount)) == q);
  }
}

TEST(Utf8, RejectsMalformedSequences) {
  using r1::text::find_invalid_utf8;
  EXPECT_FALSE(find_invalid_utf8("plain ascii"));
  EXPECT_FALSE(find_invalid_utf8("\xc3\xa9t\xc3\xa9 \xe2\x82\xac \xf0\x9f\x98\x80"));
  EXPECT_EQ(find_invalid_utf8("ab\x80"), 2u);
  EXPECT_EQ(find_invalid_utf8("\xc0\xaf"), 0u);          // overlong '/'
  EXPECT_EQ(find_invalid_utf8("\xed\xa0\x80"), 0u);      // surrogate
  EXPECT_EQ(find_invalid_utf8("\xf4\x90\x80\x80"), 0u);  // above U+10FFFF
  EXPECT_EQ(find_invalid_utf8("x\xe2\x82"), 1u);         // truncated
}

TEST(GraphFile, CanonicalWriteReadWriteIsStable) {
  auto s = read_text("a\tb\t2\t1\nb\tc\t0.5\t-1\nc\ta\n", "x.tsv");
  s.titles = {"Alpha", "", "Gamma\twith tab"};
  const std::string bytes = r1::graph_file_bytes(s, "x");
  r1::test::TempDir d;
  r1::test::write_file(d / "x.graph", bytes);
  auto back = r1::read_snapshot((d / "x.graph").string());
  ASSERT_TRUE(back.is_ok()) << back.status().message();
  EXPECT_EQ(r1::snapshot_digest(*back), r1::snapshot_digest(s));
  EXPECT_EQ(back->titles, s.titles);
  EXPECT_EQ(back->particles, s.particles);
  EXPECT_EQ(r1::graph_file_bytes(*back, "x"), bytes);
}

// A snapshot of 70,000 links (past the two-halves threshold of R1-IN-021) numbered serially by
// the builder: ids drawn so that the second half reuses first-half particles and neurons and
// brings new ones, some of them first seen as a link's target.
r1::Snapshot two_halves_snapshot() {
  r1::SnapshotBuilder b("two halves");
  r1::Snapshot& s = b.snapshot();
  s.config = r1::text_input_config();
  s.config.block = 1000;
  const auto id_of = [](std::uint64_t k, std::uint8_t kind) {
    std::array<std::uint8_t, 32> id{};
    std::uint64_t x = k * 0x9E3779B97F4A7C15ull + kind;
    for (std::size_t w = 0; w < 4; ++w) {
      x ^= x >> 31;
      x *= 0xBF58476D1CE4E5B9ull;
      x ^= x >> 27;
      std::memcpy(id.data() + 8 * w, &x, 8);
    }
    return id;
  };
  constexpr std::uint64_t kLinks = 70000;
  for (std::uint64_t i = 0; i < kLinks; ++i) {
    r1::Link l;
    // Particle ranges grow with i (new ones throughout), and every third link reaches back.
    const std::uint64_t reach = 16 + i / 4;
    l.from = b.particle_by_id(id_of(i % 3 == 0 ? (i * 7919) % reach : reach - 1 - (i % 5), 1));
    l.to = b.particle_by_id(id_of((i * 104729 + 13) % (reach + 3), 1));
    l.neuron = b.neuron_by_id(id_of((i * 31) % (3 + i / 2000), 2));
    l.token = 0;
    l.amount = (u128{1} << 32) + i;
    l.valence = static_cast<std::int8_t>(static_cast<int>(i % 3) - 1);
    l.height = 1 + i / 100;
    b.add_link(l);
  }
  auto r = b.finish();
  EXPECT_TRUE(r.is_ok());
  return std::move(r).value();
}

TEST(GraphReader, TwoHalvesGiveTheSerialNumbering) {
  const r1::Snapshot s = two_halves_snapshot();
  ASSERT_EQ(s.links.size(), 70000u);
  // The second half holds particles and neurons that the first does not.
  std::set<std::uint32_t> first_half;
  for (std::size_t i = 0; i < 35000; ++i) first_half.insert(s.links[i].to);
  std::size_t new_in_second = 0;
  for (std::size_t i = 35000; i < s.links.size(); ++i) new_in_second += first_half.count(s.links[i].to) == 0;
  ASSERT_GT(new_in_second, 1000u);
  ASSERT_GT(s.links.back().neuron, s.links[34999].neuron);
  r1::test::TempDir d;
  const std::string bytes = r1::graph_file_bytes(s, "x");
  r1::test::write_file(d / "x.graph", bytes);
  auto back = r1::read_snapshot((d / "x.graph").string());
  ASSERT_TRUE(back.is_ok()) << back.status().message();
  EXPECT_EQ(back->particles, s.particles);
  EXPECT_EQ(back->neurons, s.neurons);
  ASSERT_EQ(back->links.size(), s.links.size());
  for (std::size_t i = 0; i < s.links.size(); ++i) {
    const r1::Link &a = back->links[i], &e = s.links[i];
    ASSERT_TRUE(a.from == e.from && a.to == e.to && a.neuron == e.neuron && a.amount == e.amount &&
                a.height == e.height && a.valence == e.valence && a.token == e.token)
        << "link " << i;
  }
  EXPECT_EQ(r1::graph_file_bytes(*back, "x"), bytes);
}

TEST(GraphReader, TwoHalvesReportTheFirstBadRecordAsASerialParseWould) {
  const r1::Snapshot s = two_halves_snapshot();
  const std::string bytes = r1::graph_file_bytes(s, "x");
  auto c = r1::parse_container(bytes, "x");
  ASSERT_TRUE(c.is_ok());
  const std::size_t at = c->find("cyberlinks")->offset;
  const auto read_with = [&](const std::vector<std::pair<std::size_t, std::uint8_t>>& pokes) {
    std::string b = bytes;
    for (const auto& [record_byte, value] : pokes) b[at + record_byte] = static_cast<char>(value);
    r1::test::TempDir d;
    r1::test::write_file(d / "x.graph", b);
    auto r = r1::read_snapshot((d / "x.graph").string());
    return r.is_ok() ? std::string("ok") : r.status().message();
  };
  const auto byte = [](std::size_t record, std::size_t field) { return record * 128 + field; };
  // A bad valence in the second half alone, then in both halves: the first half's error wins.
  EXPECT_NE(read_with({{byte(50000, 116), 5}}).find("record 50000: valence 5"), std::string::npos);
  EXPECT_NE(read_with({{byte(50000, 116), 5}, {byte(20000, 126), 1}}).find("record 20000: padding"), std::string::npos);
  // The second half's first record checked against the height of the record before it.
  EXPECT_NE(read_with({{byte(35000, 117), 0}, {byte(35000, 118), 0}}).find("record 35000: block height"), std::string::npos);
  EXPECT_NE(read_with({{byte(35000, 117), 1}, {byte(35000, 118), 0}}).find("record 35000: block height 1 after 350"),
            std::string::npos);
}

TEST(GraphFile, ContainerKeepsEveryByte) {
  const auto path = r1::test::source_dir() / "tests/good_input/extension_section.graph";
  const std::string bytes = r1::test::read_file(path);
  auto c = r1::parse_container(bytes, path.string());
  ASSERT_TRUE(c.is_ok()) << c.status().message();
  EXPECT_EQ(c->serialize(), bytes);
  ASSERT_EQ(c->sections.size(), 5u);
  EXPECT_EQ(c->sections[0].header, "~~~card\n");
  EXPECT_EQ(c->sections[0].body, "# t\r\n");
  EXPECT_EQ(c->sections[3].separator, "\n");
  EXPECT_EQ(c->find("blob")->body, std::string_view("\x00\x01\x02", 3));
  auto s = r1::read_snapshot(path.string());
  ASSERT_TRUE(s.is_ok()) << s.status().message();
  EXPECT_EQ(s->links.size(), 3u);
  EXPECT_EQ(s->config.chain_id, "test");
}

TEST(GraphFile, CrystalSectionRoundTrips) {
  auto s = read_text("a\tb\nb\tc\n", "x.tsv");
  s.crystal = {r1::CrystalTag{0, 3, 1}, r1::CrystalTag{}, r1::CrystalTag{5, 20, 4}};
  r1::test::TempDir d;
  ASSERT_TRUE(r1::write_snapshot(s, (d / "c.graph").string()).is_ok());
  auto back = r1::read_snapshot((d / "c.graph").string());
  ASSERT_TRUE(back.is_ok()) << back.status().message();
  EXPECT_EQ(back->crystal, s.crystal);
}

TEST(SideFiles, TitlesByNameOrHexAndUnknownKeysIgnored) {
  r1::test::TempDir d;
  r1::test::write_file(d / "g.tsv", "a\tb\nb\tc\n");
  r1::test::write_file(d / "t.tsv", "a\tTitle A\n" + r1::hemera::to_hex(r1::hemera::hash("c")) + "\tTitle C\nzzz\tnobody\n");
  r1::ReadOptions o;
  o.titles_path = (d / "t.tsv").string();
  auto s = r1::read_snapshot((d / "g.tsv").string(), o);
  ASSERT_TRUE(s.is_ok()) << s.status().message();
  EXPECT_EQ(s->titles, (std::vector<std::string>{"Title A", "", "Title C"}));
  r1::test::write_file(d / "dup.tsv", "a\tx\na\ty\n");
  o.titles_path = (d / "dup.tsv").string();
  const auto dup = r1::read_snapshot((d / "g.tsv").string(), o);
  ASSERT_FALSE(dup.is_ok());
  EXPECT_NE(dup.status().message().find("dup.tsv:2: second entry"), std::string::npos) << dup.status().message();
}

TEST(Formats, DetectedByExtensionThenContent) {
  EXPECT_EQ(r1::format_from_path("a/b.GRAPH"), r1::SnapshotFormat::kGraph);
  EXPECT_EQ(r1::format_from_path("x.csv"), r1::SnapshotFormat::kCsv);
  EXPECT_EQ(r1::format_from_path("x.mtx"), r1::SnapshotFormat::kMatrixMarket);
  EXPECT_EQ(r1::format_from_path("x"), r1::SnapshotFormat::kAuto);
  const auto tsv = read_text("# c\na b\tc\n", "noext");
  EXPECT_EQ(tsv.names[0], "a b");
  const auto csv = read_text("a,b\n", "noext2");
  EXPECT_EQ(csv.names.size(), 2u);
  const auto mtx = read_text("%%MatrixMarket matrix coordinate pattern general\n2 2 1\n1 2\n", "noext3");
  EXPECT_EQ(mtx.links.size(), 1u);
}

}  // namespace
