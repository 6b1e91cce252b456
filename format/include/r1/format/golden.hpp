// The golden set's binary files (spec/conformance.md R1-CONF-010, R1-CONF-021, R1-FMT-020):
// topology bytes (what 12.1 compares) and position bytes, with their parsers.
#pragma once

#include <array>
#include <string>
#include <string_view>
#include <vector>

#include "r1/fixedpoint/hemera.hpp"
#include "r1/fixedpoint/q32.hpp"
#include "r1/spec/epoch.hpp"
#include "r1/spec/status.hpp"

namespace r1::format {

// The tag `r1topo1\n`, the particle count (u32), then per level the cluster count, per cluster
// its parent and children (count, then ids), then every particle's cluster id (R1-CONF-010).
std::string topology_bytes(const Hierarchy& h);
hemera::Digest topology_digest(const Hierarchy& h);
// The parts of a Hierarchy the topology bytes hold (levels' parents and children, cluster_of).
Result<Hierarchy> parse_topology_bytes(std::string_view bytes, const std::string& name);

// The particle count (i64), then x, y, z raws (i64) per particle (R1-CONF-021).
std::string position_bytes(const std::vector<std::array<fx::Q32, 3>>& pos);
Result<std::vector<std::array<fx::Q32, 3>>> parse_position_bytes(std::string_view bytes, const std::string& name);

}  // namespace r1::format
