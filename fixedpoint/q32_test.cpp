// Q32 arithmetic and conversions against Boost.Multiprecision cpp_int (R1-NUM-010..017).
#include "r1/fixedpoint/q32.hpp"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <boost/multiprecision/cpp_int.hpp>
#include <bit>
#include <cmath>
#include <limits>
#include <sstream>
#include <vector>

namespace {

using boost::multiprecision::cpp_int;
using r1::fx::Q32;

const cpp_int kTwo32 = cpp_int(1) << 32;
const cpp_int kRawMax = cpp_int(INT64_MAX);
const cpp_int kRawMin = cpp_int(INT64_MIN);

// Reference rounding, written independently of the implementation: nearest integer to n / d,
// ties to even, by floor division and a comparison of twice the remainder with d.
cpp_int ref_rne(const cpp_int& n, const cpp_int& d) {
  cpp_int num = d < 0 ? cpp_int(-n) : n;
  const cpp_int den = d < 0 ? cpp_int(-d) : d;
  cpp_int q = num / den;  // truncates toward zero
  cpp_int r = num - q * den;
  if (r < 0) {  // make it a floor division
    q -= 1;
    r += den;
  }
  const cpp_int twice = 2 * r;
  if (twice > den || (twice == den && (q & 1) != 0)) q += 1;
  return q;
}

bool in_range(const cpp_int& r) { return r >= kRawMin && r <= kRawMax; }

// cpp_int from decimal digits; cpp_int's own string constructor reads a leading 0 as octal.
cpp_int dec(const std::string& digits) {
  cpp_int v = 0;
  for (const char c : digits) v = v * 10 + (c - '0');
  return v;
}

// Raw values that stress carries, ties and the range ends, mixed with uniform ones.
std::vector<std::int64_t> edge_raws() {
  std::vector<std::int64_t> v = {0, 1, -1, 2, -2, INT64_MAX, INT64_MIN, INT64_MAX - 1, INT64_MIN + 1};
  for (int k = 0; k < 63; k += 3) {
    const std::int64_t p = std::int64_t{1} << k;
    for (const std::int64_t d : {-1, 0, 1}) {
      v.push_back(p + d);
      v.push_back(-p + d);
      v.push_back(3 * (p >> 1) + d);
    }
  }
  for (const std::int64_t d : {-3, -1, 0, 1, 3}) {
    v.push_back((std::int64_t{1} << 32) + d);              // 1 + tiny
    v.push_back(-(std::int64_t{1} << 32) + d);
    v.push_back((std::int64_t{1} << 31) + d);              // 0.5 + tiny
    v.push_back(std::int64_t{3037000499} + d);             // sqrt(2^63): squares near the top
    v.push_back(std::int64_t{0x0000B504F333F9DE} + d);     // sqrt(2) * 2^46: products near 2^63
    v.push_back(-std::int64_t{0x0000B504F333F9DE} + d);
  }
  return v;
}

rc::Gen<std::int64_t> any_raw() {
  const auto edges = edge_raws();
  return rc::gen::oneOf(rc::gen::resize(100, rc::gen::arbitrary<std::int64_t>()),
                        rc::gen::resize(100, rc::gen::map(rc::gen::arbitrary<std::int32_t>(),
                                                          [](std::int32_t x) { return std::int64_t{x}; })),
                        rc::gen::elementOf(edges),
                        rc::gen::map(rc::gen::pair(rc::gen::elementOf(edges), rc::gen::inRange(-5, 6)),
                                     [](std::pair<std::int64_t, int> p) {
                                       return static_cast<std::int64_t>(
                                           static_cast<std::uint64_t>(p.first) + static_cast<std::uint64_t>(p.second));
                                     }));
}

rc::Gen<Q32> any_q32() { return rc::gen::map(any_raw(), [](std::int64_t r) { return Q32{r}; }); }

// Checks a checked_* result and its throwing operator against an exact reference raw.
template <class Checked, class Throwing>
void check_op(const cpp_int& expect, Checked checked, Throwing throwing) {
  const std::optional<Q32> c = checked();
  if (in_range(expect)) {
    RC_ASSERT(c.has_value());
    RC_ASSERT(cpp_int(c->raw) == expect);
    RC_ASSERT(throwing().raw == c->raw);
  } else {
    RC_ASSERT(!c.has_value());
    RC_ASSERT_THROWS_AS(throwing(), r1::fx::OverflowError);
  }
}

// ---- constants and compile-time use ---------------------------------------------------------

static_assert(Q32::one().raw == std::int64_t{1} << 32);
static_assert(Q32::one() * Q32::one() == Q32::one());
static_assert(Q32::from_int(3) / Q32::from_int(2) == Q32{3 * (std::int64_t{1} << 31)});
static_assert(r1::fx::sqrt(Q32::from_int(4)) == Q32::from_int(2));
static_assert(Q32::epsilon() < Q32::one() && Q32::min() < Q32::zero() && Q32::max() > Q32::one());
static_assert(!r1::fx::checked_neg(Q32::min()).has_value());

TEST(Q32, FromIntBoundaries) {
  EXPECT_EQ(Q32::from_int(-(std::int64_t{1} << 31)), Q32::min());
  EXPECT_EQ(Q32::from_int((std::int64_t{1} << 31) - 1).raw, ((std::int64_t{1} << 31) - 1) << 32);
  EXPECT_THROW(Q32::from_int(std::int64_t{1} << 31), r1::fx::OverflowError);
  EXPECT_THROW(Q32::from_int(-(std::int64_t{1} << 31) - 1), r1::fx::OverflowError);
  EXPECT_FALSE(Q32::checked_from_int(INT64_MAX).has_value());
}

TEST(Q32, ErrorTypesDeriveFromStandardOnes) {
  EXPECT_THROW(Q32::max() + Q32::epsilon(), std::overflow_error);
  EXPECT_THROW(Q32::one() / Q32::zero(), std::domain_error);
  EXPECT_THROW(r1::fx::sqrt(Q32{-1}), r1::fx::DomainError);
  EXPECT_THROW(Q32::from_decimal("1..2"), std::invalid_argument);
  EXPECT_THROW(-Q32::min(), r1::fx::OverflowError);
  EXPECT_THROW(r1::fx::abs(Q32::min()), r1::fx::OverflowError);
  EXPECT_THROW(r1::fx::mul_div(Q32::one(), Q32::one(), Q32::zero()), r1::fx::DomainError);
  EXPECT_EQ(r1::fx::abs(Q32{-5}), Q32{5});
}

TEST(Q32, RoundToIntTiesToEven) {
  EXPECT_EQ(Q32::from_decimal("2.5").round_to_int(), 2);
  EXPECT_EQ(Q32::from_decimal("3.5").round_to_int(), 4);
  EXPECT_EQ(Q32::from_decimal("-2.5").round_to_int(), -2);
  EXPECT_EQ(Q32::from_decimal("-2.5").floor_to_int(), -3);
  EXPECT_EQ(Q32::min().round_to_int(), -(std::int64_t{1} << 31));
  EXPECT_EQ(Q32::max().round_to_int(), std::int64_t{1} << 31);  // fits in int64
}

// ---- arithmetic against cpp_int ---------------------------------------------------------------

RC_GTEST_PROP(Q32, AddSubNegAbsExact, ()) {
  const Q32 a = *any_q32(), b = *any_q32();
  check_op(cpp_int(a.raw) + b.raw, [&] { return r1::fx::checked_add(a, b); }, [&] { return a + b; });
  check_op(cpp_int(a.raw) - b.raw, [&] { return r1::fx::checked_sub(a, b); }, [&] { return a - b; });
  check_op(-cpp_int(a.raw), [&] { return r1::fx::checked_neg(a); }, [&] { return -a; });
  check_op(abs(cpp_int(a.raw)), [&] { return r1::fx::checked_abs(a); }, [&] { return r1::fx::abs(a); });
}

RC_GTEST_PROP(Q32, MulRoundsOnceToNearestEven, ()) {
  const Q32 a = *any_q32(), b = *any_q32();
  check_op(ref_rne(cpp_int(a.raw) * b.raw, kTwo32), [&] { return r1::fx::checked_mul(a, b); }, [&] { return a * b; });
}

RC_GTEST_PROP(Q32, DivRoundsOnceToNearestEven, ()) {
  const Q32 a = *any_q32(), b = *any_q32();
  if (b.raw == 0) {
    RC_ASSERT(!r1::fx::checked_div(a, b).has_value());
    RC_ASSERT_THROWS_AS(a / b, r1::fx::DomainError);
    return;
  }
  check_op(ref_rne(cpp_int(a.raw) * kTwo32, cpp_int(b.raw)), [&] { return r1::fx::checked_div(a, b); },
           [&] { return a / b; });
}

RC_GTEST_PROP(Q32, MulDivRoundsOnce, ()) {
  const Q32 a = *any_q32(), b = *any_q32(), c = *any_q32();
  if (c.raw == 0) {
    RC_ASSERT(!r1::fx::checked_mul_div(a, b, c).has_value());
    return;
  }
  check_op(ref_rne(cpp_int(a.raw) * b.raw, cpp_int(c.raw)), [&] { return r1::fx::checked_mul_div(a, b, c); },
           [&] { return r1::fx::mul_div(a, b, c); });
}

// Exact ties, which random raws almost never produce: odd * (odd * 2^31) leaves exactly half
// an ulp, and so does odd / 2^33; both must go to the even neighbour.
RC_GTEST_PROP(Q32, MulAndDivTiesGoToEven, ()) {
  const std::int64_t a = *any_raw() | 1;
  const std::int64_t k = *rc::gen::inRange<std::int64_t>(-(1 << 20), 1 << 20);
  const Q32 half_odd{(2 * k + 1) * (std::int64_t{1} << 31)};
  check_op(ref_rne(cpp_int(a) * half_odd.raw, kTwo32), [&] { return r1::fx::checked_mul(Q32{a}, half_odd); },
           [&] { return Q32{a} * half_odd; });
  const auto q = r1::fx::checked_div(Q32{a}, Q32{std::int64_t{1} << 33});
  RC_ASSERT(q.has_value());
  RC_ASSERT(q->raw % 2 == 0);
  RC_ASSERT(cpp_int(q->raw) == ref_rne(cpp_int(a), 2));
}

// Correct rounding of the root without computing one: s is the nearest integer to sqrt(N) iff
// (2s - 1)^2 <= 4N <= (2s + 1)^2 (equality is impossible for integers).
RC_GTEST_PROP(Q32, SqrtIsCorrectlyRounded, ()) {
  const Q32 a = *any_q32();
  if (a.raw < 0) {
    RC_ASSERT(!r1::fx::checked_sqrt(a).has_value());
    RC_ASSERT_THROWS_AS(r1::fx::sqrt(a), r1::fx::DomainError);
    return;
  }
  const cpp_int n4 = 4 * (cpp_int(a.raw) << 32);
  const cpp_int s = r1::fx::sqrt(a).raw;
  if (s > 0) RC_ASSERT((2 * s - 1) * (2 * s - 1) <= n4);
  RC_ASSERT(n4 < (2 * s + 1) * (2 * s + 1));
}

// Every pair of edge raws, exhaustively: mul, div and mul_div at the carries and range ends.
TEST(Q32, EdgePairsExhaustive) {
  const auto edges = edge_raws();
  std::size_t checked = 0;
  for (const std::int64_t x : edges) {
    for (const std::int64_t y : edges) {
      const Q32 a{x}, b{y};
      const cpp_int mul = ref_rne(cpp_int(x) * y, kTwo32);
      const auto m = r1::fx::checked_mul(a, b);
      ASSERT_EQ(m.has_value(), in_range(mul)) << x << " * " << y;
      if (m) {
        ASSERT_EQ(cpp_int(m->raw), mul) << x << " * " << y;
      }
      if (y != 0) {
        const cpp_int div = ref_rne(cpp_int(x) * kTwo32, cpp_int(y));
        const auto d = r1::fx::checked_div(a, b);
        ASSERT_EQ(d.has_value(), in_range(div)) << x << " / " << y;
        if (d) {
          ASSERT_EQ(cpp_int(d->raw), div) << x << " / " << y;
        }
      }
      for (const std::int64_t z : {std::int64_t{1}, std::int64_t{3}, -(std::int64_t{1} << 32), INT64_MIN, INT64_MAX}) {
        const cpp_int md = ref_rne(cpp_int(x) * y, cpp_int(z));
        const auto r = r1::fx::checked_mul_div(a, b, Q32{z});
        ASSERT_EQ(r.has_value(), in_range(md)) << x << " * " << y << " / " << z;
        if (r) {
          ASSERT_EQ(cpp_int(r->raw), md);
        }
      }
      ++checked;
    }
  }
  EXPECT_EQ(checked, edges.size() * edges.size());
}

TEST(Q32, OverflowAtExactBoundaries) {
  // mul: the largest product that rounds to INT64_MAX and the smallest that does not.
  // 2^63 - 1 + 1/2 is a tie whose even neighbour 2^63 overflows.
  const Q32 half{std::int64_t{1} << 31};
  EXPECT_EQ(Q32::max() * Q32::one(), Q32::max());
  EXPECT_EQ((Q32::min() * half).raw, INT64_MIN / 2);
  EXPECT_THROW(Q32::min() * Q32{-(std::int64_t{1} << 32)}, r1::fx::OverflowError);  // -2^31 * -1
  EXPECT_EQ((Q32::max() * Q32{-(std::int64_t{1} << 32)}).raw, -INT64_MAX);
  EXPECT_EQ(Q32::min() / Q32::one(), Q32::min());
  EXPECT_THROW(Q32::min() / Q32{-(std::int64_t{1} << 32)}, r1::fx::OverflowError);
  EXPECT_THROW(Q32::one() / Q32::epsilon(), r1::fx::OverflowError);  // 2^32
  EXPECT_EQ((Q32{1} / Q32{std::int64_t{1} << 33}).raw, 0);            // 2^-33: a tie, to even 0
  EXPECT_EQ((Q32{3} / Q32{std::int64_t{1} << 33}).raw, 2);            // 1.5 ulp: tie, to even 2
  EXPECT_EQ(r1::fx::sqrt(Q32::max()).raw, std::int64_t{0x0000B504F333F9DE});  // sqrt(2) * 2^47 rounded
}

// ---- conversions --------------------------------------------------------------------------

// The exact value of a finite double as num / 2^shift.
struct Dyadic {
  cpp_int num;
  int shift;  // value = num / 2^shift (shift may be negative)
};
Dyadic exact(double d) {
  int e = 0;
  const double f = std::frexp(d, &e);           // d = f * 2^e, 0.5 <= |f| < 1
  const auto m = static_cast<std::int64_t>(std::ldexp(f, 53));  // exact: 53 significant bits
  return {cpp_int(m), 53 - e};
}

cpp_int ref_from_double(double d) {
  const Dyadic x = exact(d);  // raw = num * 2^32 / 2^shift
  const int s = x.shift - 32;
  if (s <= 0) return x.num << -s;
  return ref_rne(x.num, cpp_int(1) << s);
}

rc::Gen<double> any_double() {
  return rc::gen::oneOf(
      rc::gen::map(rc::gen::resize(100, rc::gen::arbitrary<std::uint64_t>()),
                   [](std::uint64_t bits) { return std::bit_cast<double>(bits); }),
      rc::gen::map(any_raw(), [](std::int64_t r) { return std::ldexp(static_cast<double>(r), -32); }),
      rc::gen::map(rc::gen::pair(any_raw(), rc::gen::inRange(-40, 0)),
                   [](std::pair<std::int64_t, int> p) { return std::ldexp(static_cast<double>(p.first), p.second); }));
}

RC_GTEST_PROP(Q32, FromDoubleRoundsExactValueOnce, ()) {
  const double d = *any_double();
  const auto c = Q32::checked_from_double(d);
  if (std::isnan(d)) {
    RC_ASSERT(!c.has_value());
    RC_ASSERT_THROWS_AS(Q32::from_double(d), r1::fx::DomainError);
    return;
  }
  if (std::isinf(d)) {
    RC_ASSERT(!c.has_value());
    RC_ASSERT_THROWS_AS(Q32::from_double(d), r1::fx::OverflowError);
    return;
  }
  const cpp_int expect = ref_from_double(d);
  if (!in_range(expect)) {
    RC_ASSERT(!c.has_value());
    RC_ASSERT_THROWS_AS(Q32::from_double(d), r1::fx::OverflowError);
    return;
  }
  RC_ASSERT(c.has_value());
  RC_ASSERT(cpp_int(c->raw) == expect);
}

// to_double is correctly rounded: |d - v| <= ulp(d) / 2, and a tie leaves an even significand.
RC_GTEST_PROP(Q32, ToDoubleIsCorrectlyRounded, ()) {
  const Q32 q = *any_q32();
  const double d = q.to_double();
  if (q.raw == 0) {
    RC_ASSERT(d == 0.0);
    return;
  }
  const Dyadic x = exact(d);
  // Compare d * 2^32 with raw at the common scale 2^-(shift).
  const int shift = std::max(x.shift, 32);
  const cpp_int dn = x.num << (shift - x.shift);
  const cpp_int vn = cpp_int(q.raw) << (shift - 32);
  const cpp_int err = abs(dn - vn);
  int e = 0;
  std::frexp(d, &e);
  const cpp_int ulp = cpp_int(1) << (shift + e - 53);  // ulp(d) = 2^(e - 53); shift >= 53 - e
  RC_ASSERT(2 * err <= ulp);
  if (2 * err == ulp) RC_ASSERT((x.num & 1) == 0);
}

TEST(Q32, FromDoubleEdges) {
  EXPECT_EQ(Q32::from_double(0.5).raw, std::int64_t{1} << 31);
  EXPECT_EQ(Q32::from_double(-0.0).raw, 0);
  EXPECT_EQ(Q32::from_double(0x1p-33).raw, 0);                  // tie to even
  EXPECT_EQ(Q32::from_double(0x1.8p-32).raw, 2);                // 1.5 ulp: tie to even 2
  EXPECT_EQ(Q32::from_double(0x1.0000000000001p-33).raw, 1);    // just above half an ulp
  EXPECT_EQ(Q32::from_double(-2147483648.0), Q32::min());
  EXPECT_THROW(Q32::from_double(2147483648.0), r1::fx::OverflowError);
  EXPECT_EQ(Q32::from_double(std::nextafter(2147483648.0, 0.0)).raw, INT64_MAX - ((std::int64_t{1} << 10) - 1));
  EXPECT_THROW(Q32::from_double(std::numeric_limits<double>::quiet_NaN()), r1::fx::DomainError);
  EXPECT_THROW(Q32::from_double(-std::numeric_limits<double>::infinity()), r1::fx::OverflowError);
  EXPECT_EQ(Q32::from_double(std::numeric_limits<double>::denorm_min()).raw, 0);
}

// ---- decimal text ----------------------------------------------------------------------------

// A random decimal string and its exact value num / den.
struct Decimal {
  std::string text;
  cpp_int num;
  cpp_int den;
};

rc::Gen<Decimal> any_decimal() {
  return rc::gen::exec([] {
    Decimal d;
    const bool neg = *rc::gen::arbitrary<bool>();
    const int int_digits = *rc::gen::inRange(0, 13);
    const int frac_digits = *rc::gen::inRange(0, 45);
    const bool point = frac_digits > 0 || *rc::gen::arbitrary<bool>();
    const bool has_exp = *rc::gen::inRange(0, 4) == 0;
    const int exp = has_exp ? *rc::gen::inRange(-25, 15) : 0;
    std::string digits;
    for (int i = 0; i < int_digits + frac_digits; ++i) {
      // Mostly random digits; runs of 0 and 9 and a trailing 5 make ties and carries likely.
      const int kind = *rc::gen::inRange(0, 10);
      digits.push_back(kind < 6 ? static_cast<char>('0' + *rc::gen::inRange(0, 10)) : (kind < 8 ? '0' : '9'));
    }
    if (!digits.empty() && *rc::gen::inRange(0, 3) == 0) digits.back() = '5';
    if (int_digits + frac_digits == 0) digits = "0";
    const int ilen = int_digits + frac_digits == 0 ? 1 : int_digits;
    d.text = (neg ? "-" : (*rc::gen::inRange(0, 4) == 0 ? "+" : ""));
    d.text += ilen > 0 ? digits.substr(0, static_cast<std::size_t>(ilen)) : "";
    if (point) d.text += "." + digits.substr(static_cast<std::size_t>(ilen));
    if (has_exp) d.text += (*rc::gen::arbitrary<bool>() ? "e" : "E") + std::to_string(exp);
    d.num = dec(digits);
    if (neg) d.num = -d.num;
    const int scale = static_cast<int>(digits.size()) - ilen - exp;  // value = num * 10^-scale
    d.den = 1;
    if (scale >= 0) d.den = boost::multiprecision::pow(cpp_int(10), static_cast<unsigned>(scale));
    else d.num *= boost::multiprecision::pow(cpp_int(10), static_cast<unsigned>(-scale));
    return d;
  });
}

RC_GTEST_PROP(Q32, FromDecimalRoundsExactValueOnce, ()) {
  const Decimal d = *any_decimal();
  const cpp_int expect = ref_rne(d.num << 32, d.den);
  const auto c = Q32::checked_from_decimal(d.text);
  if (in_range(expect)) {
    RC_ASSERT(c.has_value());
    RC_ASSERT(cpp_int(c->raw) == expect);
  } else {
    RC_ASSERT(!c.has_value());
    RC_ASSERT_THROWS_AS(Q32::from_decimal(d.text), r1::fx::OverflowError);
  }
}

// The exact decimal of a midpoint (2r + 1) 2^-33 (33 fractional digits) rounds to the even raw;
// one more trailing digit 1 tips it up.
RC_GTEST_PROP(Q32, FromDecimalMidpointsGoToEven, ()) {
  const std::int64_t r = *any_raw() >> 1;
  const cpp_int twice = 2 * cpp_int(r) + 1;  // the midpoint is twice / 2^33
  const cpp_int digits = abs(twice) * boost::multiprecision::pow(cpp_int(5), 33);  // / 10^33
  std::string frac = digits.str();
  frac = std::string(frac.size() < 34 ? 34 - frac.size() : 0, '0') + frac;
  const std::string text = (twice < 0 ? "-" : "") + frac.substr(0, frac.size() - 33) + "." + frac.substr(frac.size() - 33);
  const Q32 q = Q32::from_decimal(text);
  RC_ASSERT(q.raw % 2 == 0);
  RC_ASSERT(cpp_int(q.raw) == ref_rne(twice, 2));
  const Q32 up = Q32::from_decimal(text + "1");
  RC_ASSERT(cpp_int(up.raw) == (twice + (twice < 0 ? -1 : 1)) / 2);
}

TEST(Q32, FromDecimalEdges) {
  EXPECT_EQ(Q32::from_decimal("0"), Q32::zero());
  EXPECT_EQ(Q32::from_decimal("-0.000"), Q32::zero());
  EXPECT_EQ(Q32::from_decimal(".5").raw, std::int64_t{1} << 31);
  EXPECT_EQ(Q32::from_decimal("5.").raw, std::int64_t{5} << 32);
  EXPECT_EQ(Q32::from_decimal("+1e0"), Q32::one());
  EXPECT_EQ(Q32::from_decimal("100e-2"), Q32::one());
  EXPECT_EQ(Q32::from_decimal("0.0001e4"), Q32::one());
  // 2^-33 is exactly 0.000000000116415321826934814453125: a tie, to even 0; a hair more is 1 ulp.
  EXPECT_EQ(Q32::from_decimal("0.000000000116415321826934814453125").raw, 0);
  EXPECT_EQ(Q32::from_decimal("0.0000000001164153218269348144531250000000000001").raw, 1);
  EXPECT_EQ(Q32::from_decimal("-2147483648"), Q32::min());
  EXPECT_EQ(Q32::from_decimal("2147483647.99999999976716935634613037109375"), Q32::max());
  // max + 1/2 ulp is a tie whose even neighbour 2^31 is out of range.
  EXPECT_THROW(Q32::from_decimal("2147483647.999999999883584678173065185546875"), r1::fx::OverflowError);
  EXPECT_EQ(Q32::from_decimal("2147483647.999999999883584678173065185546874"), Q32::max());
  EXPECT_THROW(Q32::from_decimal("2147483648"), r1::fx::OverflowError);
  EXPECT_THROW(Q32::from_decimal("1e10"), r1::fx::OverflowError);
  EXPECT_THROW(Q32::from_decimal("1e999999999999999999999"), r1::fx::OverflowError);
  EXPECT_EQ(Q32::from_decimal("1e-999999999999999999999").raw, 0);
  EXPECT_EQ(Q32::from_decimal("0.00000000000000000000000000000000000000000000000000000000001").raw, 0);
  EXPECT_EQ(Q32::from_decimal(std::string(100000, '0') + "1.5").raw, std::int64_t{3} << 31);
  for (const char* bad : {"", "-", "+", ".", "e5", "1e", "1e+", "1.2.3", " 1", "1 ", "0x10", "inf", "nan", "1,5",
                          "--1", "1e5.0", "\xd9\xa1"}) {
    EXPECT_THROW(Q32::from_decimal(bad), r1::fx::ParseError) << bad;
    EXPECT_FALSE(Q32::checked_from_decimal(bad).has_value()) << bad;
  }
}

// ---- printing --------------------------------------------------------------------------------

RC_GTEST_PROP(Q32, ToStringRoundTripsAndIsShortest, ()) {
  const Q32 q = *any_q32();
  const std::string s = q.to_string();
  RC_ASSERT(Q32::from_decimal(s) == q);
  const auto dot = s.find('.');
  if (dot == std::string::npos) {
    RC_ASSERT((q.raw & 0xFFFFFFFF) == 0);
    return;
  }
  const int k = static_cast<int>(s.size() - dot - 1);
  RC_ASSERT(k <= 10);
  RC_ASSERT(s.back() != '0');
  // No decimal with fewer fractional digits rounds back to q: check the two k-1 digit decimals
  // around q (any other is farther away).
  const cpp_int mag = abs(cpp_int(q.raw));
  const cpp_int p10 = boost::multiprecision::pow(cpp_int(10), static_cast<unsigned>(k - 1));
  const cpp_int lo = (mag * p10) >> 32;
  for (const cpp_int& c : {lo, cpp_int(lo + 1)}) RC_ASSERT(ref_rne(c << 32, p10) != mag);
}

RC_GTEST_PROP(Q32, ToExactStringIsExact, ()) {
  const Q32 q = *any_q32();
  const std::string s = q.to_exact_string();
  const auto dot = s.find('.');
  const std::size_t k = dot == std::string::npos ? 0 : s.size() - dot - 1;
  RC_ASSERT(k <= 32);
  std::string digits = s;
  if (dot != std::string::npos) digits.erase(dot, 1);
  const bool negative = digits[0] == '-';
  const cpp_int value = negative ? cpp_int(-dec(digits.substr(1))) : dec(digits);
  // digits / 10^k == raw / 2^32 exactly.
  RC_ASSERT((value << 32) == cpp_int(q.raw) * boost::multiprecision::pow(cpp_int(10), static_cast<unsigned>(k)));
}

TEST(Q32, ToStringExamples) {
  EXPECT_EQ(Q32::from_decimal("-1.5").to_string(), "-1.5");
  EXPECT_EQ(Q32::from_decimal("0.1").to_string(), "0.1");
  EXPECT_EQ(Q32::from_int(3).to_string(), "3");
  EXPECT_EQ(Q32::zero().to_string(), "0");
  EXPECT_EQ(Q32::epsilon().to_string(), "0.0000000002");
  EXPECT_EQ(Q32::epsilon().to_exact_string(), "0.00000000023283064365386962890625");
  EXPECT_EQ(Q32::min().to_string(), "-2147483648");
  EXPECT_EQ(Q32::max().to_string(), "2147483647.9999999998");
  std::ostringstream os;
  os << Q32::from_decimal("2.25");
  EXPECT_EQ(os.str(), "2.25");
}

}  // namespace
