// Canonical .graph v1 writer and the output dispatch (R1-IN-024, R1-ERR-003).
#include <filesystem>

#include "r1/reference/atomic_file.hpp"
#include "readers.hpp"

namespace r1 {

namespace {

// TOML basic string: quotes, backslashes and control characters escaped.
std::string toml_string(std::string_view s) {
  std::string o = "\"";
  for (char c : s) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      o += '\\';
      o += c;
    } else if (u < 0x20 || u == 0x7F) {
      static constexpr char hex[] = "0123456789ABCDEF";
      o += "\\u00";
      o += hex[u >> 4];
      o += hex[u & 15];
    } else {
      o += c;
    }
  }
  return o + "\"";
}

// Section names and the [cyb] name keep to a portable alphabet.
std::string safe_name(std::string_view s) {
  std::string o;
  for (char c : s)
    o += ((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' || c == '-' || c == '_') ? c : '_';
  return o.empty() ? std::string("snapshot") : o;
}

// A text section ends at a line starting "~~~": such lines in the card get a leading space, and
// the card always ends with a line end.
std::string safe_card(const Snapshot& s, const std::string& name) {
  std::string card = s.card;
  if (card.empty())
    card = "# " + name + "\n\nr1 snapshot: " + std::to_string(s.particles.size()) + " particles, " +
           std::to_string(s.links.size()) + " cyberlinks.\n";
  if (card.back() != '\n') card += '\n';
  std::string o;
  std::size_t pos = 0;
  while (pos < card.size()) {
    const std::size_t nl = card.find('\n', pos);
    const std::string_view line(card.data() + pos, nl - pos + 1);
    if (line.substr(0, 3) == "~~~") o += ' ';
    o += line;
    pos = nl + 1;
  }
  return o;
}

std::string config_text(const SnapshotConfig& c) {
  std::string o = "chain_id = " + toml_string(c.chain_id) + "\nblock = " + std::to_string(c.block) +
                  "\ncaptured_at = " + std::to_string(c.captured_at) + "\nformat_version = " +
                  std::to_string(c.format_version) + "\n\n[tokens]\n";
  for (const auto& [index, t] : c.tokens)
    o += std::to_string(index) + " = { symbol = " + toml_string(t.symbol) + ", weight = " + std::to_string(t.weight_permille) + " }\n";
  return o;
}

struct Layout {
  std::string head;  // front matter and every text section, up to and including "~~~cyberlinks\n"
};

Layout layout(const Snapshot& s, const std::string& raw_name) {
  const std::string name = safe_name(raw_name);
  std::vector<std::pair<std::string, std::string>> text_sections = {{"card", safe_card(s, name)},
                                                                    {"config", config_text(s.config)}};
  std::vector<std::string> formats = {"md", "toml"};
  if (std::string t = detail::format_titles_section(s); !t.empty()) {
    text_sections.emplace_back("titles", std::move(t));
    formats.emplace_back("tsv");
  }
  if (std::string c = detail::format_crystal_section(s); !c.empty()) {
    text_sections.emplace_back("crystal", std::move(c));
    formats.emplace_back("tsv");
  }
  Layout L;
  L.head = "[cyb]\ntypes = [\"graph\"]\nname = " + toml_string(name) + "\n";
  for (std::size_t i = 0; i < text_sections.size(); ++i)
    L.head += "\n[[files]]\nname = \"" + text_sections[i].first + "\"\nformat = \"" + formats[i] + "\"\n";
  L.head += "\n[[files]]\nname = \"cyberlinks\"\nformat = \"records\"\nsize = " +
            std::to_string(s.links.size() * kRecordBytes) + "\n";
  for (const auto& [sec, body] : text_sections) L.head += "~~~" + sec + "\n" + body;
  L.head += "~~~cyberlinks\n";
  return L;
}

}  // namespace

std::string graph_file_bytes(const Snapshot& s, const std::string& name) {
  std::string o = layout(s, name).head;
  const std::size_t base = o.size();
  o.resize(base + s.links.size() * kRecordBytes);
  for (std::size_t i = 0; i < s.links.size(); ++i)
    encode_record(s, s.links[i], reinterpret_cast<std::uint8_t*>(o.data()) + base + i * kRecordBytes);
  return o;
}

Status write_snapshot(const Snapshot& s, const std::string& path, SnapshotFormat format) {
  if (format == SnapshotFormat::kAuto) format = format_from_path(path);
  if (format == SnapshotFormat::kAuto) format = SnapshotFormat::kGraph;
  if (format == SnapshotFormat::kMatrixMarket) return Status::input(path + ": r1 does not write Matrix Market files");
  if (format == SnapshotFormat::kTsv || format == SnapshotFormat::kCsv) {
    Status st;
    const std::string bytes = detail::edge_list_bytes(s, format == SnapshotFormat::kCsv, st);
    if (!st.is_ok()) return st;
    return write_file_atomic(path, bytes);
  }
  AtomicFile out(path);
  R1_TRY(out.open());
  R1_TRY(out.write(layout(s, std::filesystem::path(path).stem().string()).head));
  // Records in blocks so that a 10^7-link snapshot never needs its 1.28 GB at once.
  constexpr std::size_t kBlock = 8192;
  std::vector<std::uint8_t> buf(kBlock * kRecordBytes);
  for (std::size_t i = 0; i < s.links.size(); i += kBlock) {
    const std::size_t n = std::min(kBlock, s.links.size() - i);
    for (std::size_t k = 0; k < n; ++k) encode_record(s, s.links[i + k], buf.data() + k * kRecordBytes);
    R1_TRY(out.write(std::span<const std::uint8_t>(buf.data(), n * kRecordBytes)));
  }
  return out.commit();
}

}  // namespace r1
