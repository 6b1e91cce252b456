// r1 bench's measured runs: the r1 binary itself re-executed as a child process, its wall time and
// its own peak resident memory (spec/bench.md R1-BEN-020..023).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "r1/spec/status.hpp"

namespace r1::cli {

struct ChildRun {
  int exit_code = -1;         // the child's exit status; -1 when a signal ended it
  int signal = 0;             // the signal that ended it, else 0
  double wall_s = 0;          // from just before fork to the child's end
  double peak_rss_mib = 0;    // ru_maxrss of the child (wait4), MiB
  double parent_rss_mib = 0;  // this process's anonymous resident memory at the fork (R1-BEN-022)
  std::string err_tail;       // the last non-empty line the child wrote on standard error
  bool ok() const { return exit_code == 0 && signal == 0; }
  std::string failure() const;  // "exit 2: r1: ..." or "killed by signal 9"
};

// Runs /proc/self/exe with `args` (args[0] is the subcommand; no shell), standard input from
// /dev/null, standard output into `out_file` and standard error into `err_file`, and waits.
// An error only when the child cannot be started; a child that fails is a ChildRun with its status.
Result<ChildRun> run_self(const std::vector<std::string>& args, const std::filesystem::path& out_file,
                          const std::filesystem::path& err_file);

}  // namespace r1::cli
