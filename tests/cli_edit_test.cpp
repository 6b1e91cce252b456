// r1 edit (spec/edits.md R1-EDT-030): the next snapshot is the edited edge list, written
// atomically; bad edit files fail with one line naming FILE:LINE and leave nothing behind.
#include <gtest/gtest.h>

#include <filesystem>

#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;

TEST(CliEdit, WritesTheEditedSnapshotAndItsCounts) {
  r1::test::TempDir d;
  r1::test::write_file(d / "g.tsv", "a\tb\na\tc\t2\nb\tc\nc\td\nd\ta\n");
  r1::test::write_file(d / "e.txt", "add\td\te\t5\nremove\ta\tc\nreweight\tb\tc\t3\n");
  r1::test::write_file(d / "want.tsv", "a\tb\nb\tc\t3\nc\td\nd\ta\nd\te\t5\n");
  const auto r = r1::test::run_cli({"edit", (d / "g.tsv").string(), (d / "e.txt").string(), "-o", (d / "next.graph").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("1 added, 1 removed, 1 reweighted"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("particles  4 -> 5 (1 new, 0 left without links)"), std::string::npos) << r.out;
  // Same digest as the edge list written by hand (r1 info prints it).
  const auto a = r1::test::run_cli({"info", (d / "next.graph").string()});
  const auto b = r1::test::run_cli({"info", (d / "want.tsv").string()});
  ASSERT_EQ(a.exit_code, 0) << a.err;
  const auto digest = [](const std::string& s) { return s.substr(s.find("digest")); };
  EXPECT_EQ(digest(a.out), digest(b.out));
}

TEST(CliEdit, BadEditsFailWithOneLineAndWriteNothing) {
  r1::test::TempDir d, out;
  r1::test::write_file(d / "g.tsv", "a\tb\nb\tc\n");
  const std::pair<const char*, const char*> cases[] = {
      {"add\ta\tb\n# fine so far\nremove\tb\tq\n", "e.txt:3: particle 'q' is not in the snapshot"},
      {"remove\tc\tb\n", "e.txt:1: no link c -> b to remove"},
      {"grow\ta\tb\n", "e.txt:1: unknown edit 'grow'"},
      {"add\ta\tb\t-2\n", "e.txt:1: weight '-2' is negative"},
  };
  for (const auto& [text, want] : cases) {
    r1::test::write_file(d / "e.txt", text);
    const auto r = r1::test::run_cli({"edit", (d / "g.tsv").string(), (d / "e.txt").string(), "-o", (out / "n.graph").string()});
    EXPECT_EQ(r.exit_code, 2) << text;
    EXPECT_TRUE(r.out.empty()) << r.out;
    EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << r.err;
    EXPECT_NE(r.err.find(want), std::string::npos) << r.err;
    EXPECT_TRUE(fs::is_empty(out.path())) << text;
  }
  const auto missing = r1::test::run_cli({"edit", (d / "g.tsv").string(), (d / "none.txt").string(), "-o", (out / "n.graph").string()});
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.err.find("none.txt"), std::string::npos) << missing.err;
  EXPECT_TRUE(fs::is_empty(out.path()));
}

}  // namespace
