// Options every command that reads a snapshot shares: --format, --titles, --crystal.
#pragma once

#include <CLI/CLI.hpp>

#include <string>

#include "r1/reference/snapshot_io.hpp"

namespace r1::cli {

struct InputOptions {
  std::string format;
  std::string titles, crystal;

  void add_to(CLI::App& cmd) {
    cmd.add_option("--format", format, "input format when the extension does not say: graph, tsv, csv, mtx");
    cmd.add_option("--titles", titles, "titles side file: particle name or hex id, TAB, title");
    cmd.add_option("--crystal", crystal, "crystal metadata side file: name or hex id, TAB type, TAB domain, TAB size");
  }

  Result<ReadOptions> read_options(const ProgressFn& progress) const {
    ReadOptions ro;
    ro.format = format.empty() ? SnapshotFormat::kAuto : format_from_name(format);
    if (!format.empty() && ro.format == SnapshotFormat::kAuto)
      return Status::input("--format '" + format + "' is not one of graph, tsv, csv, mtx");
    ro.titles_path = titles;
    ro.crystal_path = crystal;
    ro.progress = progress;
    return ro;
  }
};

}  // namespace r1::cli
