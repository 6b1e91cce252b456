// The bad-input corpus (R1-ERR-001..003, R1-TEST-020): every case exits 2 with one line on stderr
// that names the file and says what is wrong, prints nothing on stdout and writes no output.
#include <gtest/gtest.h>

#include <filesystem>
#include <set>
#include <sstream>

#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;

struct Case {
  std::string file, command, expect;
};

// ctest shows the parameter; print the case, not its bytes.
void PrintTo(const Case& c, std::ostream* os) { *os << c.command << " " << c.file; }

std::vector<Case> load_cases() {
  std::vector<Case> cases;
  std::istringstream in(r1::test::read_file(r1::test::source_dir() / "tests/bad_input/cases.tsv"));
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    const auto t1 = line.find('\t'), t2 = line.find('\t', t1 + 1);
    cases.push_back({line.substr(0, t1), line.substr(t1 + 1, t2 - t1 - 1), line.substr(t2 + 1)});
  }
  return cases;
}

class BadInput : public testing::TestWithParam<Case> {};

TEST_P(BadInput, OneLineErrorExitTwoNoOutput) {
  const Case& c = GetParam();
  const fs::path path = r1::test::source_dir() / "tests/bad_input" / c.file;
  r1::test::TempDir out;
  std::vector<std::string> args = {c.command, path.string()};
  if (c.command == "convert") args.push_back((out / "out.graph").string());
  const auto r = r1::test::run_cli(args);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
  ASSERT_FALSE(r.err.empty());
  EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << "more than one line: " << r.err;
  EXPECT_EQ(r.err.rfind("r1: ", 0), 0u) << r.err;
  EXPECT_NE(r.err.find(path.string()), std::string::npos) << "error does not name the file: " << r.err;
  EXPECT_NE(r.err.find(c.expect), std::string::npos) << "expected '" << c.expect << "' in: " << r.err;
  // Nothing half-written: the output directory is still empty (no file, no temporary).
  EXPECT_TRUE(fs::is_empty(out.path())) << "convert left output behind";
}

std::string case_name(const testing::TestParamInfo<Case>& info) {
  std::string n = info.param.command + "_" + info.param.file;
  for (char& ch : n)
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  return n;
}

INSTANTIATE_TEST_SUITE_P(Corpus, BadInput, testing::ValuesIn(load_cases()), case_name);

TEST(BadInputCorpus, EveryFileHasACase) {
  std::set<std::string> listed;
  for (const auto& c : load_cases()) listed.insert(c.file);
  for (const auto& e : fs::directory_iterator(r1::test::source_dir() / "tests/bad_input")) {
    const std::string name = e.path().filename().string();
    if (name == "cases.tsv") continue;
    EXPECT_TRUE(listed.count(name)) << name << " is in the corpus but not in cases.tsv";
  }
}

TEST(BadOptions, UnknownOptionIsExitTwo) {
  const auto r = r1::test::run_cli({"info", "--bogus", "x.tsv"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err.rfind("r1: ", 0), 0u) << r.err;
  EXPECT_NE(r.err.find("--bogus"), std::string::npos) << r.err;
}

TEST(BadOptions, UnknownCommandAndBadFormatAreExitTwo) {
  EXPECT_EQ(r1::test::run_cli({"frobnicate"}).exit_code, 2);
  const auto r = r1::test::run_cli({"info", "--format", "xml", "x.tsv"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--format 'xml'"), std::string::npos) << r.err;
}

}  // namespace
