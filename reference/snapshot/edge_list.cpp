// TSV and CSV edge lists: from, to [, weight [, valence]] (R1-IN-013..014, R1-IN-017).
#include <algorithm>
#include <cctype>
#include <span>

#include "readers.hpp"
#include "r1/reference/snapshot_builder.hpp"
#include "text_util.hpp"

namespace r1::detail {

namespace {

bool iequal(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
         });
}

// A first data row "from, to[, weight[, valence]]" is a header, not a link (R1-IN-013).
bool is_header(std::span<const std::string_view> f) {
  static constexpr std::string_view names[] = {"from", "to", "weight", "valence"};
  for (std::size_t i = 0; i < f.size(); ++i)
    if (i >= 4 || !iequal(f[i], names[i])) return false;
  return f.size() >= 2;
}

class EdgeSink {
 public:
  EdgeSink(const std::string& file, const ProgressFn& progress, std::string_view text)
      : file_(file), progress_(progress), total_(text.size()), b_(file) {
    b_.snapshot().config = text_input_config();
    // One link per line at most: reserving avoids regrowing (and re-zeroing) a 10^7-link table.
    b_.reserve_links(static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n')) + 1);
  }

  // One data row; `line` is its first line, `end` the byte offset after it (for progress).
  Status row(std::span<const std::string_view> f, std::size_t line, std::size_t end, char sep) {
    const std::string at = file_ + ":" + std::to_string(line) + ": ";
    if (first_row_) {
      first_row_ = false;
      if (is_header(f)) return Status::ok();
    }
    if (f.size() < 2 || f.size() > 4)
      return Status::input(at + "expected 2 to 4 " + (sep == '\t' ? std::string("tab") : std::string("comma")) +
                           "-separated fields (from, to, weight, valence), found " + std::to_string(f.size()));
    for (std::size_t k = 0; k < 2; ++k) {
      if (f[k].empty()) return Status::input(at + (k == 0 ? "empty source name" : "empty target name"));
      if (auto bad = text::find_invalid_utf8(f[k]))
        return Status::input(at + "particle name is not valid UTF-8 (byte " + std::to_string(*bad) + " of the name)");
      if (f[k].find('\0') != std::string_view::npos) return Status::input(at + "NUL byte in a particle name");
    }
    Link l;
    l.height = 1;
    l.amount = u128{1} << 32;  // weight 1 when the column is absent
    if (f.size() >= 3) {
      const auto w = text::parse_weight(f[2]);
      if (!w.error.empty()) return Status::input(at + w.error);
      l.amount = w.amount;
    }
    if (f.size() == 4) {
      const auto v = text::parse_valence(f[3]);
      if (!v) return Status::input(at + "valence '" + std::string(f[3].substr(0, 40)) + "' is not -1, 0 or +1");
      l.valence = *v;
    }
    l.from = b_.particle_by_name(f[0]);  // source before target: decision 2
    l.to = b_.particle_by_name(f[1]);
    b_.add_link(l);
    if ((++rows_ & 0xFFFF) == 0) report(progress_, "reading links", end, total_);
    return Status::ok();
  }

  Result<Snapshot> finish() {
    if (rows_ == 0) return Status::input(file_ + ": no links");
    return b_.finish(progress_);
  }

 private:
  const std::string& file_;
  const ProgressFn& progress_;
  std::size_t total_;
  SnapshotBuilder b_;
  bool first_row_ = true;
  std::size_t rows_ = 0;
};

Result<Snapshot> read_tsv(std::string_view text, const std::string& file, const ProgressFn& progress) {
  EdgeSink sink(file, progress, text);
  text::LineReader lines(text);
  std::string_view line;
  std::vector<std::string_view> f;
  while (lines.next(line)) {
    if (line.empty() || line.front() == '#' || text::is_blank(line)) continue;
    text::split_tabs(line, f);
    R1_TRY(sink.row(f, lines.line_number(), lines.position(), '\t'));
  }
  return sink.finish();
}

Result<Snapshot> read_csv(std::string_view text, const std::string& file, const ProgressFn& progress) {
  EdgeSink sink(file, progress, text);
  std::vector<std::string> f;
  std::size_t i = 0, line = 1;
  const std::size_t n = text.size();
  while (i < n) {
    const std::size_t row_line = line;
    // Blank lines and comment lines (a '#' first on the line) carry no record.
    if (text[i] == '#' || text[i] == '\n' || (text[i] == '\r' && i + 1 < n && text[i + 1] == '\n')) {
      const std::size_t nl = text.find('\n', i);
      i = nl == std::string_view::npos ? n : nl + 1;
      ++line;
      continue;
    }
    f.clear();
    f.emplace_back();
    for (;;) {
      if (i < n && text[i] == '"' && f.back().empty()) {
        // Quoted field: "" is a quote; commas and line ends inside are data (RFC 4180).
        const std::size_t qline = line;
        ++i;
        for (;;) {
          if (i >= n) return Status::input(file + ":" + std::to_string(qline) + ": unterminated quoted field");
          const char c = text[i++];
          if (c == '"') {
            if (i < n && text[i] == '"') {
              f.back().push_back('"');
              ++i;
              continue;
            }
            break;
          }
          if (c == '\n') ++line;
          f.back().push_back(c);
        }
        if (i < n && text[i] != ',' && text[i] != '\n' && !(text[i] == '\r' && i + 1 < n && text[i + 1] == '\n') &&
            text[i] != '\r')
          return Status::input(file + ":" + std::to_string(line) + ": text after a closing quote");
      }
      while (i < n && text[i] != ',' && text[i] != '\n' && text[i] != '\r') {
        if (text[i] == '"')
          return Status::input(file + ":" + std::to_string(line) + ": quote inside an unquoted field (quote the whole field)");
        f.back().push_back(text[i++]);
      }
      if (i < n && text[i] == ',') {
        ++i;
        f.emplace_back();
        if (f.size() > 4) break;
        continue;
      }
      if (i < n && text[i] == '\r') {
        if (i + 1 < n && text[i + 1] == '\n') {
          i += 2;
        } else {
          return Status::input(file + ":" + std::to_string(line) + ": carriage return inside an unquoted field");
        }
      } else if (i < n) {
        ++i;  // '\n'
      }
      ++line;
      break;
    }
    if (f.size() > 4) return Status::input(file + ":" + std::to_string(row_line) + ": expected 2 to 4 comma-separated fields (from, to, weight, valence), found more");
    const std::vector<std::string_view> views(f.begin(), f.end());
    R1_TRY(sink.row(views, row_line, i, ','));
  }
  return sink.finish();
}

bool needs_csv_quotes(std::string_view s) {
  return s.empty() || s.front() == '#' || s.front() == ' ' || s.back() == ' ' ||
         s.find_first_of(",\"\r\n") != std::string_view::npos;
}

std::string csv_field(std::string_view s) {
  if (!needs_csv_quotes(s)) return std::string(s);
  std::string o = "\"";
  for (char c : s) {
    if (c == '"') o += '"';
    o += c;
  }
  return o + "\"";
}

}  // namespace

Result<Snapshot> read_edge_list(std::string_view bytes, const std::string& file, bool csv, const ProgressFn& progress) {
  const std::string_view text = text::strip_bom(bytes);
  return csv ? read_csv(text, file, progress) : read_tsv(text, file, progress);
}

std::string edge_list_bytes(const Snapshot& s, bool csv, Status& status) {
  if (s.names.size() != s.particles.size()) {
    status = Status::input(s.source + ": particles have no names (a .graph snapshot); write it as .graph");
    return {};
  }
  for (const auto& l : s.links) {
    const auto tok = s.config.tokens.find(l.token);
    if (l.neuron != 0 || tok == s.config.tokens.end() || tok->second.weight_permille != 1000 || l.height != 1) {
      status = Status::input(s.source + ": links carry chain data an edge list cannot hold; write it as .graph");
      return {};
    }
  }
  if (!csv) {
    for (const auto& name : s.names) {
      if (name.find_first_of("\t\r\n") != std::string::npos || name.front() == '#') {
        status = Status::input(s.source + ": particle name '" + text::escape_cell(name).substr(0, 60) +
                               "' cannot be written to TSV (tab, line end or leading '#'); use .csv");
        return {};
      }
    }
  }
  const char sep = csv ? ',' : '\t';
  std::string o = csv ? "from,to,weight,valence\n" : "from\tto\tweight\tvalence\n";
  for (const auto& l : s.links) {
    o += csv ? csv_field(s.names[l.from]) : s.names[l.from];
    o += sep;
    o += csv ? csv_field(s.names[l.to]) : s.names[l.to];
    o += sep;
    o += text::format_weight(l.amount);
    o += sep;
    o += std::to_string(l.valence);
    o += '\n';
  }
  status = Status::ok();
  return o;
}

}  // namespace r1::detail
