// Fuzz the .graph reader (R1-TEST-010): no crash; an accepted container serialises back to the
// same bytes; an accepted snapshot survives the canonical writer with its digest.
#include "fuzz_target.hpp"
#include "readers.hpp"

R1_FUZZ_TARGET(graph_file) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  auto c = r1::parse_container(bytes, "fuzz.graph");
  if (!c.is_ok()) return 0;
  R1_FUZZ_CHECK(c->serialize() == bytes);
  auto s = r1::detail::read_graph_file(bytes, "fuzz.graph", {});
  if (!s.is_ok()) return 0;
  const std::string canonical = r1::graph_file_bytes(*s, "fuzz");
  auto back = r1::detail::read_graph_file(canonical, "canonical.graph", {});
  R1_FUZZ_CHECK(back.is_ok());
  R1_FUZZ_CHECK(r1::snapshot_digest(*back) == r1::snapshot_digest(*s));
  R1_FUZZ_CHECK(r1::graph_file_bytes(*back, "fuzz") == canonical);
  return 0;
}
