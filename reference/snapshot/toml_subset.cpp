// The narrow TOML subset r1 accepts (R1-IN-005): comments, [table] and [[array]] headers,
// key = value with single-line strings, integers, booleans, arrays and inline tables of those.
#include "toml_subset.hpp"

#include <cctype>
#include <charconv>

#include "text_util.hpp"

namespace r1::toml_subset {

namespace {

constexpr int kMaxDepth = 4;  // nesting of arrays/inline tables on one line
// Parts of one dotted key or table name: each part is a level of tables in toml++'s tree, so an
// unbounded count would nest without limit (a fuzzer found 70 levels in one key). r1's files use 3.
constexpr int kMaxKeyParts = 8;

class LineParser {
 public:
  explicit LineParser(std::string_view s) : s_(s) {}

  // Returns an empty string when the line is valid, else why not.
  std::string line() {
    ws();
    if (done() || peek() == '#') return {};
    if (peek() == '[') {
      const bool array = s_.size() > i_ + 1 && s_[i_ + 1] == '[';
      i_ += array ? 2 : 1;
      ws();
      if (auto e = key_path(); !e.empty()) return e;
      ws();
      if (!eat(']') || (array && !eat(']'))) return array ? "expected ']]' after the table name" : "expected ']' after the table name";
      return rest();
    }
    if (auto e = key_path(); !e.empty()) return e;
    ws();
    if (!eat('=')) return "expected '=' after the key";
    ws();
    if (auto e = value(0); !e.empty()) return e;
    return rest();
  }

 private:
  bool done() const { return i_ >= s_.size(); }
  char peek() const { return s_[i_]; }
  bool eat(char c) {
    if (!done() && peek() == c) {
      ++i_;
      return true;
    }
    return false;
  }
  void ws() {
    while (!done() && (peek() == ' ' || peek() == '\t')) ++i_;
  }
  std::string rest() {
    ws();
    if (done() || peek() == '#') return {};
    return "unexpected text after the value";
  }
  static bool bare(char c) {
    return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
  }
  std::string key() {
    if (done()) return "expected a key";
    if (peek() == '"' || peek() == '\'') return string();
    const std::size_t start = i_;
    while (!done() && bare(peek())) ++i_;
    return i_ == start ? "expected a key (letters, digits, '_', '-' or a quoted string)" : std::string();
  }
  std::string key_path() {
    for (int parts = 1;; ++parts) {
      if (parts > kMaxKeyParts) return "a dotted key has more than 8 parts";
      if (auto e = key(); !e.empty()) return e;
      ws();
      if (!eat('.')) return {};
      ws();
    }
  }
  std::string string() {
    const char q = s_[i_++];
    if (s_.size() >= i_ + 2 && s_[i_] == q && s_[i_ + 1] == q) return "multi-line strings are not supported";
    while (!done()) {
      const char c = s_[i_++];
      if (c == q) return {};
      if (static_cast<unsigned char>(c) < 0x20 && c != '\t') return "control character inside a string";
      if (c == 0x7F) return "control character inside a string";
      if (q == '"' && c == '\\') {
        if (done()) break;
        const char e = s_[i_++];
        if (e == 'u' || e == 'U') {
          const std::size_t n = e == 'u' ? 4 : 8;
          for (std::size_t k = 0; k < n; ++k, ++i_)
            if (done() || !std::isxdigit(static_cast<unsigned char>(peek()))) return "bad \\u escape in a string";
        } else if (std::string_view("btnfr\"\\").find(e) == std::string_view::npos) {
          return "bad escape in a string";
        }
      }
    }
    return "unterminated string";
  }
  std::string integer() {
    if (!done() && (peek() == '+' || peek() == '-')) ++i_;
    const std::size_t digits = i_;
    while (!done() && ((peek() >= '0' && peek() <= '9') || peek() == '_')) ++i_;
    if (i_ == digits) return "expected a value";
    const std::string_view num = s_.substr(digits, i_ - digits);
    if (num.front() == '_' || num.back() == '_' || num.find("__") != std::string_view::npos)
      return "malformed integer";
    if (num.size() > 1 && num.front() == '0') return "integers may not have leading zeros";
    if (!done() && (peek() == '.' || peek() == 'e' || peek() == 'E' || peek() == ':' || peek() == 'T' || peek() == 'x' ||
                    peek() == 'o' || peek() == 'b'))
      return "only decimal integers are supported (no floats, dates or hex)";
    return {};
  }
  std::string value(int depth) {
    if (depth > kMaxDepth) return "values nest too deeply";
    if (done()) return "expected a value";
    const char c = peek();
    if (c == '"' || c == '\'') return string();
    if (s_.substr(i_, 4) == "true") {
      i_ += 4;
      return {};
    }
    if (s_.substr(i_, 5) == "false") {
      i_ += 5;
      return {};
    }
    if (c == '[') {
      ++i_;
      ws();
      if (eat(']')) return {};
      for (;;) {
        if (auto e = value(depth + 1); !e.empty()) return e;
        ws();
        if (eat(']')) return {};
        if (!eat(',')) return "expected ',' or ']' in an array";
        ws();
        if (eat(']')) return {};  // trailing comma
      }
    }
    if (c == '{') {
      ++i_;
      ws();
      if (eat('}')) return {};
      for (;;) {
        if (auto e = key_path(); !e.empty()) return e;
        ws();
        if (!eat('=')) return "expected '=' in an inline table";
        ws();
        if (auto e = value(depth + 1); !e.empty()) return e;
        ws();
        if (eat('}')) return {};
        if (!eat(',')) return "expected ',' or '}' in an inline table";
        ws();
      }
    }
    return integer();
  }

  std::string_view s_;
  std::size_t i_ = 0;
};

}  // namespace

Status check(std::string_view text, const std::string& name, std::size_t first_line) {
  if (text.size() > kMaxBytes) return Status::input(name + ": TOML text is larger than 1 MiB");
  if (auto bad = text::find_invalid_utf8(text))
    return Status::input(name + ": byte " + std::to_string(*bad) + ": TOML text is not valid UTF-8");
  text::LineReader lines(text);
  std::string_view line;
  while (lines.next(line)) {
    const std::string where = name + ":" + std::to_string(first_line + lines.line_number() - 1) + ": ";
    if (line.size() > kMaxLine) return Status::input(where + "TOML line longer than 4096 bytes");
    if (line.find('\0') != std::string_view::npos) return Status::input(where + "NUL byte in TOML text");
    if (auto e = LineParser(line).line(); !e.empty()) return Status::input(where + e + " (r1 reads a narrow TOML subset)");
  }
  return Status::ok();
}

Result<toml::table> parse(std::string_view text, const std::string& name, std::size_t first_line) {
  R1_TRY(check(text, name, first_line));
  try {
    return toml::parse(text, name);
  } catch (const toml::parse_error& e) {
    const auto line = static_cast<std::size_t>(e.source().begin.line);
    return Status::input(name + ":" + std::to_string(first_line + (line > 0 ? line - 1 : 0)) + ": " +
                         std::string(e.description()));
  }
}

std::optional<double> decimal(const toml::node& n) {
  if (const auto* i = n.as_integer()) return static_cast<double>(i->get());
  const auto* s = n.as_string();
  if (!s) return std::nullopt;
  const std::string& t = s->get();
  std::size_t k = (!t.empty() && (t[0] == '-' || t[0] == '+')) ? 1 : 0;
  const std::size_t int_start = k;
  while (k < t.size() && t[k] >= '0' && t[k] <= '9') ++k;
  if (k == int_start) return std::nullopt;
  if (k < t.size() && t[k] == '.') {
    const std::size_t frac = ++k;
    while (k < t.size() && t[k] >= '0' && t[k] <= '9') ++k;
    if (k == frac) return std::nullopt;
  }
  if (k != t.size() || t.size() > 40) return std::nullopt;
  double v = 0;
  const char* first = t.data() + (t[0] == '+' ? 1 : 0);
  if (std::from_chars(first, t.data() + t.size(), v).ec != std::errc()) return std::nullopt;
  return v;
}

}  // namespace r1::toml_subset
