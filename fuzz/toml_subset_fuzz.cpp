// Fuzz the narrow TOML gate in front of toml++ (R1-IN-005, R1-TEST-010): whatever the gate admits,
// toml++ parses without undefined behaviour (the sanitizers watch), and what it yields holds only
// the value kinds of the subset: strings, integers, booleans, arrays and tables.
#include "fuzz_target.hpp"
#include "toml_subset.hpp"

namespace {
void check_kinds(const toml::node& n, int depth) {
  R1_FUZZ_CHECK(depth < 64);
  if (const auto* t = n.as_table()) {
    for (const auto& [k, v] : *t) check_kinds(v, depth + 1);
  } else if (const auto* a = n.as_array()) {
    for (const auto& v : *a) check_kinds(v, depth + 1);
  } else {
    R1_FUZZ_CHECK(n.is_string() || n.is_integer() || n.is_boolean());
  }
}
}  // namespace

R1_FUZZ_TARGET(toml_subset) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  auto t = r1::toml_subset::parse(text, "fuzz.toml");
  if (t.is_ok()) check_kinds(*t, 0);
  return 0;
}
