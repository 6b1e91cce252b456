// `--backend NAME` for every command that runs stages (spec/backends.md R1-BKD-003, R1-BKD-016):
// the option, else $R1_BACKEND, else reference; an unknown name is one line listing the built ones.
#pragma once

#include <CLI/CLI.hpp>

#include <memory>
#include <string>

#include "r1/backends/registry.hpp"

namespace r1::cli {

struct ChosenBackend {
  std::unique_ptr<backends::Backend> backend;
  std::string name;
  std::string source;  // "--backend", "R1_BACKEND" or "default"
};

struct BackendOption {
  std::string requested;

  void add_to(CLI::App& cmd) {
    cmd.add_option("--backend", requested,
                   "backend that runs the stages (default: $R1_BACKEND, else reference; `r1 conform --list` names them)");
  }

  // The backend by the precedence of R1-BKD-003; an input error (exit 2) naming the built ones.
  Result<ChosenBackend> make() const {
    ChosenBackend c;
    c.name = backends::choose_backend_name(requested, &c.source);
    R1_ASSIGN(c.backend, backends::make_backend(c.name));
    return c;
  }
};

}  // namespace r1::cli
