// r1 convert IN OUT: edge lists and Matrix Market to .graph (or edge lists); a .graph input without
// side files is copied byte for byte after validation (R1-IN-006, R1-IN-024).
#include <filesystem>

#include "commands.hpp"
#include "input_options.hpp"
#include "progress.hpp"
#include "r1/reference/atomic_file.hpp"
#include "r1/reference/graph_container.hpp"
#include "r1/reference/input_file.hpp"
#include "r1/reference/snapshot_io.hpp"

namespace r1::cli {

namespace {

struct ConvertOptions {
  std::string in, out;
  InputOptions input;
};

Status run_convert(const ConvertOptions& o) {
  ProgressLine progress;
  R1_ASSIGN(const ReadOptions ro, o.input.read_options(progress.sink()));
  R1_ASSIGN(Snapshot s, read_snapshot(o.in, ro));
  const SnapshotFormat in_format = ro.format != SnapshotFormat::kAuto ? ro.format : format_from_path(o.in);
  SnapshotFormat out_format = format_from_path(o.out);
  if (out_format == SnapshotFormat::kAuto) out_format = SnapshotFormat::kGraph;
  if (in_format == SnapshotFormat::kGraph && out_format == SnapshotFormat::kGraph && o.input.titles.empty() && o.input.crystal.empty()) {
    // Reading then writing a .graph gives identical bytes: keep its container as read.
    R1_ASSIGN(auto in, InputFile::open(o.in));
    R1_ASSIGN(Container c, parse_container(in->text(), in->name()));
    return write_file_atomic(o.out, c.serialize());
  }
  return write_snapshot(s, o.out, out_format);
}

}  // namespace

void add_convert(CLI::App& app, Runner& selected) {
  auto o = std::make_shared<ConvertOptions>();
  auto* cmd = app.add_subcommand("convert", "convert a snapshot: edge list or Matrix Market to .graph (or .tsv/.csv)");
  cmd->add_option("IN", o->in, "input snapshot (- for stdin)")->required();
  cmd->add_option("OUT", o->out, "output file; .graph (default), .tsv or .csv by extension")->required();
  o->input.add_to(*cmd);
  cmd->callback([o, &selected] { selected = [o] { return run_convert(*o); }; });
}

}  // namespace r1::cli
