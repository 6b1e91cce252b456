// Matrix Market coordinate files as snapshots (R1-IN-018).
#include <algorithm>
#include <cctype>

#include "readers.hpp"
#include "r1/reference/snapshot_builder.hpp"
#include "text_util.hpp"

namespace r1::detail {

namespace {

std::vector<std::string_view> tokens(std::string_view line) {
  std::vector<std::string_view> t;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    const std::size_t s = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
    if (i > s) t.push_back(line.substr(s, i - s));
  }
  return t;
}

std::string lower(std::string_view s) {
  std::string o(s);
  std::transform(o.begin(), o.end(), o.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return o;
}

}  // namespace

Result<Snapshot> read_matrix_market(std::string_view bytes, const std::string& file, const ProgressFn& progress) {
  text::LineReader lines(bytes);
  std::string_view line;
  if (!lines.next(line)) return Status::input(file + ": empty file");
  const auto banner = tokens(line);
  if (banner.empty() || lower(banner[0]) != "%%matrixmarket")
    return Status::input(file + ":1: expected a '%%MatrixMarket' banner");
  if (banner.size() != 5) return Status::input(file + ":1: banner needs 'matrix coordinate FIELD SYMMETRY'");
  if (lower(banner[1]) != "matrix") return Status::input(file + ":1: only 'matrix' objects are graphs");
  if (lower(banner[2]) != "coordinate")
    return Status::input(file + ":1: format '" + std::string(banner[2]) + "' is not supported (only 'coordinate')");
  const std::string field = lower(banner[3]), symmetry = lower(banner[4]);
  if (field != "real" && field != "integer" && field != "pattern")
    return Status::input(file + ":1: field '" + std::string(banner[3]) + "' is not supported (real, integer or pattern)");
  if (symmetry != "general" && symmetry != "symmetric")
    return Status::input(file + ":1: symmetry '" + std::string(banner[4]) + "' is not supported (general or symmetric)");
  const bool pattern = field == "pattern", symmetric = symmetry == "symmetric";

  // Size line after comments.
  std::uint64_t rows = 0, nnz = 0;
  for (;;) {
    if (!lines.next(line)) return Status::input(file + ": no size line (truncated file?)");
    if (text::is_blank(line) || line.front() == '%') continue;
    const auto t = tokens(line);
    const std::string at = file + ":" + std::to_string(lines.line_number()) + ": ";
    if (t.size() != 3) return Status::input(at + "size line needs 'ROWS COLUMNS ENTRIES'");
    const auto r = text::parse_u64(t[0]), c = text::parse_u64(t[1]), z = text::parse_u64(t[2]);
    if (!r || !c || !z) return Status::input(at + "size line needs three non-negative integers");
    if (*r != *c) return Status::input(at + "matrix is " + std::to_string(*r) + " x " + std::to_string(*c) + ", not square");
    if (*r >= 0xFFFFFFFFull) return Status::input(at + "more than 2^32 - 2 rows");
    rows = *r;
    nnz = *z;
    break;
  }

  SnapshotBuilder b(file);
  b.snapshot().config = text_input_config();
  std::uint64_t seen = 0, zeros = 0;
  const std::size_t want = pattern ? 2 : 3;
  while (lines.next(line)) {
    if (text::is_blank(line) || line.front() == '%') continue;
    const std::string at = file + ":" + std::to_string(lines.line_number()) + ": ";
    if (seen == nnz) return Status::input(at + "more entries than the " + std::to_string(nnz) + " the size line declares");
    const auto t = tokens(line);
    if (t.size() != want)
      return Status::input(at + "entry needs " + std::to_string(want) + " fields (" + (pattern ? "i j" : "i j value") + ")");
    const auto i = text::parse_u64(t[0]), j = text::parse_u64(t[1]);
    if (!i || !j || *i < 1 || *j < 1 || *i > rows || *j > rows)
      return Status::input(at + "index out of range 1.." + std::to_string(rows));
    ++seen;
    Link l;
    l.height = 1;
    l.amount = u128{1} << 32;
    if (!pattern) {
      const auto w = text::parse_weight(t[2]);
      if (!w.error.empty()) {
        // Explicit zeros are structural zeros in Matrix Market: not links (R1-IN-018).
        if (w.error.rfind("weight is zero", 0) == 0) {
          ++zeros;
          continue;
        }
        return Status::input(at + w.error);
      }
      l.amount = w.amount;
    }
    // Particle names are the decimal indices, so "7" and "007" are one particle.
    const std::string si = std::to_string(*i), sj = std::to_string(*j);
    l.from = b.particle_by_name(si);
    l.to = b.particle_by_name(sj);
    b.add_link(l);
    if (symmetric && *i != *j) {
      std::swap(l.from, l.to);
      b.add_link(l);
    }
    if ((seen & 0xFFFF) == 0) report(progress, "reading entries", seen, nnz);
  }
  if (seen < nnz)
    return Status::input(file + ": " + std::to_string(seen) + " entries but the size line declares " + std::to_string(nnz) +
                         " (truncated file?)");
  if (seen == zeros) return Status::input(file + ": no links (every entry is zero)");
  b.snapshot().card = "Matrix Market input; " + std::to_string(zeros) + " explicit zero entries skipped.\n";
  return b.finish(progress);
}

}  // namespace r1::detail
