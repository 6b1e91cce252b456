// Goldilocks field: inversion chain and the Q32 encoding (R1-NUM-020..023).
#include "r1/fixedpoint/goldilocks.hpp"

namespace r1::gl {

namespace {
Fp square_n(Fp a, int n) {
  for (int i = 0; i < n; ++i) a = square(a);
  return a;
}
}  // namespace

Fp pow_p_minus_2(Fp x) {
  // p - 2 = (2^32 - 2) * 2^32 + (2^32 - 1). Build x^(2^31 - 1) by doubling runs of ones.
  const Fp e1 = x;                                // x^1
  const Fp e2 = mul(square(e1), e1);              // x^(2^2 - 1)
  const Fp e3 = mul(square(e2), e1);              // x^(2^3 - 1)
  const Fp e6 = mul(square_n(e3, 3), e3);         // x^(2^6 - 1)
  const Fp e12 = mul(square_n(e6, 6), e6);        // x^(2^12 - 1)
  const Fp e24 = mul(square_n(e12, 12), e12);     // x^(2^24 - 1)
  const Fp e30 = mul(square_n(e24, 6), e6);       // x^(2^30 - 1)
  const Fp e31 = mul(square(e30), e1);            // x^(2^31 - 1)
  const Fp b = square(e31);                       // x^(2^32 - 2)
  const Fp c = mul(b, e1);                        // x^(2^32 - 1)
  return mul(square_n(b, 32), c);                 // x^((2^32 - 2) 2^32 + 2^32 - 1)
}

std::optional<Fp> inverse(Fp a) {
  if (a.v == 0) return std::nullopt;
  return pow_p_minus_2(a);
}

std::optional<Fp> encode(std::int64_t raw) {
  if (raw > ENCODE_MAX || raw < -ENCODE_MAX) return std::nullopt;
  if (raw >= 0) return Fp::from_u64(static_cast<std::uint64_t>(raw));
  return Fp::from_u64(P - static_cast<std::uint64_t>(-raw));
}

std::int64_t decode(Fp a) {
  if (a.v <= static_cast<std::uint64_t>(ENCODE_MAX)) return static_cast<std::int64_t>(a.v);
  return -static_cast<std::int64_t>(P - a.v);
}

}  // namespace r1::gl
