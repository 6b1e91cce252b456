// Topology differences and position deviation (R1-CONF-010..021); the topology and position
// bytes are the format library's (r1/format/golden.hpp).
#include "r1/conformance/compare.hpp"

#include <cmath>

namespace r1::conformance {

std::string topology_difference(const Hierarchy& got, const Hierarchy& want) {
  if (got.cluster_of[0].size() != want.cluster_of[0].size())
    return std::to_string(got.cluster_of[0].size()) + " particles, expected " + std::to_string(want.cluster_of[0].size());
  for (int l = 0; l < kLevels; ++l) {
    const std::string lv = "level " + std::to_string(l) + ": ";
    if (got.levels[l].size() != want.levels[l].size())
      return lv + std::to_string(got.levels[l].size()) + " clusters, expected " + std::to_string(want.levels[l].size());
    for (std::size_t p = 0; p < got.cluster_of[l].size(); ++p)
      if (got.cluster_of[l][p] != want.cluster_of[l][p])
        return lv + "particle " + std::to_string(p) + " is in cluster " + std::to_string(got.cluster_of[l][p]) +
               ", expected " + std::to_string(want.cluster_of[l][p]);
    for (std::size_t c = 0; c < got.levels[l].size(); ++c) {
      const auto& a = got.levels[l][c];
      const auto& b = want.levels[l][c];
      if (a.parent != b.parent)
        return lv + "cluster " + std::to_string(c) + " has parent " + std::to_string(a.parent) + ", expected " +
               std::to_string(b.parent);
      if (a.children != b.children) return lv + "cluster " + std::to_string(c) + " has other children";
    }
  }
  return "";
}

Result<PositionDeviation> position_deviation(const std::vector<std::array<Q32, 3>>& got,
                                             const std::vector<std::array<Q32, 3>>& want) {
  if (got.size() != want.size())
    return Status::input("positions of " + std::to_string(got.size()) + " particles, expected " +
                         std::to_string(want.size()));
  PositionDeviation d;
  for (std::size_t p = 0; p < got.size(); ++p) {
    double s = 0;
    for (int a = 0; a < 3; ++a) {
      // The difference of two raws is exact in int64 for |raw| < 2^62; to double it rounds once.
      const double x = static_cast<double>(got[p][a].raw - want[p][a].raw) / 4294967296.0;
      s += x * x;
    }
    const double r = std::sqrt(s) / static_cast<double>(kSceneRadius);
    if (r > d.max_over_r) d = {r, static_cast<std::uint32_t>(p)};
  }
  return d;
}

}  // namespace r1::conformance
