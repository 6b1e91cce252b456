// check_hierarchy: the structural invariants of a hierarchy against its inputs, recomputed
// independently of the builder (R1-HIER-002, R1-HIER-013, R1-HIER-015, R1-HIER-022,
// R1-HIER-040..043).
#include <algorithm>
#include <numeric>
#include <span>
#include <string>

#include "r1/fixedpoint/q32.hpp"
#include "r1/reference/hierarchy.hpp"

namespace r1 {

namespace {

Status fail(std::size_t level, std::size_t id, const std::string& what) {
  return Status::internal("hierarchy check: level " + std::to_string(level) + " node " + std::to_string(id) + ": " +
                          what);
}

}  // namespace

Status check_hierarchy(const Hierarchy& h, const std::vector<std::array<Q32, 3>>& pos, std::span<const Q32> phi,
                       std::span<const Color> color, std::span<const ParticleId> ids) {
  const std::size_t n = pos.size();
  if (phi.size() != n || color.size() != n || ids.size() != n)
    return Status::internal("hierarchy check: input lengths differ");
  // Canonical particle order (R1-HIER-012), for the colour tie rule: phi descending, ties by the
  // id bytes (their first eight as a big-endian number first, the rest only when those tie). A
  // comparison, not a rank table: only colour ties need it, and sorting every particle was most
  // of the check's time at 10^6 particles.
  std::vector<std::uint64_t> prefix(n);
  for (std::size_t p = 0; p < n; ++p)
    for (std::size_t b = 0; b < 8; ++b) prefix[p] = (prefix[p] << 8) | ids[p][b];
  const auto before = [&](std::size_t a, std::size_t b) {
    if (phi[a].raw != phi[b].raw) return phi[a].raw > phi[b].raw;
    return prefix[a] != prefix[b] ? prefix[a] < prefix[b] : ids[a] < ids[b];
  };
  std::int64_t total_phi = 0;
  for (const Q32 v : phi) total_phi += v.raw;

  std::vector<std::size_t> by_colour;  // one node's members, sorted by colour
  for (std::size_t l = 0; l < h.levels.size(); ++l) {
    const auto& nodes = h.levels[l];
    const auto& of = h.cluster_of[l];
    if (nodes.empty()) return Status::internal("hierarchy check: level " + std::to_string(l) + " is empty");
    if (of.size() != n) return Status::internal("hierarchy check: cluster_of[" + std::to_string(l) + "] has wrong length");
    // Members of every node from cluster_of, independently of the children lists: node c's are
    // flat[start[c], start[c + 1]), ascending.
    std::vector<std::size_t> start(nodes.size() + 1, 0), flat(n);
    for (std::size_t p = 0; p < n; ++p) {
      if (of[p] >= nodes.size()) return Status::internal("hierarchy check: cluster_of out of range");
      ++start[of[p] + 1];
    }
    std::partial_sum(start.begin(), start.end(), start.begin());
    {
      std::vector<std::size_t> at(start.begin(), start.end() - 1);
      for (std::size_t p = 0; p < n; ++p) flat[at[of[p]]++] = p;
    }
    const auto members = [&](std::size_t c) {
      return std::span<const std::size_t>(flat.data() + start[c], start[c + 1] - start[c]);
    };
    for (std::size_t p = 0; p < n; ++p) {
      if (l + 1 < h.levels.size()) {
        const auto& up = h.cluster_of[l + 1];
        if (up.size() != n || nodes[of[p]].parent != up[p])
          return fail(l, of[p], "parent differs from the next level's cluster of particle " + std::to_string(p));
      }
    }
    std::int64_t level_phi = 0;
    for (std::size_t id = 0; id < nodes.size(); ++id) {
      const ClusterNode& node = nodes[id];
      const auto mem = members(id);
      if (node.level != l || node.id != id) return fail(l, id, "wrong level or id field");
      if (mem.empty()) return fail(l, id, "has no particles");
      if (node.children.empty() || node.children.size() > static_cast<std::size_t>(kMaxChildren))
        return fail(l, id, std::to_string(node.children.size()) + " children");
      if (!std::is_sorted(node.children.begin(), node.children.end()) ||
          std::adjacent_find(node.children.begin(), node.children.end()) != node.children.end())
        return fail(l, id, "children not strictly ascending");
      if (l == h.levels.size() - 1 && node.parent != 0xFFFFFFFFu) return fail(l, id, "top-level node has a parent");
      // Children agree with cluster_of: level 0 lists exactly the members; above, exactly the
      // clusters below whose parent this is, and their particles add up.
      if (l == 0) {
        if (!std::equal(node.children.begin(), node.children.end(), mem.begin(), mem.end()))
          return fail(l, id, "children are not exactly its particles");
      } else {
        std::size_t below = 0;
        for (const std::uint32_t c : node.children) {
          if (c >= h.levels[l - 1].size() || h.levels[l - 1][c].parent != id) return fail(l, id, "child without parent link");
          below += h.levels[l - 1][c].particles;
        }
        if (below != mem.size()) return fail(l, id, "children do not cover its particles");
      }
      if (node.particles != mem.size()) return fail(l, id, "particle count");
      std::array<Q32, 3> lo = pos[mem[0]], hi = pos[mem[0]];
      std::int64_t s = 0;
      by_colour.clear();
      for (const std::size_t p : mem) {
        for (std::size_t d = 0; d < 3; ++d) {
          lo[d] = std::min(lo[d], pos[p][d]);
          hi[d] = std::max(hi[d], pos[p][d]);
        }
        s += phi[p].raw;
        by_colour.push_back(p);
      }
      if (lo != node.lo || hi != node.hi) return fail(l, id, "AABB is not the tight box of its particles");
      if (s != node.phi_raw) return fail(l, id, "phi_raw is not the exact sum");
      level_phi += s;
      // The dominant colour: the most phi, ties by the colour whose first member comes first in
      // canonical order (ids are distinct, so the best is unique).
      std::sort(by_colour.begin(), by_colour.end(), [&](std::size_t a, std::size_t b) { return color[a] < color[b]; });
      std::int64_t best_w = -1;
      std::size_t best_first = 0;  // compared only once best_w is a colour's weight
      Color best{};
      for (std::size_t i = 0; i < by_colour.size();) {
        std::int64_t w = 0;
        std::size_t first = by_colour[i];  // the colour's member first in canonical order
        std::size_t j = i;
        for (; j < by_colour.size() && color[by_colour[j]] == color[by_colour[i]]; ++j) {
          w += phi[by_colour[j]].raw;
          if (before(by_colour[j], first)) first = by_colour[j];
        }
        if (w > best_w || (w == best_w && before(first, best_first))) {
          best_w = w;
          best_first = first;
          best = color[by_colour[i]];
        }
        i = j;
      }
      if (best != node.color) return fail(l, id, "colour is not the dominant colour");
      // Canonical order (R1-HIER-013): phi descending, ties by the lowest member id.
      if (id > 0) {
        const ClusterNode& prev = nodes[id - 1];
        const auto lowest = [&](std::size_t k) {
          ParticleId m = ids[members(k)[0]];
          for (const std::size_t p : members(k)) m = std::min(m, ids[p]);
          return m;
        };
        if (prev.phi_raw < node.phi_raw || (prev.phi_raw == node.phi_raw && !(lowest(id - 1) < lowest(id))))
          return fail(l, id, "out of canonical order");
      }
    }
    if (level_phi != total_phi)
      return Status::internal("hierarchy check: level " + std::to_string(l) + " phi sums differ from the total");
  }
  // Radii (R1-HIER-021..022): radius_raw[L] = round(sqrt(r0^2 10^L)) from radius_raw[0].
  const u128 r0 = static_cast<u128>(h.radius_raw[0]);
  u128 r2 = r0 * r0;
  for (std::size_t l = 1; l < h.radius_raw.size(); ++l) {
    r2 = r2 > u128_max / 10 ? u128_max : r2 * 10;
    u128 s = fx::detail::isqrt(r2);
    if (r2 - s * s > s) ++s;
    const auto want = s > static_cast<u128>(INT64_MAX) ? INT64_MAX : static_cast<std::int64_t>(s);
    if (h.radius_raw[l] != want) return Status::internal("hierarchy check: radius_raw[" + std::to_string(l) + "]");
  }
  return Status::ok();
}

}  // namespace r1
