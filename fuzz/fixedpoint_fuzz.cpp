// Differential fuzz target: Q32, ExactSum, elementary functions vs Boost.Multiprecision (R1-NUM-010..041, R1-TEST-010).
// Covers R1-NUM-010..017, R1-NUM-030..034 and R1-NUM-041.
//
// Input: a sequence of records, each an opcode byte followed by its operands (8-byte
// little-endian raws, or a length byte and text); a truncated operand reads as zero bytes.
#include <algorithm>
#include <bit>
#include <boost/multiprecision/cpp_bin_float.hpp>
#include <boost/multiprecision/cpp_int.hpp>
#include <cmath>
#include <optional>
#include <string>
#include <string_view>

#include "fuzz_target.hpp"
#include "r1/fixedpoint/elementary.hpp"
#include "r1/fixedpoint/exact_sum.hpp"
#include "r1/fixedpoint/q32.hpp"

namespace {

using boost::multiprecision::cpp_int;
using r1::fx::Q32;
using Real = boost::multiprecision::cpp_bin_float_50;

class Reader {
 public:
  Reader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  bool done() const { return pos_ >= size_; }
  std::uint8_t byte() { return pos_ < size_ ? data_[pos_++] : 0; }
  std::int64_t raw() {
    std::uint64_t v = 0;
    for (int i = 0; i < 8; ++i) v |= static_cast<std::uint64_t>(byte()) << (8 * i);
    return static_cast<std::int64_t>(v);
  }
  std::string_view text(std::size_t n) {
    const std::size_t k = std::min(n, size_ - std::min(pos_, size_));
    const std::string_view s(reinterpret_cast<const char*>(data_) + pos_, k);
    pos_ += k;
    return s;
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

// Nearest integer to n / d (d > 0), ties to even.
cpp_int rne(const cpp_int& n, const cpp_int& d) {
  cpp_int q = n / d;
  cpp_int r = n - q * d;
  if (r < 0) {
    q -= 1;
    r += d;
  }
  if (2 * r > d || (2 * r == d && (q & 1) != 0)) q += 1;
  return q;
}

bool fits(const cpp_int& v) { return v >= cpp_int(INT64_MIN) && v <= cpp_int(INT64_MAX); }

// The checked result agrees with the exact reference raw (std::nullopt iff out of range).
void expect(const std::optional<Q32>& got, const cpp_int& ref) {
  R1_FUZZ_CHECK(got.has_value() == fits(ref));
  if (got) R1_FUZZ_CHECK(cpp_int(got->raw) == ref);
}

// Reference reading of the decimal grammar of R1-NUM-016: the exact value num / den, or
// std::nullopt for a syntax error. Texts are at most 47 bytes here, so a nonzero value with an
// exponent above 400 overflows and one below -400 rounds to 0; those are reported via `huge`
// instead of building 10^exponent.
struct RefDecimal {
  cpp_int num, den;
  int huge = 0;  // +1: nonzero with exponent > 400 (overflow); -1: exponent < -400 (rounds to 0)
};
std::optional<RefDecimal> ref_decimal(std::string_view s) {
  std::size_t i = 0;
  bool neg = false;
  if (i < s.size() && (s[i] == '+' || s[i] == '-')) neg = s[i++] == '-';
  cpp_int digits = 0;
  long frac = 0, ndig = 0;
  const auto digit = [&](char c) { return c >= '0' && c <= '9'; };
  while (i < s.size() && digit(s[i])) {
    digits = digits * 10 + (s[i++] - '0');
    ++ndig;
  }
  if (i < s.size() && s[i] == '.') {
    ++i;
    while (i < s.size() && digit(s[i])) {
      digits = digits * 10 + (s[i++] - '0');
      ++ndig;
      ++frac;
    }
  }
  if (ndig == 0) return std::nullopt;
  long exponent = 0;
  if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
    ++i;
    bool eneg = false;
    if (i < s.size() && (s[i] == '+' || s[i] == '-')) eneg = s[i++] == '-';
    if (i == s.size() || !digit(s[i])) return std::nullopt;
    while (i < s.size() && digit(s[i])) exponent = std::min(exponent * 10 + (s[i++] - '0'), 100000L);
    if (eneg) exponent = -exponent;
  }
  if (i != s.size()) return std::nullopt;
  RefDecimal r;
  r.num = neg ? cpp_int(-digits) : digits;
  r.den = 1;
  if (digits == 0) return r;
  if (exponent > 400) r.huge = 1;
  if (exponent < -400) r.huge = -1;
  if (r.huge != 0) return r;
  const long scale = frac - exponent;  // value = digits * 10^-scale
  if (scale >= 0) r.den = boost::multiprecision::pow(cpp_int(10), static_cast<unsigned>(scale));
  else r.num *= boost::multiprecision::pow(cpp_int(10), static_cast<unsigned>(-scale));
  return r;
}

Real real_of(Q32 q) { return ldexp(Real(q.raw), -32); }

// An elementary result within 1/2 + 2^-20 ulp of the exact value (or OverflowError when the
// exact value is beyond the range, up to the bound at the edge).
template <class F>
void check_elementary(F f, const Real& exact) {
  const Real scaled = ldexp(exact, 32);
  const Real slack = ldexp(Real(1), r1::fx::kElementaryBoundLog2);
  const Real edge = Real(INT64_MAX) + Real(0.5);
  try {
    const Q32 got = f();
    R1_FUZZ_CHECK(scaled < edge + slack);
    R1_FUZZ_CHECK(abs(Real(got.raw) - scaled) <= Real(0.5) + slack);
  } catch (const r1::fx::OverflowError&) {
    R1_FUZZ_CHECK(scaled >= edge - slack);
  }
}

void elementary(Reader& in) {
  const std::uint8_t which = in.byte() % 11;
  const Q32 x{in.raw()}, y{in.raw()};
  const Real rx = real_of(x), ry = real_of(y);
  const Real ln2 = log(Real(2));
  switch (which) {
    case 0: if (x.raw < (std::int64_t{40} << 32)) check_elementary([&] { return r1::fx::exp(x); }, exp(rx)); break;
    case 1: if (x.raw < (std::int64_t{40} << 32)) check_elementary([&] { return r1::fx::exp2(x); }, exp(rx * ln2)); break;
    case 2: if (x.raw > 0) check_elementary([&] { return r1::fx::log(x); }, log(rx)); break;
    case 3: if (x.raw > 0) check_elementary([&] { return r1::fx::log2(x); }, log(rx) / ln2); break;
    case 4:
      if (x.raw > 0 && ry * log(rx) < 100) check_elementary([&] { return r1::fx::pow(x, y); }, exp(ry * log(rx)));
      break;
    case 5: check_elementary([&] { return r1::fx::sin(x); }, sin(rx)); break;
    case 6: check_elementary([&] { return r1::fx::cos(x); }, cos(rx)); break;
    case 7: check_elementary([&] { return r1::fx::atan(x); }, atan(rx)); break;
    case 8:
      if (x.raw != 0 || y.raw != 0) check_elementary([&] { return r1::fx::atan2(y, x); }, atan2(ry, rx));
      break;
    case 9: check_elementary([&] { return r1::fx::tanh(x); }, tanh(rx)); break;
    default: check_elementary([&] { return r1::fx::sigmoid(x); }, 1 / (1 + exp(-rx))); break;
  }
}

}  // namespace

R1_FUZZ_TARGET(fixedpoint) {
  Reader in(data, size);
  r1::fx::ExactSum sum;
  r1::fx::ExactSum parts[4];
  cpp_int sum_ref = 0;
  const cpp_int two32 = cpp_int(1) << 32;
  int records = 0;
  while (!in.done() && records++ < 64) {  // bounded work per input
    const std::uint8_t op = in.byte();
    switch (op % 10) {
      case 0: {  // add, sub, neg, abs
        const Q32 a{in.raw()}, b{in.raw()};
        expect(r1::fx::checked_add(a, b), cpp_int(a.raw) + b.raw);
        expect(r1::fx::checked_sub(a, b), cpp_int(a.raw) - b.raw);
        expect(r1::fx::checked_neg(a), -cpp_int(a.raw));
        expect(r1::fx::checked_abs(b), abs(cpp_int(b.raw)));
        R1_FUZZ_CHECK((a <=> b) == (a.raw <=> b.raw));
        break;
      }
      case 1: {
        const Q32 a{in.raw()}, b{in.raw()};
        expect(r1::fx::checked_mul(a, b), rne(cpp_int(a.raw) * b.raw, two32));
        break;
      }
      case 2: {
        const Q32 a{in.raw()}, b{in.raw()};
        if (b.raw == 0) R1_FUZZ_CHECK(!r1::fx::checked_div(a, b));
        else expect(r1::fx::checked_div(a, b), cpp_int(b.raw) > 0 ? rne(cpp_int(a.raw) * two32, cpp_int(b.raw))
                                                                  : rne(-cpp_int(a.raw) * two32, -cpp_int(b.raw)));
        break;
      }
      case 3: {
        const Q32 a{in.raw()}, b{in.raw()}, c{in.raw()};
        if (c.raw == 0) R1_FUZZ_CHECK(!r1::fx::checked_mul_div(a, b, c));
        else expect(r1::fx::checked_mul_div(a, b, c), c.raw > 0 ? rne(cpp_int(a.raw) * b.raw, cpp_int(c.raw))
                                                                : rne(-cpp_int(a.raw) * b.raw, -cpp_int(c.raw)));
        break;
      }
      case 4: {  // sqrt: (2s - 1)^2 <= 4N < (2s + 1)^2
        const Q32 a{in.raw()};
        const auto s = r1::fx::checked_sqrt(a);
        R1_FUZZ_CHECK(s.has_value() == (a.raw >= 0));
        if (s) {
          const cpp_int n4 = 4 * (cpp_int(a.raw) << 32), r = s->raw;
          R1_FUZZ_CHECK(r == 0 || (2 * r - 1) * (2 * r - 1) <= n4);
          R1_FUZZ_CHECK(n4 < (2 * r + 1) * (2 * r + 1));
        }
        break;
      }
      case 5: {  // printing round trips and is exact
        const Q32 a{in.raw()};
        R1_FUZZ_CHECK(Q32::from_decimal(a.to_string()) == a);
        R1_FUZZ_CHECK(Q32::from_decimal(a.to_exact_string()) == a);
        break;
      }
      case 6: {  // decimal text against the reference reading
        const std::string_view text = in.text(in.byte() % 48);
        const auto got = Q32::checked_from_decimal(text);
        const auto ref = ref_decimal(text);
        if (!ref) {
          R1_FUZZ_CHECK(!got);
        } else if (ref->huge > 0) {
          R1_FUZZ_CHECK(!got);
        } else if (ref->huge < 0) {
          R1_FUZZ_CHECK(got && got->raw == 0);
        } else {
          expect(got, rne(ref->num << 32, ref->den));
        }
        break;
      }
      case 7: {  // exact accumulation, split over partial sums chosen by the input
        const std::uint8_t k = in.byte();
        const Q32 a{in.raw()}, b{in.raw()};
        r1::fx::ExactSum& part = parts[k % 4];
        const auto apply = [&](r1::fx::ExactSum& s) {
          switch ((k / 4) % 4) {
            case 0: s.add_product(a, b); break;
            case 1: s.sub_product(a, b); break;
            case 2: s.add(a); break;
            default: s.sub(a); break;
          }
        };
        apply(sum);
        apply(part);
        const cpp_int term = (k / 4) % 4 < 2 ? cpp_int(cpp_int(a.raw) * b.raw) : cpp_int(cpp_int(a.raw) << 32);
        sum_ref += (k / 4) % 2 == 0 ? term : cpp_int(-term);
        break;
      }
      case 8: {  // from_double against the exact binary value
        const double d = std::bit_cast<double>(static_cast<std::uint64_t>(in.raw()));
        const auto got = Q32::checked_from_double(d);
        if (!std::isfinite(d)) {
          R1_FUZZ_CHECK(!got);
        } else {
          int e = 0;
          const auto m = static_cast<std::int64_t>(std::ldexp(std::frexp(d, &e), 53));
          const int shift = 53 - e - 32;  // raw = m / 2^shift
          expect(got, shift <= 0 ? cpp_int(cpp_int(m) << -shift) : rne(cpp_int(m), cpp_int(1) << shift));
        }
        break;
      }
      default: elementary(in); break;
    }
  }
  // The whole sum against cpp_int, and the partial sums merged in the input's order.
  r1::fx::ExactSum merged = parts[3];
  merged.merge(parts[1]);
  merged.merge(parts[0]);
  merged.merge(parts[2]);
  R1_FUZZ_CHECK(merged == sum);
  expect(sum.checked_round(), rne(sum_ref, two32));
  return 0;
}
