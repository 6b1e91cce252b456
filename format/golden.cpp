// Topology and position bytes of golden sets (R1-CONF-010, R1-CONF-021, R1-FMT-020).
#include "r1/format/golden.hpp"

#include "r1/format/arrays.hpp"
#include "r1/format/bytes.hpp"

namespace r1::format {

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

Result<Hierarchy> parse_topology_bytes(std::string_view b, const std::string& name) {
  const std::string_view tag = "r1topo1\n";
  if (b.substr(0, tag.size()) != tag) return Status::input(name + ": byte 0: not r1 topology bytes");
  ByteReader r(b.substr(tag.size()), name, tag.size());
  auto truncated = [&] { return r.error("truncated topology"); };
  std::uint32_t n = 0;
  if (!r.u32(n)) return truncated();
  Hierarchy h;
  for (int l = 0; l < kLevels; ++l) {
    std::uint32_t count = 0;
    if (!r.u32(count)) return truncated();
    // Each cluster needs at least 8 bytes: a count larger than the rest of the file is malformed.
    if (count > r.left() / 8) return r.error("cluster count too large");
    h.levels[l].resize(count);
    for (std::uint32_t c = 0; c < count; ++c) {
      ClusterNode& node = h.levels[l][c];
      node.level = static_cast<std::uint32_t>(l);
      node.id = c;
      std::uint32_t k = 0;
      if (!r.u32(node.parent) || !r.u32(k)) return truncated();
      if (k > kMaxChildren) return r.error("more than 16 children");
      node.children.resize(k);
      for (auto& ch : node.children)
        if (!r.u32(ch)) return truncated();
    }
    if (n > r.left() / 4) return truncated();
    h.cluster_of[l].resize(n);
    for (auto& c : h.cluster_of[l])
      if (!r.u32(c)) return truncated();
  }
  if (r.left() != 0) return r.error("trailing bytes");
  return h;
}

std::string position_bytes(const std::vector<std::array<fx::Q32, 3>>& pos) {
  std::string s;
  s.reserve(8 + pos.size() * 24);
  put_i64(s, static_cast<std::int64_t>(pos.size()));
  s += q32_triples(pos);
  return s;
}

Result<std::vector<std::array<fx::Q32, 3>>> parse_position_bytes(std::string_view b, const std::string& name) {
  if (b.size() < 8) return Status::input(name + ": byte 0: truncated position file");
  const std::uint64_t n = load_u64(b.data());
  if (n > (b.size() - 8) / 24 || b.size() != 8 + n * 24)
    return Status::input(name + ": byte 0: position count " + std::to_string(n) + " does not match the file size " +
                         std::to_string(b.size()));
  return read_q32_triples(b.substr(8), n);
}

}  // namespace r1::format
