// r1 export DIR --tsv FILE --ply FILE: one row per particle of an epoch (R1-EPO-020), and the
// epoch as 3D Gaussian Splatting splats (R1-RND-095..097).
#include <cstdio>

#include "commands.hpp"
#include "r1/reference/atomic_file.hpp"
#include "r1/reference/epoch_io.hpp"
#include "r1/reference/ply_export.hpp"

namespace r1::cli {

namespace {

struct ExportOptions {
  std::string dir;
  std::string tsv;
  std::string ply;
};

Status run_export(const ExportOptions& o) {
  if (o.tsv.empty() && o.ply.empty()) return Status::input("export: say what to write (--tsv FILE, --ply FILE)");
  R1_ASSIGN(const Epoch e, read_epoch(o.dir));
  // Each file is atomic on its own; the .ply goes first so that a refused .ply leaves nothing on
  // standard output either.
  if (!o.ply.empty()) R1_TRY(write_file_atomic(o.ply, ply_bytes(e)));
  if (o.tsv.empty()) return Status::ok();
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
  auto* cmd = app.add_subcommand("export", "export an epoch: one TSV row per particle (positions, focus, encoding, clusters), or 3DGS splats (.ply)");
  cmd->add_option("DIR", o->dir, "epoch directory written by r1 epoch")->required();
  cmd->add_option("--tsv", o->tsv, "write the per-particle table to this file (- for standard output)");
  cmd->add_option("--ply", o->ply, "write the particles as 3D Gaussian Splatting splats (binary .ply) to this file");
  cmd->callback([o, &selected] { selected = [o] { return run_export(*o); }; });
}

}  // namespace r1::cli
