// Text-input helpers: UTF-8 validation, exact decimal weights, escapes (R1-IN-013, R1-IN-016).
#include "text_util.hpp"

#include "r1/fixedpoint/q32.hpp"

#include <boost/multiprecision/cpp_int.hpp>

#include <algorithm>
#include <cstring>

namespace r1::text {

std::optional<std::size_t> find_invalid_utf8(std::string_view s) {
  const auto* p = reinterpret_cast<const unsigned char*>(s.data());
  const std::size_t n = s.size();
  std::size_t i = 0;
  while (i < n) {
    const unsigned char c = p[i];
    if (c < 0x80) {
      ++i;
      continue;
    }
    std::size_t len;
    std::uint32_t cp;
    if (c >= 0xC2 && c <= 0xDF) {
      len = 2;
      cp = c & 0x1Fu;
    } else if (c >= 0xE0 && c <= 0xEF) {
      len = 3;
      cp = c & 0x0Fu;
    } else if (c >= 0xF0 && c <= 0xF4) {
      len = 4;
      cp = c & 0x07u;
    } else {
      return i;  // continuation byte without a lead, 0xC0/0xC1 (overlong) or 0xF5..0xFF
    }
    if (i + len > n) return i;
    for (std::size_t k = 1; k < len; ++k) {
      if ((p[i + k] & 0xC0u) != 0x80u) return i;
      cp = (cp << 6) | (p[i + k] & 0x3Fu);
    }
    // Overlong 3/4-byte forms, UTF-16 surrogates and values above U+10FFFF are not UTF-8.
    if ((len == 3 && cp < 0x800) || (len == 4 && (cp < 0x10000 || cp > 0x10FFFF)) || (cp >= 0xD800 && cp <= 0xDFFF))
      return i;
    i += len;
  }
  return std::nullopt;
}

namespace {

bool iequals(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
         });
}

bool is_digit(char c) { return c >= '0' && c <= '9'; }

// Amounts must fit the record's u128 and be at least one unit (2^-32).
constexpr const char* kTooLarge = "weight is too large (at most 2^96)";

}  // namespace

WeightResult parse_weight(std::string_view f) {
  WeightResult r;
  if (f.empty()) {
    r.error = "empty weight";
    return r;
  }
  {
    std::string_view t = f;
    if (t.front() == '+' || t.front() == '-') t.remove_prefix(1);
    if (iequals(t, "nan") || iequals(t, "inf") || iequals(t, "infinity")) {
      r.error = "weight '" + std::string(f) + "' is not a finite number";
      return r;
    }
  }
  std::size_t i = 0;
  if (f[i] == '-') {
    r.error = "weight '" + std::string(f) + "' is negative; weights must be positive";
    return r;
  }
  if (f[i] == '+') ++i;
  // Mantissa digits without leading zeros, and the decimal exponent they carry.
  std::string digits;
  std::int64_t exp10 = 0;
  bool any_digit = false;
  while (i < f.size() && is_digit(f[i])) {
    any_digit = true;
    if (!(digits.empty() && f[i] == '0')) digits.push_back(f[i]);
    ++i;
  }
  if (i < f.size() && f[i] == '.') {
    ++i;
    while (i < f.size() && is_digit(f[i])) {
      any_digit = true;
      if (!(digits.empty() && f[i] == '0')) digits.push_back(f[i]);
      --exp10;
      ++i;
    }
  }
  if (!any_digit) {
    r.error = "weight '" + std::string(f) + "' is not a number";
    return r;
  }
  if (i < f.size() && (f[i] == 'e' || f[i] == 'E')) {
    ++i;
    bool neg = false;
    if (i < f.size() && (f[i] == '+' || f[i] == '-')) neg = f[i++] == '-';
    if (i == f.size()) {
      r.error = "weight '" + std::string(f) + "' has an empty exponent";
      return r;
    }
    std::int64_t e = 0;
    while (i < f.size() && is_digit(f[i])) {
      // Exponents beyond +-10^6 over- or underflow any weight; clamp to keep the arithmetic small.
      e = std::min<std::int64_t>(e * 10 + (f[i] - '0'), 1000000);
      ++i;
    }
    exp10 += neg ? -e : e;
  }
  if (i != f.size()) {
    r.error = "weight '" + std::string(f) + "' is not a number";
    return r;
  }
  if (digits.empty()) {
    r.error = "weight is zero; weights must be positive";
    return r;
  }
  // The digits strip leading zeros only; trailing zeros could be folded into the exponent but
  // the exact arithmetic below does not need it.
  const std::int64_t magnitude = static_cast<std::int64_t>(digits.size()) + exp10;  // value < 10^magnitude
  if (magnitude > 30) {  // >= 10^30 > 2^96
    r.error = kTooLarge;
    return r;
  }
  if (magnitude < -12) {  // < 10^-12 < 2^-33: rounds to zero units
    r.error = "weight '" + std::string(f) + "' is below 2^-33 and rounds to zero";
    return r;
  }
  // Exact: amount = round_half_even(digits * 10^exp10 * 2^32), ties to even so that halves of a
  // unit do not drift one way. Fast path in 128 bits for up to 19 significant digits (every
  // weight a person types); cpp_int otherwise.
  if (digits.size() <= 19 && magnitude <= 19 && exp10 >= -19) {
    u128 num = 0;
    for (char c : digits) num = num * 10 + static_cast<unsigned>(c - '0');
    for (std::int64_t k = 0; k < exp10; ++k) num *= 10;  // digits + exp10 <= 19: stays < 10^19
    num <<= 32;                                            // < 2^96
    u128 den = 1;
    for (std::int64_t k = 0; k < -exp10; ++k) den *= 10;
    u128 q = num / den;
    const u128 rem = num - q * den;
    if (rem * 2 > den || (rem * 2 == den && (q & 1) != 0)) ++q;
    if (q == 0) {
      r.error = "weight '" + std::string(f) + "' is below 2^-33 and rounds to zero";
      return r;
    }
    r.amount = q;
    return r;
  }
  using boost::multiprecision::cpp_int;
  cpp_int num(digits);
  num <<= 32;
  cpp_int den = 1;
  if (exp10 >= 0) {
    num *= boost::multiprecision::pow(cpp_int(10), static_cast<unsigned>(exp10));
  } else {
    den = boost::multiprecision::pow(cpp_int(10), static_cast<unsigned>(-exp10));
  }
  cpp_int q = num / den;
  const cpp_int rem = num - q * den;
  const cpp_int twice = rem * 2;
  if (twice > den || (twice == den && (q & 1) != 0)) ++q;
  if (q == 0) {
    r.error = "weight '" + std::string(f) + "' is below 2^-33 and rounds to zero";
    return r;
  }
  if (q >= (cpp_int(1) << 128)) {
    r.error = kTooLarge;
    return r;
  }
  const std::uint64_t lo = static_cast<std::uint64_t>(q & cpp_int(~std::uint64_t{0}));
  const std::uint64_t hi = static_cast<std::uint64_t>(q >> 64);
  r.amount = (static_cast<u128>(hi) << 64) | lo;
  return r;
}

std::string format_weight(u128 amount) {
  // Integer part, then the 32 fractional bits as an exact decimal (each bit is a finite decimal).
  const u128 ip = amount >> 32;
  const std::uint64_t frac = static_cast<std::uint64_t>(amount & 0xFFFFFFFFu);
  std::string s;
  u128 v = ip;
  do {
    s.push_back(static_cast<char>('0' + static_cast<int>(v % 10)));
    v /= 10;
  } while (v != 0);
  std::reverse(s.begin(), s.end());
  if (frac != 0) s += "." + fx::exact_fraction_digits(static_cast<std::uint32_t>(frac));
  return s;
}

std::optional<std::int8_t> parse_valence(std::string_view f) {
  if (f == "1" || f == "+1") return 1;
  if (f == "0" || f == "+0" || f == "-0") return 0;
  if (f == "-1") return -1;
  return std::nullopt;
}

std::optional<std::uint64_t> parse_u64(std::string_view f) {
  if (f.empty() || f.size() > 20) return std::nullopt;
  u128 v = 0;
  for (char c : f) {
    if (!is_digit(c)) return std::nullopt;
    v = v * 10 + static_cast<unsigned>(c - '0');
  }
  if (v > ~std::uint64_t{0}) return std::nullopt;
  return static_cast<std::uint64_t>(v);
}

std::string escape_cell(std::string_view s) {
  std::string o;
  o.reserve(s.size());
  for (char c : s) {
    switch (c) {
      case '\\': o += "\\\\"; break;
      case '\t': o += "\\t"; break;
      case '\n': o += "\\n"; break;
      case '\r': o += "\\r"; break;
      default: o.push_back(c);
    }
  }
  return o;
}

std::optional<std::string> unescape_cell(std::string_view s) {
  std::string o;
  o.reserve(s.size());
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i] != '\\') {
      o.push_back(s[i]);
      continue;
    }
    if (++i == s.size()) return std::nullopt;
    switch (s[i]) {
      case '\\': o.push_back('\\'); break;
      case 't': o.push_back('\t'); break;
      case 'n': o.push_back('\n'); break;
      case 'r': o.push_back('\r'); break;
      default: return std::nullopt;
    }
  }
  return o;
}

bool LineReader::next(std::string_view& line) {
  if (pos_ >= text_.size()) return false;
  const char* start = text_.data() + pos_;
  const void* nl = std::memchr(start, '\n', text_.size() - pos_);
  const std::size_t end = nl ? static_cast<std::size_t>(static_cast<const char*>(nl) - text_.data()) : text_.size();
  offset_ = pos_;
  line = text_.substr(pos_, end - pos_);
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  pos_ = nl ? end + 1 : end;
  ++number_;
  return true;
}

void split_tabs(std::string_view line, std::vector<std::string_view>& out) {
  out.clear();
  std::size_t p = 0;
  for (;;) {
    const std::size_t t = line.find('\t', p);
    out.push_back(line.substr(p, t == std::string_view::npos ? std::string_view::npos : t - p));
    if (t == std::string_view::npos) return;
    p = t + 1;
  }
}

bool is_blank(std::string_view line) {
  return std::all_of(line.begin(), line.end(), [](char c) { return c == ' ' || c == '\t'; });
}

std::string_view strip_bom(std::string_view text) {
  if (text.size() >= 3 && text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);
  return text;
}

}  // namespace r1::text
