// The r1 subcommands: each adds itself to the CLI11 app and, when chosen, sets the runner.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>

#include "r1/spec/status.hpp"

namespace r1::cli {

using Runner = std::function<Status()>;

// The exit status of a command that ran to the end but whose checks did not all pass (r1 diff,
// r1 conform; spec/errors.md R1-ERR-005). 0 unless the runner sets it; main returns it when the
// runner's Status is ok.
int& verdict_exit();

void add_hash(CLI::App& app, Runner& selected);
void add_info(CLI::App& app, Runner& selected);
void add_convert(CLI::App& app, Runner& selected);
void add_edit(CLI::App& app, Runner& selected);
void add_drift(CLI::App& app, Runner& selected);
void add_gen(CLI::App& app, Runner& selected);
void add_export(CLI::App& app, Runner& selected);
void add_epoch(CLI::App& app, Runner& selected);
void add_spectrum(CLI::App& app, Runner& selected);
void add_render(CLI::App& app, Runner& selected);
void add_train_field(CLI::App& app, Runner& selected);
void add_golden(CLI::App& app, Runner& selected);
void add_conform(CLI::App& app, Runner& selected);
void add_diff(CLI::App& app, Runner& selected);
void add_bench(CLI::App& app, Runner& selected);
void add_view(CLI::App& app, Runner& selected);

}  // namespace r1::cli
