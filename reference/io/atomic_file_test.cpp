// Atomic outputs: all or nothing (R1-ERR-003).
#include "r1/reference/atomic_file.hpp"
#include "r1/reference/atomic_dir.hpp"

#include <gtest/gtest.h>

#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;

std::size_t entries(const fs::path& dir) {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++n;
  return n;
}

TEST(AtomicFile, CommitReplacesTarget) {
  r1::test::TempDir d;
  r1::test::write_file(d / "out.txt", "old");
  ASSERT_TRUE(r1::write_file_atomic(d / "out.txt", "new").is_ok());
  EXPECT_EQ(r1::test::read_file(d / "out.txt"), "new");
  EXPECT_EQ(entries(d.path()), 1u);
}

TEST(AtomicFile, DiscardLeavesNothing) {
  r1::test::TempDir d;
  {
    r1::AtomicFile f(d / "out.txt");
    ASSERT_TRUE(f.open().is_ok());
    ASSERT_TRUE(f.write(std::string_view("partial")).is_ok());
    // destroyed without commit: as if the writer failed half-way
  }
  EXPECT_FALSE(fs::exists(d / "out.txt"));
  EXPECT_EQ(entries(d.path()), 0u);
}

TEST(AtomicFile, MissingDirectoryAndDirectoryTargetAreErrors) {
  r1::test::TempDir d;
  const auto s1 = r1::write_file_atomic(d / "no/such/dir/out.txt", "x");
  EXPECT_EQ(s1.kind(), r1::ErrorKind::kOutput);
  fs::create_directory(d / "sub");
  const auto s2 = r1::write_file_atomic(d / "sub", "x");
  EXPECT_FALSE(s2.is_ok());
  EXPECT_NE(s2.message().find("is a directory"), std::string::npos);
}

}  // namespace

TEST(AtomicDirectory, NamesWithFoldersAppearWithTheDirectory) {
  r1::test::TempDir d;
  {
    r1::AtomicDirectory out(d / "ep", [](const fs::path&) { return false; });
    ASSERT_TRUE(out.open().is_ok());
    ASSERT_TRUE(out.write("content/3.png", "png").is_ok());
    ASSERT_TRUE(out.write("content/deep/4.txt", "txt").is_ok());
    ASSERT_TRUE(out.write("a.bin", "a").is_ok());
    // A name that climbs out of the directory is refused, not written beside it.
    EXPECT_FALSE(out.write("../escape.txt", "x").is_ok());
    EXPECT_FALSE(out.write("/tmp/escape.txt", "x").is_ok());
    EXPECT_FALSE(fs::exists(d / "ep"));
    ASSERT_TRUE(out.commit().is_ok());
  }
  EXPECT_EQ(r1::test::read_file(d / "ep" / "content" / "3.png"), "png");
  EXPECT_EQ(r1::test::read_file(d / "ep" / "content" / "deep" / "4.txt"), "txt");
  EXPECT_FALSE(fs::exists(d / "escape.txt"));
  EXPECT_EQ(entries(d.path()), 1u);
}
