// Exact dot products and sums of Q32 spans, rounded once (R1-NUM-031, R1-NUM-033).
#include "r1/fixedpoint/exact_sum.hpp"

#include <stdexcept>

namespace r1::fx {

Q32 exact_dot(std::span<const Q32> a, std::span<const Q32> b) {
  if (a.size() != b.size()) throw std::invalid_argument("exact_dot: spans of different lengths");
  ExactSum s;
  for (std::size_t i = 0; i < a.size(); ++i) s.add_product(a[i], b[i]);
  return s.round();
}

Q32 exact_sum(std::span<const Q32> x) {
  ExactSum s;
  for (const Q32 v : x) s.add(v);
  return s.round();
}

}  // namespace r1::fx
