// Q32 conversions: double, decimal text, shortest and exact printing (R1-NUM-012..017).
#include "r1/fixedpoint/q32.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <ostream>
#include <vector>

namespace r1::fx {

namespace detail {

void throw_overflow(const char* op) { throw OverflowError(std::string("Q32 overflow in ") + op); }
void throw_domain(const char* what) { throw DomainError(std::string("Q32 domain error: ") + what); }

}  // namespace detail

namespace {

constexpr std::uint64_t kFracMask = (std::uint64_t{1} << 32) - 1;

// Largest magnitude a Q32 of the given sign can hold: 2^63 - 1 above zero, 2^63 below.
constexpr u128 magnitude_limit(bool negative) {
  return negative ? u128{1} << 63 : static_cast<u128>(INT64_MAX);
}

std::optional<Q32> with_sign(u128 magnitude, bool negative) {
  if (magnitude > magnitude_limit(negative)) return std::nullopt;
  const auto m = static_cast<std::uint64_t>(magnitude);
  // 0 - m in unsigned arithmetic then a modular conversion: exact for m = 2^63 as well.
  return Q32{negative ? static_cast<std::int64_t>(std::uint64_t{0} - m) : static_cast<std::int64_t>(m)};
}

enum class FromDouble { kOk, kNaN, kOverflow };

FromDouble convert_double(double d, Q32& out) {
  const auto bits = std::bit_cast<std::uint64_t>(d);
  const bool negative = (bits >> 63) != 0;
  const int biased = static_cast<int>((bits >> 52) & 0x7FF);
  const std::uint64_t fraction = bits & ((std::uint64_t{1} << 52) - 1);
  if (biased == 0x7FF) return fraction != 0 ? FromDouble::kNaN : FromDouble::kOverflow;
  if (biased == 0) {  // zero or subnormal: |d| < 2^-1022 rounds to 0
    out = Q32{0};
    return FromDouble::kOk;
  }
  // d = m * 2^(biased - 1075) with a 53-bit m, so raw = m * 2^(biased - 1043) before rounding.
  const std::uint64_t m = fraction | (std::uint64_t{1} << 52);
  const int e2 = biased - 1043;
  u128 magnitude = 0;
  if (e2 >= 0) {
    // m >= 2^52, so a shift above 11 gives at least 2^64, beyond every Q32.
    if (e2 > 11) return FromDouble::kOverflow;
    magnitude = static_cast<u128>(m) << e2;
  } else if (-e2 <= 54) {
    magnitude = static_cast<u128>(detail::rne_shift(static_cast<i128>(m), -e2));
  }
  // else: m * 2^e2 < 2^53 * 2^-55 = 1/4 of a raw unit, which rounds to 0.
  const auto q = with_sign(magnitude, negative);
  if (!q) return FromDouble::kOverflow;
  out = *q;
  return FromDouble::kOk;
}

// ---- decimal text --------------------------------------------------------------------------

enum class ParseStatus { kOk, kSyntax, kOverflow };

struct ParseResult {
  ParseStatus status = ParseStatus::kOk;
  std::size_t error_pos = 0;
  Q32 value{};
};

bool is_digit(char c) { return c >= '0' && c <= '9'; }

// Exponents beyond this magnitude saturate: with fewer than about 10^9 significant digits any
// exponent this large already means "overflow" or "rounds to zero", and saturation keeps the
// exponent arithmetic inside int64 whatever the text length.
constexpr std::int64_t kExponentClamp = 1'000'000'000;

ParseResult parse_decimal(std::string_view s) {
  ParseResult res;
  std::size_t i = 0;
  bool negative = false;
  if (i < s.size() && (s[i] == '+' || s[i] == '-')) negative = s[i++] == '-';
  std::string digits;  // all significand digits, integer part first
  std::int64_t int_len = 0;
  bool any_digit = false;
  while (i < s.size() && is_digit(s[i])) {
    digits.push_back(s[i++]);
    ++int_len;
    any_digit = true;
  }
  if (i < s.size() && s[i] == '.') {
    ++i;
    while (i < s.size() && is_digit(s[i])) {
      digits.push_back(s[i++]);
      any_digit = true;
    }
  }
  if (!any_digit) return {ParseStatus::kSyntax, i, {}};
  std::int64_t exponent = 0;
  if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
    ++i;
    bool exp_negative = false;
    if (i < s.size() && (s[i] == '+' || s[i] == '-')) exp_negative = s[i++] == '-';
    if (i == s.size() || !is_digit(s[i])) return {ParseStatus::kSyntax, i, {}};
    while (i < s.size() && is_digit(s[i])) {
      exponent = std::min(exponent * 10 + (s[i++] - '0'), kExponentClamp);
    }
    if (exp_negative) exponent = -exponent;
  }
  if (i != s.size()) return {ParseStatus::kSyntax, i, {}};

  // value = 0.d1 d2 ... dn * 10^point where point counts the digits before the decimal point.
  const auto first = digits.find_first_not_of('0');
  if (first == std::string::npos) return res;  // zero, whatever the sign
  const auto last = digits.find_last_not_of('0');
  std::int64_t point = int_len + exponent - static_cast<std::int64_t>(first);
  const std::string_view sig = std::string_view(digits).substr(first, last - first + 1);
  // A value >= 10^10 exceeds 2^31 (overflow); a value < 10^-11 is below half an ulp
  // (2^-33 > 1.1e-10), so it rounds to 0.
  if (point > 10) return {ParseStatus::kOverflow, 0, {}};
  if (point < -10) return res;

  // Integer part: the first `point` digits (zero-padded); at most 10 digits, so it fits.
  std::uint64_t integer = 0;
  for (std::int64_t k = 0; k < point; ++k) {
    const auto idx = static_cast<std::size_t>(k);
    integer = integer * 10 + (idx < sig.size() ? static_cast<std::uint64_t>(sig[idx] - '0') : 0);
  }
  // Fraction digits 0.f1 f2 ... fL, with -point leading zeros when point < 0.
  std::vector<std::uint8_t> frac;
  for (std::int64_t k = point; k < 0; ++k) frac.push_back(0);
  for (std::size_t idx = static_cast<std::size_t>(std::max<std::int64_t>(point, 0)); idx < sig.size(); ++idx) {
    frac.push_back(static_cast<std::uint8_t>(sig[idx] - '0'));
  }
  // Multiply the decimal fraction by 2^32 digit by digit from the right: what carries out of the
  // leading digit is floor(fraction * 2^32); the digits left behind are the exact remainder.
  std::uint64_t carry = 0;
  for (std::size_t k = frac.size(); k-- > 0;) {
    const std::uint64_t t = frac[k] * (std::uint64_t{1} << 32) + carry;  // < 10 * 2^32 + 2^32
    frac[k] = static_cast<std::uint8_t>(t % 10);
    carry = t / 10;
  }
  // Round the remainder 0.r1 r2 ... once: above 1/2 up, below down, exactly 1/2 to even.
  bool up = false;
  if (!frac.empty()) {
    const bool rest_nonzero = std::any_of(frac.begin() + 1, frac.end(), [](std::uint8_t d) { return d != 0; });
    if (frac[0] > 5 || (frac[0] == 5 && rest_nonzero)) up = true;
    else if (frac[0] == 5) up = (carry & 1) != 0;
  }
  const u128 magnitude = (static_cast<u128>(integer) << 32) + carry + (up ? 1 : 0);
  const auto q = with_sign(magnitude, negative);
  if (!q) return {ParseStatus::kOverflow, 0, {}};
  res.value = *q;
  return res;
}

std::string quoted(std::string_view s) {
  // Long inputs are cut so that an error message stays readable.
  constexpr std::size_t kShown = 64;
  std::string out = "\"";
  out.append(s.substr(0, kShown));
  if (s.size() > kShown) out.append("...");
  out.append("\"");
  return out;
}

constexpr std::array<std::uint64_t, 11> kPow10 = {1,         10,         100,         1000,        10000,      100000,
                                                   1000000,   10000000,   100000000,   1000000000,  10000000000};

// The fraction f / 2^32 that decimal c / 10^k rounds to, as from_decimal rounds (ties-to-even).
std::uint64_t round_back(std::uint64_t c, int k) {
  const i128 r = detail::rne_div(static_cast<i128>(c) << 32, static_cast<i128>(kPow10[static_cast<std::size_t>(k)]));
  return static_cast<std::uint64_t>(r);
}

std::string pad_digits(std::uint64_t v, int width) {
  std::string s = std::to_string(v);
  return std::string(static_cast<std::size_t>(width) - s.size(), '0') + s;
}

}  // namespace

Q32 Q32::from_double(double d) {
  Q32 out;
  switch (convert_double(d, out)) {
    case FromDouble::kOk: return out;
    case FromDouble::kNaN: detail::throw_domain("from_double: NaN");
    case FromDouble::kOverflow: break;
  }
  detail::throw_overflow("from_double");
}

std::optional<Q32> Q32::checked_from_double(double d) noexcept {
  Q32 out;
  if (convert_double(d, out) != FromDouble::kOk) return std::nullopt;
  return out;
}

Q32 Q32::from_decimal(std::string_view text) {
  const ParseResult r = parse_decimal(text);
  switch (r.status) {
    case ParseStatus::kOk: return r.value;
    case ParseStatus::kSyntax:
      throw ParseError("not a decimal number: " + quoted(text) + " (at offset " + std::to_string(r.error_pos) + ")");
    case ParseStatus::kOverflow: break;
  }
  throw OverflowError("decimal out of Q32 range: " + quoted(text));
}

std::optional<Q32> Q32::checked_from_decimal(std::string_view text) noexcept {
  try {
    const ParseResult r = parse_decimal(text);  // allocates, so it may throw bad_alloc
    if (r.status != ParseStatus::kOk) return std::nullopt;
    return r.value;
  } catch (const std::bad_alloc&) {
    return std::nullopt;
  }
}

namespace {
// "-" when negative and the integer part of |raw| / 2^32; the fraction bits go to `frac`.
std::string sign_and_integer(std::int64_t raw, std::uint64_t& frac) {
  const bool negative = raw < 0;
  const std::uint64_t mag = negative ? std::uint64_t{0} - static_cast<std::uint64_t>(raw) : static_cast<std::uint64_t>(raw);
  frac = mag & kFracMask;
  return (negative ? "-" : "") + std::to_string(mag >> 32);
}
}  // namespace

double Q32::to_double() const noexcept { return static_cast<double>(raw) * 0x1p-32; }

std::string Q32::to_string() const {
  std::uint64_t f = 0;
  std::string out = sign_and_integer(raw, f);
  if (f == 0) return out;
  // The k-digit decimal nearest to f / 2^32 is the only k-digit candidate that can round back
  // to f (the round-trip interval is contiguous around f). At k = 10 it always does: it is within
  // 0.5e-10 of the value, less than half an ulp (2^-33 > 1.16e-10), and below 10^10 because
  // f <= 2^32 - 1.
  for (int k = 1;; ++k) {
    const u128 scaled = static_cast<u128>(f) * kPow10[static_cast<std::size_t>(k)];
    // Nearest, ties to the even candidate so the choice is canonical.
    const auto c = static_cast<std::uint64_t>(detail::rne_shift(static_cast<i128>(scaled), 32));
    if (k == 10 || (c < kPow10[static_cast<std::size_t>(k)] && round_back(c, k) == f)) {
      return out + "." + pad_digits(c, k);
    }
  }
}

std::string exact_fraction_digits(std::uint32_t f) {
  // f / 2^32 = f * 5^32 / 10^32 exactly, and f * 5^32 < 10^32 < 2^107.
  u128 digits = f;
  for (int k = 0; k < 32; ++k) digits *= 5;
  std::string s(32, '0');
  for (int k = 31; k >= 0; --k) {
    s[static_cast<std::size_t>(k)] = static_cast<char>('0' + static_cast<int>(digits % 10));
    digits /= 10;
  }
  s.erase(s.find_last_not_of('0') + 1);
  return s;
}

std::string Q32::to_exact_string() const {
  std::uint64_t f = 0;
  std::string out = sign_and_integer(raw, f);
  if (f == 0) return out;
  return out + "." + exact_fraction_digits(static_cast<std::uint32_t>(f));
}

std::ostream& operator<<(std::ostream& os, Q32 q) { return os << q.to_string(); }

}  // namespace r1::fx
