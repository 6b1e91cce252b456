// The .graph / .cyb container: three rules, every byte kept (R1-IN-002, R1-IN-006).
#include "r1/reference/graph_container.hpp"

#include <set>

#include "toml_subset.hpp"

namespace r1 {

namespace {

// Offset of the first line at or after `from` that starts with "~~~" (a line start is offset 0
// or the byte after an LF), or npos.
std::size_t next_header(std::string_view b, std::size_t from) {
  if (from == 0 && b.substr(0, 3) == "~~~") return 0;
  std::size_t pos = from == 0 ? 0 : from - 1;
  for (;;) {
    const std::size_t nl = b.find("\n~~~", pos);
    if (nl == std::string_view::npos) return nl;
    if (nl + 1 >= from) return nl + 1;
    pos = nl + 1;
  }
}

bool valid_section_name(std::string_view n) {
  if (n.empty() || n.size() > 128) return false;
  for (char c : n)
    if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-' || c == '.'))
      return false;
  return true;
}

std::size_t line_of(std::string_view b, std::size_t offset) {
  std::size_t line = 1;
  for (std::size_t i = 0; i < offset && i < b.size(); ++i) line += b[i] == '\n';
  return line;
}

Result<std::vector<ContainerFile>> read_files_table(std::string_view front, const std::string& file) {
  R1_ASSIGN(toml::table t, toml_subset::parse(front, file));
  const toml::array* arr = t["files"].as_array();
  if (arr == nullptr) return Status::input(file + ": front matter has no [[files]] table");
  std::vector<ContainerFile> files;
  std::set<std::string> seen;
  for (std::size_t i = 0; i < arr->size(); ++i) {
    const std::string where = file + ": front matter [[files]] entry " + std::to_string(i + 1) + ": ";
    const toml::table* e = (*arr)[i].as_table();
    if (e == nullptr) return Status::input(where + "is not a table");
    ContainerFile f;
    const auto name = (*e)["name"].value<std::string>();
    if (!name) return Status::input(where + "needs a string 'name'");
    f.name = *name;
    if (!valid_section_name(f.name)) return Status::input(where + "name '" + f.name + "' is not a valid section name");
    if (!seen.insert(f.name).second) return Status::input(where + "duplicate file name '" + f.name + "'");
    f.format = (*e)["format"].value<std::string>().value_or("");
    if (const auto* sz = (*e)["size"].node()) {
      const auto v = sz->value<std::int64_t>();
      if (!sz->is_integer() || !v || *v < 0) return Status::input(where + "'size' must be a non-negative integer");
      f.size = static_cast<std::uint64_t>(*v);
    }
    files.push_back(std::move(f));
  }
  return files;
}

}  // namespace

const ContainerSection* Container::find(std::string_view name) const {
  for (const auto& s : sections)
    if (s.name == name) return &s;
  return nullptr;
}

std::string Container::serialize() const {
  std::string out(front_matter);
  for (const auto& s : sections) {
    out += s.header;
    out += s.body;
    out += s.separator;
  }
  return out;
}

Result<Container> parse_container(std::string_view b, const std::string& file) {
  if (b.empty()) return Status::input(file + ": empty file");
  Container c;
  std::size_t pos = next_header(b, 0);
  if (pos == std::string_view::npos) return Status::input(file + ": no '~~~' section line: not a .graph file");
  if (pos == 0) return Status::input(file + ":1: the file starts with a section; the TOML front matter is missing");
  c.front_matter = b.substr(0, pos);
  R1_ASSIGN(c.files, read_files_table(c.front_matter, file));

  std::size_t index = 0;
  while (pos < b.size()) {
    const std::size_t line_no = line_of(b, pos);
    const std::string where = file + ":" + std::to_string(line_no) + ": ";
    const std::size_t eol = b.find('\n', pos);
    if (eol == std::string_view::npos) return Status::input(where + "section line without a line end (truncated file?)");
    std::string_view name = b.substr(pos + 3, eol - pos - 3);
    if (!name.empty() && name.back() == '\r') name.remove_suffix(1);
    if (!valid_section_name(name)) return Status::input(where + "bad section name '" + std::string(name.substr(0, 64)) + "'");
    if (index >= c.files.size())
      return Status::input(where + "section '" + std::string(name) + "' has no [[files]] entry in the front matter");
    const ContainerFile& f = c.files[index];
    if (f.name != name)
      return Status::input(where + "section '" + std::string(name) + "' found where [[files]] lists '" + f.name +
                           "' (sections must appear in [[files]] order, each once)");
    ContainerSection s;
    s.name = f.name;
    s.header = std::string(b.substr(pos, eol + 1 - pos));
    s.offset = eol + 1;
    std::size_t next;
    if (f.size) {
      s.binary = true;
      const std::uint64_t avail = b.size() - s.offset;
      if (*f.size > avail)
        return Status::input(file + ": byte " + std::to_string(s.offset) + ": section '" + f.name + "' declares " +
                             std::to_string(*f.size) + " bytes but only " + std::to_string(avail) +
                             " remain (truncated file?)");
      s.body = b.substr(s.offset, static_cast<std::size_t>(*f.size));
      next = s.offset + static_cast<std::size_t>(*f.size);
      if (next < b.size()) {
        // After binary bytes the next section must follow, optionally after one LF.
        std::size_t h = next;
        if (b[h] == '\n') ++h;
        if (b.substr(h, 3) != "~~~")
          return Status::input(file + ": byte " + std::to_string(next) + ": unexpected bytes after binary section '" +
                               f.name + "' (its size is wrong, or the file has trailing data)");
        s.separator = std::string(b.substr(next, h - next));
        next = h;
      }
    } else {
      next = next_header(b, s.offset);
      if (next == std::string_view::npos) next = b.size();
      s.body = b.substr(s.offset, next - s.offset);
    }
    c.sections.push_back(std::move(s));
    ++index;
    pos = next;
  }
  if (index < c.files.size())
    return Status::input(file + ": [[files]] lists '" + c.files[index].name + "' but the file has no such section (truncated file?)");
  return c;
}

}  // namespace r1
