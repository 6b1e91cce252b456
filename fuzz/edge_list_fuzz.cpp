// Fuzz the TSV and CSV readers (R1-TEST-010): the first byte picks the dialect; no crash, and an
// accepted list written back as an edge list reads to the same snapshot digest and names.
#include "fuzz_target.hpp"
#include "readers.hpp"

R1_FUZZ_TARGET(edge_list) {
  if (size == 0) return 0;
  const bool csv = (data[0] & 1) != 0;
  const std::string_view bytes(reinterpret_cast<const char*>(data + 1), size - 1);
  auto s = r1::detail::read_edge_list(bytes, "fuzz", csv, {});
  if (!s.is_ok()) return 0;
  r1::Status st;
  const std::string out = r1::detail::edge_list_bytes(*s, csv, st);
  if (!st.is_ok()) {
    R1_FUZZ_CHECK(!csv);  // only TSV refuses names (tabs, line ends, leading '#')
    return 0;
  }
  auto back = r1::detail::read_edge_list(out, "written", csv, {});
  R1_FUZZ_CHECK(back.is_ok());
  R1_FUZZ_CHECK(back->names == s->names);
  R1_FUZZ_CHECK(r1::snapshot_digest(*back) == r1::snapshot_digest(*s));
  return 0;
}
