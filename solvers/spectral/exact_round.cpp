// Exact roundings for the spectral solver (R1-SPEC-010..012): RNE sqrt of a ratio, RNE shift and
// the correctly rounded double of a 192-bit exact sum.
#include "r1/solvers/exact_round.hpp"

#include <array>
#include <cmath>

namespace r1::spectral {

namespace {

// |V| of a 192-bit two's complement value as three limbs, least significant first.
std::array<std::uint64_t, 3> magnitude(const fx::ExactSum& sum, bool& negative) {
  std::array<std::uint64_t, 3> l = sum.limbs();
  negative = (l[2] >> 63) != 0;
  if (negative) {  // two's complement negation: invert, add one with carry
    std::uint64_t carry = 1;
    for (auto& limb : l) {
      limb = ~limb;
      const std::uint64_t next = limb + carry;
      carry = (carry != 0 && next == 0) ? 1 : 0;
      limb = next;
    }
  }
  return l;
}

bool bit(const std::array<std::uint64_t, 3>& l, int i) { return ((l[static_cast<std::size_t>(i / 64)] >> (i % 64)) & 1) != 0; }

// Whether any bit below position i (exclusive) is set.
bool any_below(const std::array<std::uint64_t, 3>& l, int i) {
  for (int limb = 0; limb < 3 && limb * 64 < i; ++limb) {
    const int top = i - limb * 64;  // bits [0, top) of this limb count
    const std::uint64_t mask = top >= 64 ? ~std::uint64_t{0} : ((std::uint64_t{1} << top) - 1);
    if ((l[static_cast<std::size_t>(limb)] & mask) != 0) return true;
  }
  return false;
}

// Bits [t, t + width) of the magnitude as an integer, width <= 64.
std::uint64_t extract(const std::array<std::uint64_t, 3>& l, int t, int width) {
  std::uint64_t r = 0;
  for (int b = width - 1; b >= 0; --b) {
    const int i = t + b;
    r = (r << 1) | ((i < 192 && bit(l, i)) ? 1u : 0u);
  }
  return r;
}

int bit_length(const std::array<std::uint64_t, 3>& l) {
  for (int limb = 2; limb >= 0; --limb)
    if (l[static_cast<std::size_t>(limb)] != 0) return limb * 64 + 64 - std::countl_zero(l[static_cast<std::size_t>(limb)]);
  return 0;
}

}  // namespace

std::uint64_t rne_sqrt_ratio(U256 num, u128 den) {
  // First guess in double (any rounding there is corrected below).
  const double num_d = static_cast<double>(num.hi) * 0x1p128 + static_cast<double>(num.lo);
  const double root = std::sqrt(num_d / static_cast<double>(den));
  std::uint64_t q = root >= 0x1p63 ? (std::uint64_t{1} << 63) - 1 : static_cast<std::uint64_t>(root + 0.5);
  const U256 four_num = shl(num, 2);
  // (2q - 1)^2 den <= 4 num  <=>  sqrt(num/den) >= q - 1/2.
  auto at_least_half_below = [&](std::uint64_t k) {
    if (k == 0) return true;
    const u128 odd = 2 * static_cast<u128>(k) - 1;  // < 2^64
    return mul_wide(odd * odd, den) <= four_num;
  };
  while (!at_least_half_below(q)) --q;
  while (q < (std::uint64_t{1} << 63) - 1 && at_least_half_below(q + 1)) ++q;
  // A tie (sqrt(num/den) = q - 1/2 exactly) goes to the even neighbour.
  if (q > 0 && (q & 1) != 0) {
    const u128 odd = 2 * static_cast<u128>(q) - 1;
    if (mul_wide(odd * odd, den) == four_num) --q;
  }
  return q;
}

std::optional<std::int64_t> round_shift(const fx::ExactSum& sum, int s) {
  bool negative = false;
  const std::array<std::uint64_t, 3> l = magnitude(sum, negative);
  // The quotient must fit in 64 bits before rounding can at most add one.
  if (bit_length(l) - s > 64) return std::nullopt;
  std::uint64_t q = extract(l, s, 64);
  const bool half = bit(l, s - 1), sticky = any_below(l, s - 1);
  if (half && (sticky || (q & 1) != 0)) {
    if (q == ~std::uint64_t{0}) return std::nullopt;
    ++q;
  }
  const std::uint64_t limit = negative ? (std::uint64_t{1} << 63) : (std::uint64_t{1} << 63) - 1;
  if (q > limit) return std::nullopt;
  if (!negative) return static_cast<std::int64_t>(q);
  return q == (std::uint64_t{1} << 63) ? INT64_MIN : -static_cast<std::int64_t>(q);
}

double to_double_scaled(const fx::ExactSum& sum, int k) {
  bool negative = false;
  const std::array<std::uint64_t, 3> l = magnitude(sum, negative);
  const int len = bit_length(l);
  if (len == 0) return 0.0;
  double m = 0;
  int e = -k;
  if (len <= 53) {
    m = static_cast<double>(l[0]);  // < 2^53: exact
  } else {
    const int t = len - 53;
    std::uint64_t top = extract(l, t, 53);
    const bool half = bit(l, t - 1), sticky = any_below(l, t - 1);
    if (half && (sticky || (top & 1) != 0)) ++top;  // may become 2^53: still exact
    m = static_cast<double>(top);
    e += t;
  }
  const double r = std::ldexp(m, e);
  return negative ? -r : r;
}

}  // namespace r1::spectral
