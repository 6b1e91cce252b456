// Topology bytes, position deviation and position bytes (R1-CONF-010..021).
#include "r1/conformance/compare.hpp"

#include <cmath>

namespace r1::conformance {

namespace {

void put_u32(std::string& s, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) s.push_back(static_cast<char>((v >> (8 * i)) & 0xFFu));
}
void put_i64(std::string& s, std::int64_t v) {
  const auto u = static_cast<std::uint64_t>(v);
  for (int i = 0; i < 8; ++i) s.push_back(static_cast<char>((u >> (8 * i)) & 0xFFu));
}
std::uint64_t get_u64(std::string_view b, std::size_t at) {
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v |= static_cast<std::uint64_t>(static_cast<unsigned char>(b[at + i])) << (8 * i);
  return v;
}

}  // namespace

std::string topology_bytes(const Hierarchy& h) {
  std::string s = "r1topo1\n";  // a tag and version, so the bytes name what they are
  put_u32(s, static_cast<std::uint32_t>(h.cluster_of[0].size()));
  for (int l = 0; l < kLevels; ++l) {
    put_u32(s, static_cast<std::uint32_t>(h.levels[l].size()));
    for (const auto& node : h.levels[l]) {
      put_u32(s, node.parent);
      put_u32(s, static_cast<std::uint32_t>(node.children.size()));
      for (std::uint32_t c : node.children) put_u32(s, c);
    }
    for (std::uint32_t c : h.cluster_of[l]) put_u32(s, c);
  }
  return s;
}

hemera::Digest topology_digest(const Hierarchy& h) { return hemera::hash(topology_bytes(h)); }

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

std::string position_bytes(const std::vector<std::array<Q32, 3>>& pos) {
  std::string s;
  s.reserve(8 + pos.size() * 24);
  put_i64(s, static_cast<std::int64_t>(pos.size()));
  for (const auto& x : pos)
    for (int a = 0; a < 3; ++a) put_i64(s, x[a].raw);
  return s;
}

Result<std::vector<std::array<Q32, 3>>> parse_position_bytes(std::string_view b, const std::string& name) {
  if (b.size() < 8) return Status::input(name + ": byte 0: truncated position file");
  const std::uint64_t n = get_u64(b, 0);
  if (n > (b.size() - 8) / 24 || b.size() != 8 + n * 24)
    return Status::input(name + ": byte 0: position count " + std::to_string(n) + " does not match the file size " +
                         std::to_string(b.size()));
  std::vector<std::array<Q32, 3>> pos(n);
  for (std::uint64_t p = 0; p < n; ++p)
    for (int a = 0; a < 3; ++a) pos[p][a] = Q32::from_raw(static_cast<std::int64_t>(get_u64(b, 8 + (p * 3 + a) * 8)));
  return pos;
}

}  // namespace r1::conformance
