// The canonical little-endian bytes of a hierarchy, their parser and the topology digest
// (R1-HIER-050..052, R1-FMT-020).
#include "r1/format/hierarchy.hpp"

#include "r1/fixedpoint/int128.hpp"
#include "r1/format/bytes.hpp"

namespace r1 {

using format::put_i64;
using format::put_u32;
using format::put_u8;

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

Result<Hierarchy> parse_hierarchy_bytes(std::string_view bytes, const std::string& name) {
  // One reader past the magic: its errors name the byte where reading stopped.
  format::ByteReader body(bytes, name);
  if (bytes.substr(0, 8) != "R1HIER01") return body.error("not an r1 hierarchy (expected R1HIER01)");
  body.skip(8);
  const auto truncated = [&] { return body.error("truncated hierarchy"); };
  std::uint32_t n = 0, levels = 0;
  if (!body.u32(n) || !body.u32(levels)) return truncated();
  if (levels != kLevels)
    return body.error_at(body.offset() - 4, "hierarchy has " + std::to_string(levels) + " levels, r1 reads 4");
  Hierarchy h;
  for (std::size_t l = 0; l < kLevels; ++l) {
    std::uint32_t count = 0;
    if (!body.i64(h.radius_raw[l]) || !body.u32(count)) return truncated();
    // Each node takes at least 61 bytes: a count beyond what is left is corrupt, not a reason to allocate.
    if (count > body.left() / 61) return truncated();
    h.levels[l].resize(count);
    for (std::uint32_t id = 0; id < count; ++id) {
      ClusterNode& node = h.levels[l][id];
      node.level = static_cast<std::uint32_t>(l);
      node.id = id;
      std::uint8_t children = 0;
      if (!body.u32(node.parent) || !body.u32(node.particles) || !body.i64(node.phi_raw)) return truncated();
      for (Q32& v : node.lo)
        if (!body.i64(v.raw)) return truncated();
      for (Q32& v : node.hi)
        if (!body.i64(v.raw)) return truncated();
      for (std::uint8_t& c : node.color)
        if (!body.u8(c)) return truncated();
      if (!body.u8(children)) return truncated();
      node.children.resize(children);
      for (std::uint32_t& c : node.children)
        if (!body.u32(c)) return truncated();
    }
  }
  if (body.left() != static_cast<std::size_t>(n) * kLevels * 4)
    return Status::input(name + ": " + std::to_string(bytes.size()) + " bytes do not end with " + std::to_string(n) +
                         " cluster ids per level");
  for (auto& of : h.cluster_of) {
    of.resize(n);
    for (std::uint32_t& c : of) body.u32(c);
  }
  // tau0 as build_hierarchy reports it (R1-HIER-022): radius_raw[0] is r0 itself (the rounded
  // square root of r0^2), so r0^2 / 2^66 is the same double.
  if (h.radius_raw[0] < 0) return Status::input(name + ": negative clustering radius");
  const u128 r0sq = static_cast<u128>(h.radius_raw[0]) * static_cast<u128>(h.radius_raw[0]);
  h.tau0 = static_cast<double>(r0sq) * 0x1p-66;
  return h;
}

hemera::Digest hierarchy_digest(const Hierarchy& h) { return hemera::hash(hierarchy_bytes(h)); }

}  // namespace r1
