// Q32 signed fixed point, value = raw / 2^32 in an int64 (R1-NUM-002, R1-NUM-010..017).
#pragma once

#include <cstdint>
#include <compare>
#include <iosfwd>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

#include "r1/fixedpoint/int128.hpp"

namespace r1::fx {

// A result does not fit the Q32 range [-2^31, 2^31 - 2^-32] (R1-NUM-013). Never a silent wrap.
class OverflowError : public std::overflow_error {
 public:
  using std::overflow_error::overflow_error;
};

// An argument outside a function's domain: division by zero, sqrt or log of a negative number,
// NaN given to from_double (R1-NUM-014).
class DomainError : public std::domain_error {
 public:
  using std::domain_error::domain_error;
};

// Text that is not a decimal number in the grammar of R1-NUM-016.
class ParseError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

namespace detail {
[[noreturn]] void throw_overflow(const char* op);
[[noreturn]] void throw_domain(const char* what);

// Round-to-nearest, ties-to-even of v / 2^s for 1 <= s <= 126 (R1-NUM-011). Floor plus the
// remainder describe the exact quotient for either sign, so the rule is symmetric about zero.
constexpr i128 rne_shift(i128 v, int s) {
  const i128 q = v >> s;  // floor (arithmetic shift)
  const u128 mask = (u128{1} << s) - 1;
  const u128 rem = static_cast<u128>(v) & mask;
  const u128 half = u128{1} << (s - 1);
  return q + ((rem > half || (rem == half && (q & 1) != 0)) ? 1 : 0);
}

// Round-to-nearest, ties-to-even of n / d (d != 0), as a signed 128-bit quotient.
constexpr i128 rne_div(i128 n, i128 d) {
  const bool negative = (n < 0) != (d < 0);
  const u128 un = n < 0 ? u128{0} - static_cast<u128>(n) : static_cast<u128>(n);
  const u128 ud = d < 0 ? u128{0} - static_cast<u128>(d) : static_cast<u128>(d);
  u128 q = un / ud;
  const u128 r = un % ud;
  // r < ud < 2^127, so 2r cannot wrap. Ties go to the even quotient.
  if (2 * r > ud || (2 * r == ud && (q & 1) != 0)) ++q;
  return negative ? -static_cast<i128>(q) : static_cast<i128>(q);
}

constexpr bool fits_i64(i128 v) { return v >= INT64_MIN && v <= INT64_MAX; }

// floor(sqrt(n)) by Newton's iteration from a power of two above the root; the iterates
// decrease monotonically to the floor of the root, so the loop ends when they stop decreasing.
constexpr u128 isqrt(u128 n) {
  if (n < 2) return n;
  int bits = 0;
  for (u128 t = n; t != 0; t >>= 1) ++bits;
  u128 x = u128{1} << ((bits + 1) / 2);
  for (;;) {
    const u128 y = (x + n / x) >> 1;
    if (y >= x) return x;
    x = y;
  }
}
}  // namespace detail

struct Q32 {
  std::int64_t raw = 0;

  static constexpr int kFracBits = 32;
  static constexpr std::int64_t kOneRaw = std::int64_t{1} << kFracBits;

  static constexpr Q32 from_raw(std::int64_t r) noexcept { return Q32{r}; }
  static constexpr Q32 zero() noexcept { return Q32{0}; }
  static constexpr Q32 one() noexcept { return Q32{kOneRaw}; }
  // The resolution 2^-32, one unit in the last place (ulp) everywhere in the range.
  static constexpr Q32 epsilon() noexcept { return Q32{1}; }
  static constexpr Q32 max() noexcept { return Q32{INT64_MAX}; }  // 2^31 - 2^-32
  static constexpr Q32 min() noexcept { return Q32{INT64_MIN}; }  // -2^31, the lowest value

  // Integers in [-2^31, 2^31) are exact; anything else overflows.
  static constexpr std::optional<Q32> checked_from_int(std::int64_t i) noexcept {
    if (i < -(std::int64_t{1} << 31) || i >= (std::int64_t{1} << 31)) return std::nullopt;
    return Q32{i * kOneRaw};
  }
  static constexpr Q32 from_int(std::int64_t i) {
    const auto q = checked_from_int(i);
    if (!q) detail::throw_overflow("from_int");
    return *q;
  }

  // Exact binary value of d rounded once, ties-to-even, by integer arithmetic on its bits (so the
  // FP rounding mode plays no part). NaN: DomainError; infinities and out of range: OverflowError.
  static Q32 from_double(double d);
  static std::optional<Q32> checked_from_double(double d) noexcept;

  // Exact decimal text rounded once, ties-to-even (R1-NUM-016). Grammar, whole string:
  //   [+-]? ( digits [ '.' digits? ] | '.' digits ) ( [eE] [+-]? digits )?
  // No whitespace, no hex, no inf/nan. Bad syntax: ParseError; out of range: OverflowError.
  static Q32 from_decimal(std::string_view text);
  static std::optional<Q32> checked_from_decimal(std::string_view text) noexcept;

  // raw * 2^-32 correctly rounded to double (the int64 -> double conversion rounds to nearest,
  // ties-to-even under the default FP environment R1-NUM-001 requires; the scaling is exact).
  double to_double() const noexcept;

  // The shortest decimal that from_decimal maps back to this exact value (R1-NUM-017):
  // "-1.5", "0.1", "3"; at most 10 fractional digits. to_exact_string() gives every digit of the
  // binary value instead (at most 32 fractional digits), without trailing zeros.
  std::string to_string() const;
  std::string to_exact_string() const;

  // floor(value) and value rounded to the nearest integer, ties-to-even; both always fit.
  constexpr std::int64_t floor_to_int() const noexcept { return raw >> kFracBits; }
  constexpr std::int64_t round_to_int() const noexcept {
    return static_cast<std::int64_t>(detail::rne_shift(raw, kFracBits));
  }

  friend constexpr bool operator==(Q32, Q32) noexcept = default;
  friend constexpr std::strong_ordering operator<=>(Q32, Q32) noexcept = default;
};

// ---- checked arithmetic: std::nullopt where the exact result rounds outside the range ----------

constexpr std::optional<Q32> checked_add(Q32 a, Q32 b) noexcept {
  std::int64_t r = 0;
  if (__builtin_add_overflow(a.raw, b.raw, &r)) return std::nullopt;
  return Q32{r};
}

constexpr std::optional<Q32> checked_sub(Q32 a, Q32 b) noexcept {
  std::int64_t r = 0;
  if (__builtin_sub_overflow(a.raw, b.raw, &r)) return std::nullopt;
  return Q32{r};
}

constexpr std::optional<Q32> checked_neg(Q32 a) noexcept {
  if (a.raw == INT64_MIN) return std::nullopt;  // 2^31 is not representable
  return Q32{-a.raw};
}

constexpr std::optional<Q32> checked_abs(Q32 a) noexcept { return a.raw < 0 ? checked_neg(a) : a; }

// The exact product needs at most 126 bits (R1-NUM-002) and is rounded once.
constexpr std::optional<Q32> checked_mul(Q32 a, Q32 b) noexcept {
  const i128 r = detail::rne_shift(static_cast<i128>(a.raw) * b.raw, Q32::kFracBits);
  if (!detail::fits_i64(r)) return std::nullopt;
  return Q32{static_cast<std::int64_t>(r)};
}

// a / b rounded once; std::nullopt also for b == 0 (operator/ tells the two apart).
constexpr std::optional<Q32> checked_div(Q32 a, Q32 b) noexcept {
  if (b.raw == 0) return std::nullopt;
  const i128 r = detail::rne_div(static_cast<i128>(a.raw) * Q32::kOneRaw, b.raw);
  if (!detail::fits_i64(r)) return std::nullopt;
  return Q32{static_cast<std::int64_t>(r)};
}

// a * b / c with one rounding of the exact rational (the product is never rounded);
// std::nullopt also for c == 0.
constexpr std::optional<Q32> checked_mul_div(Q32 a, Q32 b, Q32 c) noexcept {
  if (c.raw == 0) return std::nullopt;
  const i128 r = detail::rne_div(static_cast<i128>(a.raw) * b.raw, c.raw);
  if (!detail::fits_i64(r)) return std::nullopt;
  return Q32{static_cast<std::int64_t>(r)};
}

// Correctly rounded square root; std::nullopt for a negative argument. Never overflows:
// sqrt(2^31) < 2^16. With N = raw * 2^32 and s = floor(sqrt(N)), the root rounds up exactly when
// N >= s^2 + s + 1 (sqrt(N) >= s + 1/2 <=> N >= s^2 + s + 1/4); a tie would need N = s^2 + s + 1/4,
// which is not an integer, so no tie rule is needed.
constexpr std::optional<Q32> checked_sqrt(Q32 a) noexcept {
  if (a.raw < 0) return std::nullopt;
  const u128 n = static_cast<u128>(a.raw) << Q32::kFracBits;
  u128 s = detail::isqrt(n);
  if (n - s * s > s) ++s;
  return Q32{static_cast<std::int64_t>(s)};
}

// ---- throwing arithmetic (R1-NUM-013, R1-NUM-014) -------------------------------------------

constexpr Q32 operator+(Q32 a, Q32 b) {
  const auto r = checked_add(a, b);
  if (!r) detail::throw_overflow("add");
  return *r;
}
constexpr Q32 operator-(Q32 a, Q32 b) {
  const auto r = checked_sub(a, b);
  if (!r) detail::throw_overflow("sub");
  return *r;
}
constexpr Q32 operator-(Q32 a) {
  const auto r = checked_neg(a);
  if (!r) detail::throw_overflow("neg");
  return *r;
}
constexpr Q32 operator*(Q32 a, Q32 b) {
  const auto r = checked_mul(a, b);
  if (!r) detail::throw_overflow("mul");
  return *r;
}
constexpr Q32 operator/(Q32 a, Q32 b) {
  if (b.raw == 0) detail::throw_domain("division by zero");
  const auto r = checked_div(a, b);
  if (!r) detail::throw_overflow("div");
  return *r;
}
constexpr Q32& operator+=(Q32& a, Q32 b) { return a = a + b; }
constexpr Q32& operator-=(Q32& a, Q32 b) { return a = a - b; }
constexpr Q32& operator*=(Q32& a, Q32 b) { return a = a * b; }
constexpr Q32& operator/=(Q32& a, Q32 b) { return a = a / b; }

constexpr Q32 abs(Q32 a) {
  const auto r = checked_abs(a);
  if (!r) detail::throw_overflow("abs");
  return *r;
}
constexpr Q32 mul_div(Q32 a, Q32 b, Q32 c) {
  if (c.raw == 0) detail::throw_domain("mul_div: division by zero");
  const auto r = checked_mul_div(a, b, c);
  if (!r) detail::throw_overflow("mul_div");
  return *r;
}
constexpr Q32 sqrt(Q32 a) {
  const auto r = checked_sqrt(a);
  if (!r) detail::throw_domain("sqrt of a negative number");
  return *r;
}

// Writes to_string(); lets test frameworks print values.
// The exact decimal digits of f / 2^32 after the point, trailing zeros dropped ("" for 0): every
// binary fraction of 32 bits is a finite decimal of at most 32 digits.
std::string exact_fraction_digits(std::uint32_t f);

std::ostream& operator<<(std::ostream& os, Q32 q);

}  // namespace r1::fx
