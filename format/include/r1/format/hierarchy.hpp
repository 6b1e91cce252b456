// The hierarchy's canonical bytes (R1-HIER-050..052, R1-FMT-020): the little-endian
// serialisation whose Hemera hash is the topology digest 12.1 requires to be bit-identical
// across implementations, and its bounds-checked parser.
#pragma once

#include <string>
#include <string_view>

#include "r1/fixedpoint/hemera.hpp"
#include "r1/spec/epoch.hpp"
#include "r1/spec/status.hpp"

namespace r1 {

std::string hierarchy_bytes(const Hierarchy& h);
hemera::Digest hierarchy_digest(const Hierarchy& h);

// Reads bytes written by hierarchy_bytes (R1-HIER-052): every field bounds-checked, a malformed
// or truncated input is an input error naming `name` and the byte offset. The structure is not
// validated against particle data here: check_hierarchy (reference) does that.
Result<Hierarchy> parse_hierarchy_bytes(std::string_view bytes, const std::string& name);

}  // namespace r1
