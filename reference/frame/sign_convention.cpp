// Eigenvector sign convention: the lowest-index entry within 2^-10 of the largest magnitude is
// made positive (R1-FRM-001..002).
#include <algorithm>
#include <cmath>
#include <type_traits>

#include "r1/reference/frame.hpp"

namespace r1 {

namespace {

// |raw| as an unsigned value: exact for every raw, INT64_MIN included.
std::uint64_t magnitude(Q32 x) {
  return x.raw < 0 ? std::uint64_t{0} - static_cast<std::uint64_t>(x.raw) : static_cast<std::uint64_t>(x.raw);
}
double magnitude(double x) { return std::fabs(x); }

bool is_negative(Q32 x) { return x.raw < 0; }
bool is_negative(double x) { return x < 0; }

Q32 negated(Q32 x) { return fx::Q32::from_raw(static_cast<std::int64_t>(std::uint64_t{0} - static_cast<std::uint64_t>(x.raw))); }
double negated(double x) { return -x; }

// The magnitude an entry must reach to count as tied with the largest M (R1-FRM-001): entries
// within 2^-10 of M are ties, so solver noise on symmetric pairs cannot pick the sign.
std::uint64_t tie_floor(std::uint64_t m) { return m - (m >> 10); }
double tie_floor(double m) { return m * (1.0 - 0x1p-10); }

template <class Scalar>
std::int64_t pivot_of(std::span<const Scalar> u) {
  auto best_mag = magnitude(Scalar{});
  for (const auto& x : u) best_mag = std::max(best_mag, magnitude(x));
  if (!(best_mag > magnitude(Scalar{}))) return -1;  // all zero: nothing to decide
  const auto floor = tie_floor(best_mag);
  for (std::size_t i = 0; i < u.size(); ++i)
    if (magnitude(u[i]) >= floor) return static_cast<std::int64_t>(i);  // lowest index among the ties
  return -1;
}

template <class Scalar>
std::array<bool, 5> convention(Spectrum<Scalar>& s) {
  std::array<bool, 5> flipped{};
  for (std::size_t k = 0; k < s.u.size(); ++k) {
    auto& u = s.u[k];
    const std::int64_t p = pivot_of<Scalar>(u);
    if (p < 0 || !is_negative(u[static_cast<std::size_t>(p)])) continue;
    // Unit-norm entries lie in [-1, 1]; negation is exact. The raw -2^63 (value -2^31) cannot
    // occur in a unit vector, and negated() maps it to itself rather than overflowing.
    for (auto& x : u) x = negated(x);
    // The image numerators of L~ u (R1-INC-038) negate with it, exactly; the sums stay.
    if constexpr (std::is_same_v<Scalar, Q32>)
      if (s.image.size() == 5 * u.size())
        for (std::size_t i = 0; i < u.size(); ++i) s.image[i * 5 + k] = -s.image[i * 5 + k];
    flipped[k] = true;
  }
  return flipped;
}

}  // namespace

std::int64_t sign_pivot(std::span<const Q32> u) { return pivot_of<Q32>(u); }
std::int64_t sign_pivot(std::span<const double> u) { return pivot_of<double>(u); }

std::array<bool, 5> apply_sign_convention(Spectrum<Q32>& spectrum) { return convention(spectrum); }
std::array<bool, 5> apply_sign_convention(Spectrum<double>& spectrum) { return convention(spectrum); }

}  // namespace r1
