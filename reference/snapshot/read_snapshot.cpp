// Snapshot input dispatch: format by option, extension or content; side files (R1-IN-001, R1-IN-015).
#include <algorithm>
#include <filesystem>

#include "r1/reference/input_file.hpp"
#include "readers.hpp"

namespace r1 {

namespace {

std::string lower_ext(const std::string& path) {
  std::string e = std::filesystem::path(path).extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return e;
}

// Content sniffing when neither option nor extension decides (R1-IN-001).
SnapshotFormat sniff(std::string_view b) {
  if (b.substr(0, 14) == "%%MatrixMarket" || b.substr(0, 14) == "%%matrixmarket") return SnapshotFormat::kMatrixMarket;
  if (b.find("\n~~~") != std::string_view::npos && b.find("[[files]]") != std::string_view::npos)
    return SnapshotFormat::kGraph;
  // First data line: a tab makes it TSV, otherwise CSV.
  std::size_t pos = 0;
  while (pos < b.size()) {
    const std::size_t nl = b.find('\n', pos);
    const std::string_view line = b.substr(pos, nl == std::string_view::npos ? std::string_view::npos : nl - pos);
    if (!line.empty() && line.front() != '#' && line != "\r") return line.find('\t') != std::string_view::npos ? SnapshotFormat::kTsv : SnapshotFormat::kCsv;
    if (nl == std::string_view::npos) break;
    pos = nl + 1;
  }
  return SnapshotFormat::kTsv;
}

}  // namespace

SnapshotFormat format_from_name(const std::string& name) {
  if (name == "graph") return SnapshotFormat::kGraph;
  if (name == "tsv") return SnapshotFormat::kTsv;
  if (name == "csv") return SnapshotFormat::kCsv;
  if (name == "mtx" || name == "mm") return SnapshotFormat::kMatrixMarket;
  return SnapshotFormat::kAuto;
}

SnapshotFormat format_from_path(const std::string& path) {
  const std::string e = lower_ext(path);
  if (e == ".graph" || e == ".cyb") return SnapshotFormat::kGraph;
  if (e == ".tsv" || e == ".tab" || e == ".txt") return SnapshotFormat::kTsv;
  if (e == ".csv") return SnapshotFormat::kCsv;
  if (e == ".mtx" || e == ".mm") return SnapshotFormat::kMatrixMarket;
  return SnapshotFormat::kAuto;
}

Result<Snapshot> read_snapshot(const std::string& path, const ReadOptions& o) {
  R1_ASSIGN(auto in, InputFile::open(path));
  const std::string& name = in->name();
  SnapshotFormat f = o.format;
  if (f == SnapshotFormat::kAuto) f = format_from_path(path);
  if (f == SnapshotFormat::kAuto) f = sniff(in->text());
  if (in->bytes().empty()) return Status::input(name + ": empty file");
  Result<Snapshot> r = Status::internal("unreachable");
  switch (f) {
    case SnapshotFormat::kGraph:
      r = detail::read_graph_file(in->text(), name, o.progress, [&in](std::string_view part) { in->drop_pages(part); });
      break;
    case SnapshotFormat::kTsv: r = detail::read_edge_list(in->text(), name, false, o.progress); break;
    case SnapshotFormat::kCsv: r = detail::read_edge_list(in->text(), name, true, o.progress); break;
    case SnapshotFormat::kMatrixMarket: r = detail::read_matrix_market(in->text(), name, o.progress); break;
    case SnapshotFormat::kAuto: return Status::internal("format not resolved");
  }
  if (!r.is_ok()) return r;
  Snapshot& s = r.value();
  if (!o.titles_path.empty()) {
    R1_ASSIGN(auto t, InputFile::open(o.titles_path));
    R1_TRY(detail::apply_side_text(s, t->text(), t->name(), detail::SideKind::kTitles, false, 1, nullptr));
  }
  if (!o.crystal_path.empty()) {
    R1_ASSIGN(auto c, InputFile::open(o.crystal_path));
    R1_TRY(detail::apply_side_text(s, c->text(), c->name(), detail::SideKind::kCrystal, false, 1, nullptr));
  }
  return r;
}

}  // namespace r1
