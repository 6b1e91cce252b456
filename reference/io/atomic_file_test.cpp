// Atomic outputs: all or nothing (R1-ERR-003).
#include "r1/reference/atomic_file.hpp"
#include "r1/reference/atomic_dir.hpp"
#include "r1/reference/input_file.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <sstream>
#include <string>

#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;

std::size_t entries(const fs::path& dir) {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++n;
  return n;
}

// The resident kilobytes of this process's mapping that holds `p` (from /proc/self/smaps).
std::uint64_t resident_kb(const void* p) {
  std::ifstream smaps("/proc/self/smaps");
  const auto at = reinterpret_cast<std::uintptr_t>(p);
  std::string line;
  bool inside = false;
  while (std::getline(smaps, line)) {
    std::uintptr_t lo = 0, hi = 0;
    char dash = 0;
    std::istringstream head(line);
    if (head >> std::hex >> lo >> dash >> hi && dash == '-') {
      inside = lo <= at && at < hi;
      continue;
    }
    if (inside && line.rfind("Rss:", 0) == 0) return std::stoull(line.substr(4));
  }
  return ~std::uint64_t{0};
}

// R1-IN-022: a mapped input's pages leave the process when released, and the bytes read the
// same afterwards; a part outside the file is ignored.
TEST(InputFile, ReleasedPagesLeaveTheProcessAndReadTheSame) {
  r1::test::TempDir d;
  std::string bytes(std::size_t{4} << 20, '\0');
  for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<char>(i * 131 + i / 4096);
  r1::test::write_file(d / "in.bin", bytes);
  auto in = r1::InputFile::open((d / "in.bin").string());
  ASSERT_TRUE(in.is_ok()) << in.status().message();
  const std::string_view text = (*in)->text();
  ASSERT_EQ(text, bytes);  // every page touched
  const std::uint64_t before = resident_kb(text.data());
  ASSERT_GE(before, 4000u);
  (*in)->drop_pages(text.substr(1000, text.size() - 2000));  // whole pages inside it go
  const std::uint64_t after = resident_kb(text.data());
  EXPECT_LE(after, 16u) << "before " << before;
  EXPECT_EQ(text, bytes);  // read again from the file
  const std::string elsewhere(64, 'x');
  (*in)->drop_pages(elsewhere);  // not the file's bytes: nothing happens
  EXPECT_EQ(elsewhere, std::string(64, 'x'));
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
