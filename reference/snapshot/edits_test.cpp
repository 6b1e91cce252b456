// Edit files (spec/edits.md R1-EDT-001..030): parsing, application, order, errors.
#include "r1/reference/edits.hpp"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include "r1/reference/generate.hpp"
#include "r1/reference/snapshot_io.hpp"
#include "test_support.hpp"

namespace {

r1::Snapshot text_snapshot(const std::string& text) {
  r1::test::TempDir d;
  r1::test::write_file(d / "g.tsv", text);
  auto r = r1::read_snapshot((d / "g.tsv").string());
  EXPECT_TRUE(r.is_ok()) << r.status().message();
  return r.is_ok() ? std::move(r).value() : r1::Snapshot{};
}

r1::Result<r1::Snapshot> edit(const r1::Snapshot& s, const std::string& text, r1::EditCounts* c = nullptr) {
  R1_ASSIGN(const auto edits, r1::parse_edits(text, "e.txt"));
  return r1::apply_edits(s, edits, "e.txt", c);
}

// The snapshot an edge list with these rows reads as: the oracle for every applied edit.
std::string rows(const r1::Snapshot& s) {
  std::string o;
  for (const r1::Link& l : s.links)
    o += s.names[l.from] + "\t" + s.names[l.to] + "\t" + std::to_string(static_cast<std::uint64_t>(l.amount >> 32)) + "\n";
  return o;
}

TEST(Edits, ApplyAsTheEdgeListWithTheEditsMadeByHand) {
  const auto s = text_snapshot("a\tb\na\tc\t2\nb\tc\nc\td\nd\ta\n");
  r1::EditCounts c;
  auto r = edit(s, "# a batch\n\nadd\td\te\t5\nremove\ta\tc\nreweight\tb\tc\t3\nadd\te\tb\n", &c);
  ASSERT_TRUE(r.is_ok()) << r.status().message();
  const auto want = text_snapshot("a\tb\nb\tc\t3\nc\td\nd\ta\nd\te\t5\ne\tb\n");
  EXPECT_EQ(r->names, want.names);
  EXPECT_EQ(r->particles, want.particles);
  EXPECT_EQ(rows(*r), rows(want));
  EXPECT_EQ(r1::snapshot_digest(*r), r1::snapshot_digest(want));
  EXPECT_EQ(c.added, 2u);
  EXPECT_EQ(c.removed, 1u);
  EXPECT_EQ(c.reweighted, 1u);
  EXPECT_EQ(c.new_particles, 1u);
  EXPECT_EQ(c.dropped_particles, 0u);
}

TEST(Edits, RemovalRenumbersByFirstAppearanceAndDropsLinklessParticles) {
  // c first appears in the removed link: it moves behind d; e loses its only link.
  const auto s = text_snapshot("a\tc\na\tb\nb\tc\nd\tb\ne\ta\n");
  r1::EditCounts c;
  auto r = edit(s, "remove\ta\tc\nremove\te\ta\n", &c);
  ASSERT_TRUE(r.is_ok()) << r.status().message();
  EXPECT_EQ(r->names, (std::vector<std::string>{"a", "b", "c", "d"}));
  EXPECT_EQ(c.dropped_particles, 1u);
  EXPECT_EQ(c.links_removed, 2u);
}

TEST(Edits, ParallelLinksAreRemovedTogetherAndReweightKeepsTheFirst) {
  const auto s = text_snapshot("a\tb\t1\nb\tc\na\tb\t2\nb\ta\t7\n");
  auto r = edit(s, "reweight\ta\tb\t4\n");
  ASSERT_TRUE(r.is_ok()) << r.status().message();
  EXPECT_EQ(rows(*r), "a\tb\t4\nb\tc\t1\nb\ta\t7\n");  // the reverse direction is another pair
  auto r2 = edit(s, "remove\ta\tb\n");
  ASSERT_TRUE(r2.is_ok());
  EXPECT_EQ(rows(*r2), "b\tc\t1\nb\ta\t7\n");
}

TEST(Edits, EachEditSeesTheOnesBefore) {
  const auto s = text_snapshot("a\tb\n");
  auto r = edit(s, "add\tb\tz\nremove\tb\tz\nadd\tz\ta\t2\tremove\n");
  EXPECT_FALSE(r.is_ok());  // the valence field is checked
  auto r2 = edit(s, "add\tb\tz\nremove\tb\tz\nadd\tz\ta\t2\t-1\n");
  ASSERT_TRUE(r2.is_ok()) << r2.status().message();
  EXPECT_EQ(rows(*r2), "a\tb\t1\nz\ta\t2\n");
  EXPECT_EQ(r2->links[1].valence, -1);
  auto r3 = edit(s, "remove\ta\tb\nremove\ta\tb\n");
  ASSERT_FALSE(r3.is_ok());
  EXPECT_EQ(r3.status().message(), "e.txt:2: no link a -> b to remove");
}

TEST(Edits, BadInputNamesTheLine) {
  const auto s = text_snapshot("a\tb\nb\tc\n");
  const std::pair<const char*, const char*> cases[] = {
      {"frob\ta\tb\n", "e.txt:1: unknown edit 'frob'"},
      {"\nadd\ta\n", "e.txt:2: add takes 2 to 4"},
      {"remove\ta\tb\t1\n", "e.txt:1: remove takes 2"},
      {"reweight\ta\tb\n", "e.txt:1: reweight takes 3"},
      {"reweight\ta\tb\tnan\n", "e.txt:1: "},
      {"add\ta\tb\t0\n", "e.txt:1: weight is zero"},
      {"remove\ta\tq\n", "e.txt:1: particle 'q' is not in the snapshot"},
      {"remove\tc\ta\n", "e.txt:1: no link c -> a to remove"},
      {"add\t\tb\n", "e.txt:1: empty source particle"},
      {"remove\ta\tb\nremove\tb\tc\n", "e.txt: the edits leave no links"},
  };
  for (const auto& [text, want] : cases) {
    auto r = edit(s, text);
    ASSERT_FALSE(r.is_ok()) << text;
    EXPECT_EQ(r.status().message().rfind(want, 0), 0u) << r.status().message();
  }
}

TEST(Edits, IdSnapshotsTakeHexIds) {
  r1::GenParams p;
  p.kind = r1::GenKind::kRing;
  p.n = 12;
  auto g = r1::generate(p);
  ASSERT_TRUE(g.is_ok());
  r1::Snapshot s = std::move(g).value();
  s.names.clear();  // as read from a .graph file
  const std::string a = r1::hemera::to_hex(s.particles[0]), b = r1::hemera::to_hex(s.particles[5]);
  const std::string fresh(64, 'e');
  auto r = edit(s, "add\t" + a + "\t" + b + "\nadd\t" + b + "\t" + fresh + "\n");
  ASSERT_TRUE(r.is_ok()) << r.status().message();
  EXPECT_EQ(r->particles.size(), 13u);
  auto bad = edit(s, "add\t" + a + "\tnewname\n");
  ASSERT_FALSE(bad.is_ok());
  EXPECT_NE(bad.status().message().find("not a 64-hex-digit particle id"), std::string::npos);
}

TEST(Edits, FormatReadsBack) {
  rc::check("format_edit and parse_edits round-trip", [](int op, std::uint32_t w, bool neg) {
    r1::Edit e;
    e.op = static_cast<r1::EditOp>(((op % 3) + 3) % 3);
    e.from = "p " + std::to_string(w % 97);
    e.to = "q";
    e.amount = e.op == r1::EditOp::kRemove ? (r1::u128{1} << 32) : r1::u128{w} + 1;
    e.valence = e.op == r1::EditOp::kAdd ? (neg ? -1 : 1) : 0;
    auto back = r1::parse_edits(r1::format_edit(e) + "\n", "x");
    RC_ASSERT(back.is_ok());
    RC_ASSERT(back->size() == 1u);
    const r1::Edit& f = back->front();
    RC_ASSERT(f.op == e.op && f.from == e.from && f.to == e.to && f.amount == e.amount && f.valence == e.valence);
  });
}

}  // namespace
