// r1 bench's child processes: fork + exec of the r1 binary, wait4 for its resource usage
// (spec/bench.md R1-BEN-020..023).
#include "bench_child.hpp"

#include <fcntl.h>
#include <malloc.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <sstream>

namespace r1::cli {

namespace fs = std::filesystem;

std::string ChildRun::failure() const {
  if (signal != 0) return "killed by signal " + std::to_string(signal);
  return "exit " + std::to_string(exit_code) + (err_tail.empty() ? "" : ": " + err_tail);
}

namespace {

// RssAnon of /proc/self/status in MiB (0 when unreadable): what a fork copies into the child's
// page tables and so into its starting high-water mark (R1-BEN-022).
double anon_rss_mib() {
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line)) {
    if (line.rfind("RssAnon:", 0) == 0) {
      std::istringstream in(line.substr(8));
      double kib = 0;
      in >> kib;
      return kib / 1024.0;
    }
  }
  return 0;
}

std::string last_line(const fs::path& p) {
  std::ifstream f(p);
  std::string line, last;
  while (std::getline(f, line)) {
    // A progress line ends in "\r\033[K" erasures; keep the text after the last carriage return.
    const auto cr = line.rfind('\r');
    if (cr != std::string::npos) line = line.substr(cr + 1);
    if (!line.empty()) last = line;
  }
  return last;
}

}  // namespace

Result<ChildRun> run_self(const std::vector<std::string>& args, const fs::path& out_file, const fs::path& err_file) {
  char exe[4096];
  const ssize_t len = ::readlink("/proc/self/exe", exe, sizeof exe - 1);
  if (len <= 0)
    return Status::internal(std::string("bench: cannot find the r1 binary (/proc/self/exe): ") + std::strerror(errno));
  exe[len] = '\0';
  // Everything the child touches is prepared before fork: between fork and exec it calls only
  // async-signal-safe functions (open, dup2, execv, _exit).
  std::vector<std::string> argv_s;
  argv_s.reserve(args.size() + 1);
  argv_s.emplace_back(exe);
  argv_s.insert(argv_s.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : argv_s) argv.push_back(a.data());
  argv.push_back(nullptr);
  const std::string out_path = out_file.string(), err_path = err_file.string();

  // fork, not posix_spawn or vfork: exec records the high-water mark of the memory it replaces
  // in the child's ru_maxrss. After vfork that is this process's own peak; after fork it is only
  // what is resident now, which malloc_trim keeps near r1's start-up size (R1-BEN-022).
  ::malloc_trim(0);
  ChildRun run;
  run.parent_rss_mib = anon_rss_mib();
  const auto t0 = std::chrono::steady_clock::now();
  const pid_t pid = ::fork();
  if (pid < 0) return Status::internal(std::string("bench: fork: ") + std::strerror(errno));
  if (pid == 0) {
    const int in = ::open("/dev/null", O_RDONLY);
    const int out = ::open(out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int err = ::open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (in < 0 || out < 0 || err < 0 || ::dup2(in, 0) < 0 || ::dup2(out, 1) < 0 || ::dup2(err, 2) < 0) ::_exit(126);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  int status = 0;
  rusage ru{};
  pid_t waited;
  do {
    waited = ::wait4(pid, &status, 0, &ru);
  } while (waited < 0 && errno == EINTR);
  if (waited < 0) return Status::internal(std::string("bench: wait4: ") + std::strerror(errno));
  run.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  run.peak_rss_mib = static_cast<double>(ru.ru_maxrss) / 1024.0;  // KiB on Linux
  if (WIFEXITED(status)) {
    run.exit_code = WEXITSTATUS(status);
  } else if (WIFSIGNALED(status)) {
    run.signal = WTERMSIG(status);
  }
  if (run.exit_code == 126 || run.exit_code == 127)
    return Status::internal("bench: cannot run " + std::string(exe) + " (exit " + std::to_string(run.exit_code) + ")");
  if (!run.ok()) run.err_tail = last_line(err_file);
  return run;
}

}  // namespace r1::cli
