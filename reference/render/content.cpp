// T0 content of an epoch: the side file, the copies and index in the epoch, reading them back
// (spec/epoch.md R1-EPO-030..036).
#include "content.hpp"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <array>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <system_error>
#include <vector>

#include "../snapshot/text_util.hpp"
#include "r1/fixedpoint/hemera.hpp"
#include "r1/reference/input_file.hpp"
#include "r1/reference/intern_index.hpp"

namespace r1::render {

namespace fs = std::filesystem;

namespace {

// Still-image formats OpenImageIO reads (R1-EPO-033). A fixed list rather than "whatever OIIO
// opens": a build of OIIO with its video plugin would otherwise turn a film into its first frame.
constexpr std::array<std::string_view, 14> kImageTypes = {"png", "jpg",  "jpeg", "exr", "tif", "tiff", "bmp",
                                                         "gif", "webp", "tga",  "hdr", "ppm", "pgm",  "pnm"};
// Types that must be UTF-8 text (R1-EPO-033).
constexpr std::array<std::string_view, 4> kTextTypes = {"txt", "text", "md", "markdown"};
// Types r1 does not draw, whatever their bytes (R1-EPO-033): documents, vector drawings, video,
// sound, archives and components get a card naming the type even when their bytes are UTF-8.
constexpr std::array<std::string_view, 22> kOtherTypes = {"pdf", "ps",  "svg",  "mp4", "webm", "mkv", "mov",  "avi",
                                                         "mp3", "ogg", "wav",  "flac", "zip", "gz",  "tar",  "wasm",
                                                         "doc", "docx", "xls", "xlsx", "ppt", "pptx"};

template <std::size_t N>
bool one_of(const std::array<std::string_view, N>& list, std::string_view s) {
  return std::find(list.begin(), list.end(), s) != list.end();
}

// The extension of `p` in lower case, or "" when it has none or one that is not 1..16 ASCII
// letters and digits (so a copy's name in the epoch and its URL in the viewer stay plain).
std::string extension_of(const fs::path& p) {
  std::string e = p.extension().string();
  if (e.size() < 2 || e.size() > 17) return "";
  e.erase(0, 1);
  for (char& c : e) {
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
    else if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9'))) return "";
  }
  return e;
}

bool is_utf8_text(std::string_view s) {
  return !text::find_invalid_utf8(s) && s.find('\0') == std::string_view::npos;
}

std::string digest_hex(std::string_view bytes) {
  return hemera::to_hex(hemera::root_hash(std::span(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size())));
}

// True when OpenImageIO reads an image with at least one pixel and channel from `path`.
bool oiio_reads(const fs::path& path, std::string& why) {
  auto in = OIIO::ImageInput::open(path.string());
  if (!in) {
    why = "OpenImageIO cannot read it as an image";
    (void)OIIO::geterror();  // clear OIIO's per-thread message
    return false;
  }
  const OIIO::ImageSpec& spec = in->spec();
  const bool ok = spec.width > 0 && spec.height > 0 && spec.nchannels > 0;
  if (!ok) why = "an image without pixels";
  in->close();
  return ok;
}

// Resolves, reads and classifies one side-file path (R1-EPO-032, R1-EPO-033) into `e`.
void load_entry(const fs::path& base, const std::string& cell, ContentEntry& e) {
  e.source = cell;
  const fs::path rel_in(cell);
  e.type = extension_of(rel_in);
  const auto fail = [&](ContentStatus st, std::string why) {
    e.status = st;
    e.reason = std::move(why);
  };
  if (rel_in.is_absolute()) return fail(ContentStatus::kRefused, "an absolute path; paths are relative to the side file's folder");
  std::error_code ec;
  // weakly_canonical follows every symbolic link of the part that exists, so a link that points
  // out of the folder is refused like "../x".
  const fs::path target = fs::weakly_canonical(base / rel_in, ec);
  if (ec) return fail(ContentStatus::kUnreadable, ec.message());
  const fs::path rel = target.lexically_relative(base);
  if (rel.empty() || *rel.begin() == ".." || rel == ".")
    return fail(ContentStatus::kRefused, "outside the side file's folder");
  const fs::file_status st = fs::status(target, ec);
  if (!fs::exists(st)) return fail(ContentStatus::kMissing, "no such file");
  if (!fs::is_regular_file(st)) return fail(ContentStatus::kUnreadable, "not a regular file");
  const std::uintmax_t size = fs::file_size(target, ec);
  if (ec) return fail(ContentStatus::kUnreadable, ec.message());
  if (size > kMaxContentBytes) return fail(ContentStatus::kUnreadable, "larger than 64 MiB");
  auto in = InputFile::open(target.string());
  if (!in.is_ok()) return fail(ContentStatus::kUnreadable, in.status().message());
  e.bytes = std::string((*in)->text());
  e.path = target;
  std::string why;
  if (one_of(kImageTypes, e.type)) {
    if (!oiio_reads(target, why)) return fail(ContentStatus::kUnreadable, why);
    e.kind = ContentKind::kImage;
  } else if (one_of(kTextTypes, e.type)) {
    if (!is_utf8_text(e.bytes)) return fail(ContentStatus::kUnreadable, "not UTF-8 text");
    e.kind = ContentKind::kText;
  } else if (!one_of(kOtherTypes, e.type) && is_utf8_text(e.bytes)) {
    e.kind = ContentKind::kText;
    if (e.type.empty()) e.type = "text";
  } else {
    e.kind = ContentKind::kOther;
    if (e.type.empty()) e.type = "binary";
  }
  e.status = ContentStatus::kOk;
  const std::string ext = extension_of(rel_in);
  e.file = "content/" + std::to_string(e.particle) + (ext.empty() ? "" : "." + ext);
}

std::string cell_or_dash(const std::string& s) { return s.empty() ? "-" : text::escape_cell(s); }

}  // namespace

const char* content_status_name(ContentStatus s) {
  switch (s) {
    case ContentStatus::kOk: return "ok";
    case ContentStatus::kMissing: return "missing";
    case ContentStatus::kUnreadable: return "unreadable";
    case ContentStatus::kRefused: return "refused";
  }
  return "?";
}

const char* content_kind_name(ContentKind k) {
  switch (k) {
    case ContentKind::kImage: return "image";
    case ContentKind::kText: return "text";
    case ContentKind::kOther: return "other";
  }
  return "?";
}

Result<ContentSet> read_content_side_file(const fs::path& side, std::span<const ParticleId> ids) {
  R1_ASSIGN(const auto in, InputFile::open(side.string()));
  std::error_code ec;
  const fs::path base = fs::weakly_canonical(fs::absolute(side, ec).parent_path(), ec);
  if (ec) return Status::input(side.string() + ": cannot resolve its folder: " + ec.message());
  const std::vector<ParticleId> table(ids.begin(), ids.end());
  const IdIndex by_id = IdIndex::over(table);
  ContentSet out;
  std::map<std::uint32_t, std::size_t> line_of;  // particle -> side-file line, for the duplicate message
  std::vector<ContentEntry> entries;
  text::LineReader lines(text::strip_bom(in->text()));
  std::string_view line;
  std::vector<std::string_view> fields;
  while (lines.next(line)) {
    const std::string at = side.string() + ":" + std::to_string(lines.line_number()) + ": ";
    if (text::is_blank(line) || line.front() == '#') continue;
    if (const auto bad = text::find_invalid_utf8(line)) return Status::input(at + "not UTF-8 (byte " + std::to_string(*bad + 1) + ")");
    text::split_tabs(line, fields);
    if (fields.size() != 2 || fields[0].empty() || fields[1].empty())
      return Status::input(at + "expected PARTICLE (a name or a 64-hex id), TAB, PATH");
    const auto key = text::unescape_cell(fields[0]);
    const auto path = text::unescape_cell(fields[1]);
    if (!key || !path) return Status::input(at + "a bad backslash escape (\\\\ \\t \\n \\r are allowed)");
    // By name first (a text input's particle id is Hemera(name)), then by hex id, as the overlay
    // resolves particles (R1-ENC): a name that is 64 hex digits is still a name.
    std::int64_t p = by_id.find(hemera::hash(*key), table);
    ParticleId id{};
    if (p < 0 && hemera::from_hex(*key, id)) p = by_id.find(id, table);
    if (p < 0) {
      ++out.unknown;  // one side file may serve many snapshots, as an overlay does
      continue;
    }
    const auto particle = static_cast<std::uint32_t>(p);
    if (const auto it = line_of.find(particle); it != line_of.end())
      return Status::input(at + "a second entry for particle '" + key->substr(0, 80) + "' (the first is line " +
                           std::to_string(it->second) + ")");
    line_of.emplace(particle, lines.line_number());
    ContentEntry e;
    e.particle = particle;
    load_entry(base, *path, e);
    entries.push_back(std::move(e));
  }
  std::sort(entries.begin(), entries.end(), [](const ContentEntry& a, const ContentEntry& b) { return a.particle < b.particle; });
  out.entries = std::move(entries);
  return out;
}

std::vector<std::pair<std::string, std::string>> content_epoch_files(const ContentSet& c) {
  std::vector<std::pair<std::string, std::string>> files;
  std::string index = "# r1 content: particle\tstatus\tkind\ttype\tfile\tbytes\themera\tsource\treason\n";
  for (const ContentEntry& e : c.entries) {
    const bool ok = e.status == ContentStatus::kOk;
    index += std::to_string(e.particle) + "\t" + content_status_name(e.status) + "\t" + (ok ? content_kind_name(e.kind) : "-") +
             "\t" + cell_or_dash(e.type) + "\t" + (ok ? e.file : "-") + "\t" + (ok ? std::to_string(e.bytes.size()) : "-") +
             "\t" + (ok ? digest_hex(e.bytes) : "-") + "\t" + cell_or_dash(e.source) + "\t" + cell_or_dash(e.reason) + "\n";
    if (ok) files.emplace_back(e.file, e.bytes);
  }
  files.insert(files.begin(), {"content.tsv", std::move(index)});
  return files;
}

Result<ContentSet> read_epoch_content(const fs::path& dir, std::size_t n) {
  ContentSet out;
  const fs::path index = dir / "content.tsv";
  std::error_code ec;
  if (!fs::exists(index, ec)) return out;
  R1_ASSIGN(const auto in, InputFile::open(index.string()));
  text::LineReader lines(in->text());
  std::string_view line;
  std::vector<std::string_view> f;
  std::int64_t last = -1;
  while (lines.next(line)) {
    const std::string at = index.string() + ":" + std::to_string(lines.line_number()) + ": ";
    if (line.empty() || line.front() == '#') continue;
    text::split_tabs(line, f);
    if (f.size() != 9) return Status::input(at + "expected 9 fields (particle status kind type file bytes hemera source reason)");
    ContentEntry e;
    const auto p = text::parse_u64(f[0]);
    if (!p || *p >= n || static_cast<std::int64_t>(*p) <= last)
      return Status::input(at + "particle index not below " + std::to_string(n) + " or not ascending");
    last = static_cast<std::int64_t>(*p);
    e.particle = static_cast<std::uint32_t>(*p);
    const auto cell = [](std::string_view s) { return s == "-" ? std::optional<std::string>("") : text::unescape_cell(s); };
    const auto type = cell(f[3]), source = cell(f[7]), reason = cell(f[8]);
    if (!type || !source || !reason) return Status::input(at + "a bad backslash escape");
    e.type = *type, e.source = *source, e.reason = *reason;
    bool known = false;
    for (ContentStatus s : {ContentStatus::kOk, ContentStatus::kMissing, ContentStatus::kUnreadable, ContentStatus::kRefused})
      if (f[1] == content_status_name(s)) e.status = s, known = true;
    if (!known) return Status::input(at + "unknown status '" + std::string(f[1]) + "'");
    if (e.status == ContentStatus::kOk) {
      known = false;
      for (ContentKind k : {ContentKind::kImage, ContentKind::kText, ContentKind::kOther})
        if (f[2] == content_kind_name(k)) e.kind = k, known = true;
      if (!known) return Status::input(at + "unknown kind '" + std::string(f[2]) + "'");
      // The copy's name is the one the writer gives it: nothing else of the file system is read.
      const std::string stem = "content/" + std::to_string(e.particle);
      const std::string_view name = f[4];
      if (!(name == stem || (name.size() > stem.size() + 1 && name.substr(0, stem.size() + 1) == stem + "." &&
                             extension_of(fs::path(std::string(name))) == name.substr(stem.size() + 1))))
        return Status::input(at + "the copy must be named " + stem + "[.ext], not '" + std::string(name) + "'");
      e.file = std::string(name);
      e.path = dir / e.file;
      const auto bytes = text::parse_u64(f[5]);
      if (!bytes) return Status::input(at + "bad byte count '" + std::string(f[5]) + "'");
      R1_ASSIGN(const auto copy, InputFile::open(e.path.string()));
      if (copy->bytes().size() != *bytes)
        return Status::input(e.path.string() + ": " + std::to_string(copy->bytes().size()) + " bytes, content.tsv says " +
                             std::to_string(*bytes));
      e.bytes = std::string(copy->text());
      if (digest_hex(e.bytes) != f[6]) return Status::input(e.path.string() + ": Hemera digest differs from content.tsv");
    }
    out.entries.push_back(std::move(e));
  }
  return out;
}

std::string content_summary(const ContentSet& c) {
  std::size_t kind[3] = {0, 0, 0}, status[4] = {0, 0, 0, 0};
  for (const ContentEntry& e : c.entries) {
    ++status[static_cast<int>(e.status)];
    if (e.status == ContentStatus::kOk) ++kind[static_cast<int>(e.kind)];
  }
  const auto n = [](std::size_t v) { return std::to_string(v); };
  return n(c.entries.size()) + " particle" + (c.entries.size() == 1 ? "" : "s") + ": " + n(kind[0]) + " image, " + n(kind[1]) +
         " text, " + n(kind[2]) + " other; " + n(status[1]) + " missing, " + n(status[2]) + " unreadable, " + n(status[3]) +
         " refused" +
         (c.unknown ? "; " + n(c.unknown) + (c.unknown == 1 ? " entry names" : " entries name") + " no particle of the snapshot" : "");
}

}  // namespace r1::render
