// Titles and crystal metadata: side files and .graph extension sections (R1-IN-007, R1-IN-015..016).

#include "r1/reference/intern_index.hpp"
#include "readers.hpp"
#include "text_util.hpp"

namespace r1::detail {

Status apply_side_text(Snapshot& s, std::string_view text, const std::string& where, SideKind kind, bool strict,
                       std::size_t first_line, std::size_t* unmatched) {
  const char* what = kind == SideKind::kTitles ? "titles" : "crystal metadata";
  if (auto bad = text::find_invalid_utf8(text))
    return Status::input(where + ": byte " + std::to_string(*bad) + ": " + what + " are not valid UTF-8");
  const IdIndex by_id = IdIndex::over(s.particles);
  const NameIndex by_name = strict ? NameIndex() : NameIndex::over(s.names);
  std::vector<bool> seen(s.particles.size(), false);
  if (kind == SideKind::kTitles && s.titles.size() != s.particles.size()) s.titles.assign(s.particles.size(), {});
  if (kind == SideKind::kCrystal && s.crystal.size() != s.particles.size()) s.crystal.assign(s.particles.size(), {});

  text::LineReader lines(text::strip_bom(text));
  std::string_view line;
  std::vector<std::string_view> f;
  while (lines.next(line)) {
    const std::string at = where + ":" + std::to_string(first_line + lines.line_number() - 1) + ": ";
    if (text::is_blank(line) || line.front() == '#') continue;
    text::split_tabs(line, f);
    const std::size_t want = kind == SideKind::kTitles ? 2 : 4;
    if (f.size() != want)
      return Status::input(at + "expected " + std::to_string(want) + " tab-separated fields, found " + std::to_string(f.size()));
    std::optional<std::uint32_t> index;
    ParticleId id;
    if (const std::int64_t k = by_name.find(f[0], s.names); k >= 0) {
      index = static_cast<std::uint32_t>(k);
    } else if (hemera::from_hex(f[0], id)) {
      if (const std::int64_t j = by_id.find(id, s.particles); j >= 0) index = static_cast<std::uint32_t>(j);
    } else if (strict) {
      return Status::input(at + "'" + std::string(f[0].substr(0, 80)) + "' is not a 64-hex-digit particle id");
    }
    if (!index) {
      if (strict) return Status::input(at + "particle " + std::string(f[0]) + " is not in the snapshot");
      if (unmatched) ++*unmatched;
      continue;
    }
    if (seen[*index]) return Status::input(at + "second entry for particle '" + std::string(f[0].substr(0, 80)) + "'");
    seen[*index] = true;
    if (kind == SideKind::kTitles) {
      auto title = text::unescape_cell(f[1]);
      if (!title) return Status::input(at + "bad backslash escape in the title (use \\\\, \\t, \\n, \\r)");
      s.titles[*index] = std::move(*title);
    } else {
      const auto type = crystal_type_index(f[1]);
      const auto domain = crystal_domain_index(f[2]);
      const auto size = crystal_size_index(f[3]);
      if (!type) return Status::input(at + "unknown crystal type '" + std::string(f[1].substr(0, 40)) + "'");
      if (!domain) return Status::input(at + "unknown crystal domain '" + std::string(f[2].substr(0, 40)) + "'");
      if (!size) return Status::input(at + "unknown crystal size '" + std::string(f[3].substr(0, 40)) + "'");
      s.crystal[*index] = CrystalTag{*type, *domain, *size};
    }
  }
  return Status::ok();
}

std::string format_titles_section(const Snapshot& s) {
  std::string o;
  for (std::size_t i = 0; i < s.titles.size(); ++i) {
    if (s.titles[i].empty()) continue;
    o += hemera::to_hex(s.particles[i]);
    o += '\t';
    o += text::escape_cell(s.titles[i]);
    o += '\n';
  }
  return o;
}

std::string format_crystal_section(const Snapshot& s) {
  std::string o;
  for (std::size_t i = 0; i < s.crystal.size(); ++i) {
    const CrystalTag& t = s.crystal[i];
    if (!t.known()) continue;
    o += hemera::to_hex(s.particles[i]);
    o += '\t';
    o += kCrystalTypes[t.type];
    o += '\t';
    o += kCrystalDomains[t.domain];
    o += '\t';
    o += kCrystalSizes[t.size];
    o += '\n';
  }
  return o;
}

}  // namespace r1::detail
