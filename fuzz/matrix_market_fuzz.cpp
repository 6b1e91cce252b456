// Fuzz the Matrix Market reader (R1-TEST-010): no crash; accepted files give links whose
// endpoints are particles and whose weights are positive.
#include "fuzz_target.hpp"
#include "readers.hpp"

R1_FUZZ_TARGET(matrix_market) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  auto s = r1::detail::read_matrix_market(bytes, "fuzz.mtx", {});
  if (!s.is_ok()) return 0;
  R1_FUZZ_CHECK(!s->links.empty());
  for (const auto& l : s->links) {
    R1_FUZZ_CHECK(l.from < s->particles.size() && l.to < s->particles.size());
    R1_FUZZ_CHECK(l.amount > 0);
  }
  return 0;
}
