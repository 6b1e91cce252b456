// r1 export DIR --tsv FILE: one row per particle of an epoch (R1-EPO-020).
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
  return write_file_atomic(o.tsv, export_tsv(e));
}

}  // namespace

void add_export(CLI::App& app, Runner& selected) {
  auto o = std::make_shared<ExportOptions>();
  auto* cmd = app.add_subcommand("export", "export an epoch: one TSV row per particle (positions, focus, encoding, clusters)");
  cmd->add_option("DIR", o->dir, "epoch directory written by r1 epoch")->required();
  cmd->add_option("--tsv", o->tsv, "write the per-particle table to this file");
  cmd->callback([o, &selected] { selected = [o] { return run_export(*o); }; });
}

}  // namespace r1::cli
