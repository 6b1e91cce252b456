// r1 edit SNAPSHOT EDITS -o NEXT: applies an edit file (spec/edits.md) and writes the next
// snapshot atomically, in the format its extension names (.graph by default).
#include <cstdio>

#include "commands.hpp"
#include "input_options.hpp"
#include "progress.hpp"
#include "r1/reference/edits.hpp"
#include "r1/reference/input_file.hpp"
#include "r1/reference/snapshot_io.hpp"

namespace r1::cli {

namespace {

struct EditOptions {
  std::string in, edits, out;
  InputOptions input;
};

Status run_edit(const EditOptions& o) {
  ProgressLine progress;
  R1_ASSIGN(const ReadOptions ro, o.input.read_options(progress.sink()));
  R1_ASSIGN(const Snapshot s, read_snapshot(o.in, ro));
  R1_ASSIGN(auto file, InputFile::open(o.edits));
  R1_ASSIGN(const std::vector<Edit> edits, parse_edits(file->text(), file->name()));
  EditCounts c;
  R1_ASSIGN(const Snapshot next, apply_edits(s, edits, file->name(), &c));
  SnapshotFormat format = format_from_path(o.out);
  if (format == SnapshotFormat::kAuto) format = SnapshotFormat::kGraph;
  R1_TRY(write_snapshot(next, o.out, format));
  progress.finish();
  std::printf("edits      %zu added, %zu removed, %zu reweighted (%zu link records deleted)\n", c.added, c.removed,
              c.reweighted, c.links_removed);
  std::printf("particles  %zu -> %zu (%zu new, %zu left without links)\n", s.particles.size(), next.particles.size(),
              c.new_particles, c.dropped_particles);
  std::printf("links      %zu -> %zu\n", s.links.size(), next.links.size());
  std::printf("wrote      %s\n", o.out.c_str());
  return Status::ok();
}

}  // namespace

void add_edit(CLI::App& app, Runner& selected) {
  auto o = std::make_shared<EditOptions>();
  auto* cmd = app.add_subcommand("edit", "apply an edit file (add, remove, reweight links) to a snapshot");
  cmd->add_option("SNAPSHOT", o->in, "input snapshot (- for stdin)")->required();
  cmd->add_option("EDITS", o->edits, "edit file: add|remove|reweight TAB from TAB to [TAB weight [TAB valence]] per line")
      ->required();
  cmd->add_option("-o,--output", o->out, "next snapshot; .graph (default), .tsv or .csv by extension")->required();
  o->input.add_to(*cmd);
  cmd->callback([o, &selected] { selected = [o] { return run_edit(*o); }; });
}

}  // namespace r1::cli
