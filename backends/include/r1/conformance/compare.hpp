// The comparisons of section 15 (spec/conformance.md R1-CONF-010..032): topology as
// canonical bytes, position deviation in units of R_scene, pixels as CIEDE2000 of the display
// images. Shared by `r1 conform`, `r1 golden`, the property library and the differential fuzzer.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "r1/fixedpoint/hemera.hpp"
#include "r1/format/golden.hpp"
#include "r1/spec/epoch.hpp"
#include "r1/spec/status.hpp"

namespace r1::conformance {

// 12.2 / 15.2: epsilon_X = 1e-3 R_scene. 15.3: mean Delta E <= 2.
inline constexpr double kPositionBound = 1e-3;
inline constexpr double kPixelBound = 2.0;

// The topology of 12.1 as canonical bytes (R1-CONF-010) and positions as bytes
// (R1-CONF-021): the format library's codecs (r1/format/golden.hpp). AABBs, focus sums and colours
// are left out of the topology: they are held by P_RENDER_POS, not by the strict topology check.
using format::parse_position_bytes;
using format::position_bytes;
using format::topology_bytes;
using format::topology_digest;

// The first difference between two topologies, in words ("level 0: particle 17 is in cluster 3,
// expected 4"); empty when they are the same.
std::string topology_difference(const Hierarchy& got, const Hierarchy& want);

// max_p ||X_got(p) - X_want(p)||_2 / R_scene (R1-CONF-020), and the particle where it is reached.
// Different particle counts are an input error.
struct PositionDeviation {
  double max_over_r = 0;
  std::uint32_t worst = 0;
};
Result<PositionDeviation> position_deviation(const std::vector<std::array<Q32, 3>>& got,
                                             const std::vector<std::array<Q32, 3>>& want);


}  // namespace r1::conformance
