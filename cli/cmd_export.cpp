// r1 export DIR --tsv FILE: one row per particle of an epoch (R1-EPO-020).
#include <cstdio>

#include "commands.hpp"
#include "r1/reference/atomic_file.hpp"
#include "r1/reference/epoch_io.hpp"

namespace r1::cli {

namespace {

struct ExportOptions {
  std::string dir;
  std::string tsv;
};

Status run_export(const ExportOptions& o) {
  if (o.tsv.empty()) return Status::input("export: say what to write (--tsv FILE)");
  R1_ASSIGN(const Epoch e, read_epoch(o.dir));
  if (o.tsv == "-") {  // standard output, as `r1 hash -` reads standard input
    const std::string text = export_tsv(e);
    if (std::fwrite(text.data(), 1, text.size(), stdout) != text.size() || std::fflush(stdout) != 0)
      return Status::output("standard output: write failed");
    return Status::ok();
  }
  return write_file_atomic(o.tsv, export_tsv(e));
}

}  // namespace

void add_export(CLI::App& app, Runner& selected) {
  auto o = std::make_shared<ExportOptions>();
  auto* cmd = app.add_subcommand("export", "export an epoch: one TSV row per particle (positions, focus, encoding, clusters)");
  cmd->add_option("DIR", o->dir, "epoch directory written by r1 epoch")->required();
  cmd->add_option("--tsv", o->tsv, "write the per-particle table to this file (- for standard output)");
  cmd->callback([o, &selected] { selected = [o] { return run_export(*o); }; });
}

}  // namespace r1::cli
