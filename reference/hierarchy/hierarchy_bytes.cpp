// The canonical little-endian bytes of a hierarchy and its topology digest (R1-HIER-050..051).
#include "r1/reference/hierarchy.hpp"

namespace r1 {

namespace {

void put_u8(std::string& out, std::uint8_t v) { out.push_back(static_cast<char>(v)); }

void put_u32(std::string& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xFFu));
}

void put_i64(std::string& out, std::int64_t v) {
  const auto u = static_cast<std::uint64_t>(v);  // two's complement
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<char>((u >> (8 * i)) & 0xFFu));
}

}  // namespace

std::string hierarchy_bytes(const Hierarchy& h) {
  std::string out;
  std::size_t nodes = 0;
  for (const auto& level : h.levels) nodes += level.size();
  const std::size_t n = h.cluster_of[0].size();
  out.reserve(16 + kLevels * 12 + nodes * (8 + 8 + 48 + 4 + 4 * kMaxChildren) + kLevels * 4 * n);
  out.append("R1HIER01");  // format tag and version
  put_u32(out, static_cast<std::uint32_t>(n));
  put_u32(out, static_cast<std::uint32_t>(kLevels));
  for (std::size_t l = 0; l < h.levels.size(); ++l) {
    put_i64(out, h.radius_raw[l]);
    put_u32(out, static_cast<std::uint32_t>(h.levels[l].size()));
    for (const ClusterNode& node : h.levels[l]) {
      put_u32(out, node.parent);
      put_u32(out, node.particles);
      put_i64(out, node.phi_raw);
      for (const Q32 v : node.lo) put_i64(out, v.raw);
      for (const Q32 v : node.hi) put_i64(out, v.raw);
      for (const std::uint8_t c : node.color) put_u8(out, c);
      // One byte suffices: a valid node has at most kMaxChildren = 16 (check_hierarchy).
      put_u8(out, static_cast<std::uint8_t>(node.children.size()));
      for (const std::uint32_t c : node.children) put_u32(out, c);
    }
  }
  for (const auto& of : h.cluster_of)
    for (const std::uint32_t c : of) put_u32(out, c);
  return out;
}

hemera::Digest hierarchy_digest(const Hierarchy& h) { return hemera::hash(hierarchy_bytes(h)); }

}  // namespace r1
