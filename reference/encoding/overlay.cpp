// Metadata overlays: the crystal-v5 preset and the custom TOML format, parse, canonical text, per-particle style (R1-ENC-030..043).
#include <algorithm>
#include <cctype>
#include <memory>
#include <string>

#include "../snapshot/toml_subset.hpp"
#include "r1/reference/encoding.hpp"
#include "r1/reference/input_file.hpp"

namespace r1 {

namespace {

// A particle key longer than this is refused: with TOML escapes (at most 6 bytes per byte) a
// canonical line stays under the 4096-byte line limit of the subset, so every accepted overlay
// writes back and reads again (R1-ENC-043). Longer names can use the 64-hex id.
constexpr std::size_t kMaxKeyBytes = 512;

std::string lower(std::string_view s) {
  std::string out(s);
  for (auto& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::optional<Shape> shape_index(std::string_view name) {
  const std::string l = lower(name);
  for (std::size_t i = 0; i < kShapeNames.size(); ++i)
    if (l == kShapeNames[i]) return static_cast<Shape>(i);
  return std::nullopt;
}

int hex_digit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

std::optional<Rgb8> parse_color(std::string_view s) {
  if (s.size() != 7 || s[0] != '#') return std::nullopt;
  Rgb8 out{};
  for (std::size_t k = 0; k < 3; ++k) {
    const int hi = hex_digit(s[1 + 2 * k]), lo = hex_digit(s[2 + 2 * k]);
    if (hi < 0 || lo < 0) return std::nullopt;
    out[k] = static_cast<std::uint8_t>(hi * 16 + lo);
  }
  return out;
}

std::string color_text(const Rgb8& c) {
  constexpr char kHex[] = "0123456789abcdef";
  std::string out = "#";
  for (const auto b : c) {
    out.push_back(kHex[b >> 4]);
    out.push_back(kHex[b & 15]);
  }
  return out;
}

bool size_in_range(Q32 m) { return m.raw > 0 && m.raw <= kMaxSizeMultiplier * Q32::kOneRaw; }

// Whether a decimal text that Q32 already accepted (R1-NUM-016 grammar) is exactly above 16.
// Only asked when it rounds to 16: values within half a raw unit above 16 round down to 16, and
// R1-ENC-040 bounds the decimal itself. Value = 0.D x 10^P with D the significant digits (no
// leading or trailing zeros); it exceeds 0.16 x 10^2 iff P > 2, or P = 2 and D > "16" as digit
// strings (with trailing zeros stripped, lexicographic order is numeric order).
bool decimal_exceeds_16(std::string_view text) {
  std::size_t i = 0;
  if (i < text.size() && (text[i] == '+' || text[i] == '-')) {
    if (text[i] == '-') return false;
    ++i;
  }
  std::string digits;
  std::int64_t point = 0;  // digits before the decimal point
  bool seen_point = false;
  for (; i < text.size() && text[i] != 'e' && text[i] != 'E'; ++i) {
    if (text[i] == '.') {
      seen_point = true;
      continue;
    }
    digits.push_back(text[i]);
    if (!seen_point) ++point;
  }
  std::int64_t exp = 0;
  if (i < text.size()) {
    ++i;
    bool neg = false;
    if (i < text.size() && (text[i] == '+' || text[i] == '-')) neg = text[i++] == '-';
    // Saturate: any exponent beyond 10^6 decides the comparison the same way.
    for (; i < text.size(); ++i) exp = std::min<std::int64_t>(exp * 10 + (text[i] - '0'), 1000000);
    if (neg) exp = -exp;
  }
  const std::size_t first = digits.find_first_not_of('0');
  if (first == std::string::npos) return false;  // zero
  const std::size_t last = digits.find_last_not_of('0');
  const std::int64_t p = point - static_cast<std::int64_t>(first) + exp;
  const std::string d = digits.substr(first, last - first + 1);
  return p > 2 || (p == 2 && d > "16");
}

// A TOML string for a key or value: a literal string when it needs no escape (the shortest form
// the subset accepts), else a basic string with the short escapes and \uXXXX for other controls.
std::string toml_string(std::string_view s) {
  const bool literal_ok = std::none_of(s.begin(), s.end(), [](char c) {
    const auto u = static_cast<unsigned char>(c);
    return c == '\'' || (u < 0x20 && c != '\t') || u == 0x7F;
  });
  if (literal_ok) return "'" + std::string(s) + "'";
  std::string out = "\"";
  for (const char c : s) {
    const auto u = static_cast<unsigned char>(c);
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\b': out += "\\b"; break;
      case '\n': out += "\\n"; break;
      case '\f': out += "\\f"; break;
      case '\r': out += "\\r"; break;
      default:
        if ((u < 0x20 && c != '\t') || u == 0x7F) {
          constexpr char kHex[] = "0123456789ABCDEF";
          out += "\\u00";
          out.push_back(kHex[u >> 4]);
          out.push_back(kHex[u & 15]);
        } else {
          out.push_back(c);
        }
    }
  }
  return out + "\"";
}

class Parser {
 public:
  explicit Parser(std::string name) : name_(std::move(name)) {}

  Result<CustomOverlay> run(const toml::table& root) {
    for (auto&& [k, v] : root) {
      const std::string key(k.str());
      const auto* t = v.as_table();
      if (key != "overlay" && key != "type" && key != "domain" && key != "size" && key != "particle")
        return err(k, "unknown key '" + key.substr(0, 80) + "' (tables: overlay, type, domain, size, particle)");
      if (!t) return err(k, "[" + key + "] must be a table");
      Status st;
      if (key == "overlay") st = overlay(*t);
      if (key == "type") st = names(*t, "type", &crystal_type_index, out_.type_shape);
      if (key == "domain") st = names(*t, "domain", &crystal_domain_index, out_.domain_color);
      if (key == "size") st = names(*t, "size", &crystal_size_index, out_.size_multiplier);
      if (key == "particle") st = particles(*t);
      R1_TRY(st);
    }
    std::sort(out_.particles.begin(), out_.particles.end(),
              [](const OverlayParticle& a, const OverlayParticle& b) { return a.key < b.key; });
    return out_;
  }

 private:
  static std::size_t line_of(const toml::source_region& r) { return r.begin.line; }
  Status err(const toml::key& k, const std::string& why) const { return err_at(line_of(k.source()), why); }
  Status err(const toml::node& n, const std::string& why) const { return err_at(line_of(n.source()), why); }
  Status err_at(std::size_t line, const std::string& why) const {
    return Status::input(name_ + ":" + std::to_string(line) + ": " + why);
  }

  Status overlay(const toml::table& t) {
    for (auto&& [k, v] : t) {
      if (k.str() != "version") return err(k, "unknown field '" + std::string(k.str()).substr(0, 80) + "' in [overlay] (version)");
      const auto* i = v.as_integer();
      if (!i || i->get() != 1) return err(v, "overlay version must be the integer 1");
    }
    return Status::ok();
  }

  // Values of the [type], [domain] and [size] tables.
  Result<Shape> value_of(const toml::node& v, Shape*) const {
    const auto* s = v.as_string();
    const auto shape = s ? shape_index(s->get()) : std::nullopt;
    if (!shape) return err(v, "shape must be one of sphere, torus, tetrahedron, cube, octahedron, cylinder");
    return *shape;
  }
  Result<Rgb8> value_of(const toml::node& v, Rgb8*) const {
    const auto* s = v.as_string();
    const auto c = s ? parse_color(s->get()) : std::nullopt;
    if (!c) return err(v, "colour must be \"#rrggbb\" (six hex digits)");
    return *c;
  }
  Result<Q32> value_of(const toml::node& v, Q32*) const {
    std::optional<Q32> m;
    if (const auto* i = v.as_integer()) {
      if (i->get() > 0 && i->get() <= kMaxSizeMultiplier) m = Q32::from_int(i->get());
    } else if (const auto* s = v.as_string()) {
      m = Q32::checked_from_decimal(s->get());
      if (m && m->raw == kMaxSizeMultiplier * Q32::kOneRaw && decimal_exceeds_16(s->get())) m.reset();
    }
    if (!m || !size_in_range(*m)) return err(v, "size multiplier must be a decimal in (0, 16], e.g. 2 or \"1.5\"");
    return *m;
  }

  template <class T, std::size_t N, class Index>
  Status names(const toml::table& t, const char* what, Index index, std::array<std::optional<T>, N>& out) {
    std::array<std::size_t, N> line{};
    for (auto&& [k, v] : t) {
      const auto i = index(k.str());
      if (!i) return err(k, std::string("unknown crystal ") + what + " '" + std::string(k.str()).substr(0, 80) + "'");
      // The same name in another case: report the later line, the one to fix.
      if (out[*i]) return err_at(std::max(line[*i], line_of(k.source())), std::string("crystal ") + what + " '" +
                                                                               std::string(k.str()).substr(0, 80) + "' given twice");
      R1_ASSIGN(out[*i], value_of(v, static_cast<T*>(nullptr)));
      line[*i] = line_of(k.source());
    }
    return Status::ok();
  }

  Status particles(const toml::table& t) {
    for (auto&& [k, v] : t) {
      if (k.str().empty() || k.str().size() > kMaxKeyBytes)
        return err(k, "a particle key must be a name or id of 1 to 512 bytes");
      const auto* e = v.as_table();
      if (!e) return err(v, "particle entry must be a table, e.g. { shape = \"cube\" }");
      OverlayParticle p;
      p.key = std::string(k.str());
      p.line = line_of(k.source());
      for (auto&& [fk, fv] : *e) {
        if (fk.str() == "shape") {
          R1_ASSIGN(p.style.shape, value_of(fv, static_cast<Shape*>(nullptr)));
        } else if (fk.str() == "color") {
          R1_ASSIGN(p.style.color, value_of(fv, static_cast<Rgb8*>(nullptr)));
        } else if (fk.str() == "size") {
          R1_ASSIGN(p.style.size, value_of(fv, static_cast<Q32*>(nullptr)));
        } else {
          return err(fk, "unknown field '" + std::string(fk.str()).substr(0, 80) + "' (shape, color, size)");
        }
      }
      if (!p.style.shape && !p.style.color && !p.style.size) return err(k, "particle entry sets nothing (shape, color, size)");
      out_.particles.push_back(std::move(p));
    }
    return Status::ok();
  }

  std::string name_;
  CustomOverlay out_;
};

CustomOverlay make_crystal_v5() {
  CustomOverlay o;
  // Type -> shape in kCrystalTypes order: entity, process, property, relation, measure, pattern.
  constexpr std::array<Shape, 6> kTypeShape = {Shape::kSphere, Shape::kTorus, Shape::kTetrahedron,
                                               Shape::kCube, Shape::kOctahedron, Shape::kCylinder};
  for (std::size_t t = 0; t < kTypeShape.size(); ++t) o.type_shape[t] = kTypeShape[t];
  // Triad hues in degrees (FORM .. PLAY); degrees / 60 is an exact Q32 for each.
  constexpr std::array<std::int64_t, 7> kTriadHueDeg = {0, 30, 120, 150, 210, 270, 330};
  constexpr std::array<std::uint32_t, 3> kLightnessPermille = {400, 550, 700};
  const Q32 saturation = Q32::from_raw(3 * (Q32::kOneRaw / 4));  // 0.75, exact
  for (std::size_t d = 0; d < kCrystalDomains.size(); ++d) {
    const Q32 sixths = Q32::from_raw(kTriadHueDeg[d / 3] * Q32::kOneRaw / 60);
    o.domain_color[d] = hsl_to_srgb8(sixths, saturation, kLightnessPermille[d % 3]);
  }
  // atom, enzyme, bridge, article, deep; 1.4 rounds to the nearest Q32 (R1-ENC-031).
  constexpr std::array<const char*, 5> kSize = {"0.5", "0.75", "1", "1.4", "2"};
  for (std::size_t s = 0; s < kSize.size(); ++s) o.size_multiplier[s] = Q32::from_decimal(kSize[s]);
  return o;
}

}  // namespace

const CustomOverlay& crystal_v5_overlay() {
  static const CustomOverlay kOverlay = make_crystal_v5();
  return kOverlay;
}

Result<CustomOverlay> parse_custom_overlay(std::string_view text, const std::string& name) {
  R1_ASSIGN(const toml::table root, toml_subset::parse(text, name));
  return Parser(name).run(root);
}

Result<CustomOverlay> read_custom_overlay(const std::string& path) {
  R1_ASSIGN(auto file, InputFile::open(path));
  return parse_custom_overlay(file->text(), file->name());
}

Status load_custom_overlay(EncodingOptions& options, const std::string& path) {
  if (path.empty()) return Status::ok();
  R1_ASSIGN(CustomOverlay overlay, read_custom_overlay(path));
  options.custom = std::make_shared<const CustomOverlay>(std::move(overlay));
  options.custom_name = path;
  return Status::ok();
}

std::string custom_overlay_text(const CustomOverlay& o) {
  std::string out = "# r1 custom overlay (spec/encoding.md R1-ENC-040)\n[overlay]\nversion = 1\n";
  auto table = [&](const char* name, const auto& values, const auto& names, auto text) {
    bool any = false;
    for (std::size_t i = 0; i < values.size(); ++i) {
      if (!values[i]) continue;
      if (!any) out += std::string("\n[") + name + "]\n";
      any = true;
      out += std::string(names[i]) + " = " + text(*values[i]) + "\n";
    }
  };
  auto shape_text = [](Shape s) { return "\"" + std::string(kShapeNames[static_cast<std::size_t>(s)]) + "\""; };
  auto color_value = [](const Rgb8& c) { return "\"" + color_text(c) + "\""; };
  auto size_text = [](Q32 m) { return "\"" + m.to_string() + "\""; };
  table("type", o.type_shape, kCrystalTypes, shape_text);
  table("domain", o.domain_color, kCrystalDomains, color_value);
  table("size", o.size_multiplier, kCrystalSizes, size_text);
  std::vector<const OverlayParticle*> ps;
  for (const auto& p : o.particles) ps.push_back(&p);
  std::sort(ps.begin(), ps.end(), [](const OverlayParticle* a, const OverlayParticle* b) { return a->key < b->key; });
  if (!ps.empty()) out += "\n[particle]\n";
  for (const auto* p : ps) {
    std::string fields;
    auto field = [&](const std::string& f) { fields += (fields.empty() ? "" : ", ") + f; };
    if (p->style.shape) field("shape = " + shape_text(*p->style.shape));
    if (p->style.color) field("color = " + color_value(*p->style.color));
    if (p->style.size) field("size = " + size_text(*p->style.size));
    out += toml_string(p->key) + " = { " + fields + " }\n";
  }
  return out;
}

OverlayStyle overlay_style(const CustomOverlay& o, const CrystalTag& tag, const OverlayStyle* own) {
  OverlayStyle s;
  // Field by field through the crystal metadata (R1-ENC-041); kUnknown fields match nothing.
  if (tag.type < o.type_shape.size()) s.shape = o.type_shape[tag.type];
  if (tag.domain < o.domain_color.size()) s.color = o.domain_color[tag.domain];
  if (tag.size < o.size_multiplier.size()) s.size = o.size_multiplier[tag.size];
  if (own) {
    if (own->shape) s.shape = own->shape;
    if (own->color) s.color = own->color;
    if (own->size) s.size = own->size;
  }
  return s;
}

}  // namespace r1
