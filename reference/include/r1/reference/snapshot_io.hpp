// Reading and writing snapshots: .graph v1, TSV/CSV edge lists, Matrix Market; titles and crystal
// side files (R1-IN-001..035). Every error names the file and the line or byte offset.
#pragma once

#include <string>

#include "r1/spec/progress.hpp"
#include "r1/spec/snapshot.hpp"
#include "r1/spec/status.hpp"

namespace r1 {

enum class SnapshotFormat { kAuto, kGraph, kTsv, kCsv, kMatrixMarket };

// "graph", "tsv", "csv", "mtx"; nullopt-like kAuto for anything else.
SnapshotFormat format_from_name(const std::string& name);
// By extension (.graph, .tsv/.tab/.txt, .csv, .mtx/.mm); kAuto when unknown.
SnapshotFormat format_from_path(const std::string& path);

struct ReadOptions {
  SnapshotFormat format = SnapshotFormat::kAuto;  // kAuto: by extension, then by content
  std::string titles_path;                        // optional side file: name-or-hex TAB title
  std::string crystal_path;                       // optional side file: name-or-hex TAB type TAB domain TAB size
  ProgressFn progress;
};

Result<Snapshot> read_snapshot(const std::string& path, const ReadOptions& options = {});

// The canonical .graph v1 bytes of a snapshot (R1-IN-024): front matter, card, config, titles and
// crystal text sections when present, then the cyberlinks records.
std::string graph_file_bytes(const Snapshot& s, const std::string& name);

// Writes atomically; the format comes from the extension unless given (.graph, .tsv, .csv).
Status write_snapshot(const Snapshot& s, const std::string& path, SnapshotFormat format = SnapshotFormat::kAuto);

}  // namespace r1
