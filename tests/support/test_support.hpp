// Shared helpers for r1's test suites: source paths, temporary directories, running the CLI.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace r1::test {

std::filesystem::path source_dir();
// ../shared/data beside the checkout when present (published constants and vectors), else empty.
std::filesystem::path shared_data_dir();
std::string read_file(const std::filesystem::path& p);
std::vector<std::uint8_t> read_bytes(const std::filesystem::path& p);
void write_file(const std::filesystem::path& p, const std::string& bytes);

// A fresh directory under the build tree, removed when the object goes out of scope.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

// Sets an environment variable (or unsets it, for nullptr) for the object's lifetime and restores
// what was there before, so a failing assertion cannot leak the setting into later tests.
class ScopedEnv {
 public:
  ScopedEnv(std::string name, const char* value);
  ~ScopedEnv();
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;
  // Changes the value again (nullptr unsets); the destructor still restores the original.
  void set(const char* value);

 private:
  std::string name_, saved_;
  bool had_ = false;
};

struct CliResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};
// Runs the built `r1` with the given arguments (no shell), capturing stdout and stderr.
// `stdin_data`, when given, is fed to standard input. An `epoch` command that does not name the
// neural field (--field, --no-field, --field-steps) gets --no-field: training it, the default,
// costs seconds a run.
CliResult run_cli(const std::vector<std::string>& args, const std::string* stdin_data = nullptr);

}  // namespace r1::test
