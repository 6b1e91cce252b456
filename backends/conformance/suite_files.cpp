// A suite's snapshot graphs (spec/conformance.md R1-CONF-006, 007, 044): the path rule and the
// loading of each file with the snapshot readers of `r1 epoch`, before anything is computed.
#include <filesystem>

#include "r1/conformance/suite.hpp"
#include "r1/reference/input_file.hpp"
#include "r1/reference/snapshot_io.hpp"

namespace r1::conformance {

namespace fs = std::filesystem;

Status check_suite_path(std::string_view path, const std::string& where) {
  const std::string rule = where + ": '" + std::string(path) +
                           "' must be a relative path below the suite's directory ('/' between names, no '..', '.' or "
                           "empty name; R1-CONF-007)";
  if (path.empty() || path.front() == '/' || path.find('\\') != std::string_view::npos ||
      path.find('\0') != std::string_view::npos)
    return Status::input(rule);
  std::size_t start = 0;
  while (true) {
    const std::size_t end = path.find('/', start);
    const std::string_view part = path.substr(start, end == std::string_view::npos ? std::string_view::npos : end - start);
    if (part.empty() || part == "." || part == "..") return Status::input(rule);
    if (end == std::string_view::npos) break;
    start = end + 1;
  }
  return Status::ok();
}

namespace {

// The bytes of `rel` under `base`, or an error placed at the suite entry.
Result<SuiteFile> read_side(const fs::path& base, const std::string& rel, const std::string& at) {
  SuiteFile f;
  f.path = rel;
  if (rel.empty()) return f;
  auto in = InputFile::open((base / rel).string());
  if (!in.is_ok()) return Status::input(at + ": " + in.status().message());
  f.bytes = std::string((*in)->text());
  return f;
}

}  // namespace

Status load_suite_files(Suite& suite, const fs::path& base, const SuiteFilesCheck& check_bytes) {
  for (std::size_t gi = 0; gi < suite.graphs.size(); ++gi) {
    SuiteGraph& g = suite.graphs[gi];
    if (!g.is_file()) continue;
    const std::string at = g.where(suite.source);
    auto loaded = std::make_shared<LoadedSnapshot>();
    R1_ASSIGN(loaded->file, read_side(base, g.file, at + ": file"));
    R1_ASSIGN(loaded->titles, read_side(base, g.titles, at + ": titles"));
    R1_ASSIGN(loaded->crystal, read_side(base, g.crystal, at + ": crystal"));
    if (check_bytes) R1_TRY(check_bytes(gi, *loaded));
    // The readers of `r1 epoch FILE --format --titles --crystal`: no second parser.
    ReadOptions ro;
    ro.format = g.format.empty() ? SnapshotFormat::kAuto : format_from_name(g.format);
    if (!g.titles.empty()) ro.titles_path = (base / g.titles).string();
    if (!g.crystal.empty()) ro.crystal_path = (base / g.crystal).string();
    auto snap = read_snapshot((base / g.file).string(), ro);
    if (!snap.is_ok()) return Status::input(at + ": " + snap.status().message());
    loaded->snapshot = std::move(*snap);
    g.loaded = std::move(loaded);
  }
  return Status::ok();
}

}  // namespace r1::conformance
