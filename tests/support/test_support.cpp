// Shared helpers for r1's test suites.
#include "test_support.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <utility>

extern char** environ;

namespace r1::test {

namespace fs = std::filesystem;

fs::path source_dir() { return fs::path(R1_SOURCE_DIR); }

fs::path shared_data_dir() {
  const fs::path p = source_dir().parent_path() / "shared" / "data";
  return fs::exists(p) ? p : fs::path();
}

std::string read_file(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  if (!f) throw std::runtime_error("cannot read " + p.string());
  std::ostringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

std::vector<std::uint8_t> read_bytes(const fs::path& p) {
  const std::string s = read_file(p);
  return {s.begin(), s.end()};
}

void write_file(const fs::path& p, const std::string& bytes) {
  std::ofstream f(p, std::ios::binary | std::ios::trunc);
  f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!f) throw std::runtime_error("cannot write " + p.string());
}

ScopedEnv::ScopedEnv(std::string name, const char* value) : name_(std::move(name)) {
  if (const char* v = std::getenv(name_.c_str())) saved_ = v, had_ = true;
  set(value);
}

ScopedEnv::~ScopedEnv() { set(had_ ? saved_.c_str() : nullptr); }

void ScopedEnv::set(const char* value) {
  if (value) setenv(name_.c_str(), value, 1);
  else unsetenv(name_.c_str());
}

TempDir::TempDir() {
  static std::atomic<int> counter{0};
  const fs::path base = fs::path(R1_BINARY_DIR) / "test-tmp";
  fs::create_directories(base);
  path_ = base / ("t" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
  fs::remove_all(path_);
  fs::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ec;
  fs::remove_all(path_, ec);
}

CliResult run_cli(const std::vector<std::string>& args, const std::string* stdin_data) {
  const TempDir io;
  const fs::path out_path = io / "stdout", err_path = io / "stderr", in_path = io / "stdin";
  write_file(in_path, stdin_data ? *stdin_data : std::string());

  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 0, in_path.c_str(), O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 1, out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&fa, 2, err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);

  std::vector<std::string> argv_s;
  argv_s.push_back(R1_CLI_PATH);
  argv_s.insert(argv_s.end(), args.begin(), args.end());
  // `r1 epoch` trains the neural field by default (a few seconds a run); a test that does not
  // name it (--field, --no-field, --field-steps) skips it.
  if (!args.empty() && args[0] == "epoch" &&
      std::none_of(args.begin(), args.end(), [](const std::string& a) { return a.rfind("--field", 0) == 0 || a == "--no-field"; }))
    argv_s.push_back("--no-field");
  std::vector<char*> argv;
  for (auto& a : argv_s) argv.push_back(a.data());
  argv.push_back(nullptr);

  pid_t pid = 0;
  const int rc = posix_spawn(&pid, argv[0], &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) throw std::runtime_error("cannot start " + argv_s[0]);
  int status = 0;
  ::waitpid(pid, &status, 0);

  CliResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.out = read_file(out_path);
  r.err = read_file(err_path);
  return r;
}

}  // namespace r1::test
