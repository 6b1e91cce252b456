// build_hierarchy: validation, canonical particle order, the radius choice, and the nodes with
// their AABBs, phi sums and dominant colours (R1-HIER-001..003, R1-HIER-012, R1-HIER-022,
// R1-HIER-033, R1-HIER-040..043, R1-HIER-060, R1-HIER-070).
#include <algorithm>
#include <exception>
#include <limits>
#include <numeric>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "levels.hpp"
#include "r1/reference/hierarchy.hpp"
#include "radius_search.hpp"

namespace r1 {

namespace {

using hier::Items;
using hier::Level;
using hier::Point;

constexpr std::uint32_t kNoParent = 0xFFFFFFFFu;
// R1-HIER-003: |raw| <= 2^60, i.e. 2^28 scene units.
constexpr std::int64_t kMaxCoordRaw = std::int64_t{1} << 60;
constexpr std::int64_t kPhiTotal = std::int64_t{1} << 32;

Status validate(const std::vector<std::array<Q32, 3>>& pos, std::span<const Q32> phi, std::span<const Color> color,
                std::span<const ParticleId> ids, const HierarchyOptions& options) {
  const std::size_t n = pos.size();
  if (n == 0) return Status::input("hierarchy: no particles");
  if (phi.size() != n || color.size() != n || ids.size() != n)
    return Status::input("hierarchy: " + std::to_string(n) + " positions but " + std::to_string(phi.size()) +
                         " phi values, " + std::to_string(color.size()) + " colours and " +
                         std::to_string(ids.size()) + " ids");
  if (n > std::numeric_limits<std::uint32_t>::max() - 1)
    return Status::input("hierarchy: " + std::to_string(n) + " particles is more than 2^32 - 2");
  std::int64_t total = 0;
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t d = 0; d < 3; ++d)
      if (pos[i][d].raw > kMaxCoordRaw || pos[i][d].raw < -kMaxCoordRaw)
        return Status::input("hierarchy: particle " + std::to_string(i) + ": coordinate " + std::to_string(d) + " = " +
                             pos[i][d].to_string() + " lies outside [-2^28, 2^28] scene units");
    if (phi[i].raw <= 0)
      return Status::input("hierarchy: particle " + std::to_string(i) + ": phi raw " + std::to_string(phi[i].raw) +
                           " is not positive");
    if (phi[i].raw > kPhiTotal - total)
      return Status::input("hierarchy: phi raws sum to more than 2^32 (at particle " + std::to_string(i) + ")");
    total += phi[i].raw;
  }
  if (total != kPhiTotal)
    return Status::input("hierarchy: phi raws sum to " + std::to_string(total) + ", not 2^32");
  if (options.radius0_raw && *options.radius0_raw < 0)
    return Status::input("hierarchy: radius0 raw " + std::to_string(*options.radius0_raw) + " is negative");
  return Status::ok();
}

// A sort key and the particle it belongs to: sorting these moves the keys with the particles,
// without a lookup per comparison.
struct Keyed {
  std::uint64_t key;
  std::uint32_t index;
};

// Sorts v by `less`, a strict total order, so that the result is the one sorted sequence
// whichever algorithm runs: TBB's parallel sort when `parallel` (R1-HIER-070).
template <class T, class Less>
void sort_total(std::vector<T>& v, const Less& less, bool parallel) {
  if (parallel) {
    tbb::parallel_sort(v.begin(), v.end(), less);
  } else {
    std::sort(v.begin(), v.end(), less);
  }
}

// The first 8 bytes of an id as a big-endian integer: ids compare as these first (the same
// order as the bytes), then by their remaining bytes.
std::uint64_t id_prefix(const ParticleId& id) {
  std::uint64_t k = 0;
  for (std::size_t b = 0; b < 8; ++b) k = (k << 8) | id[b];
  return k;
}

// Rank of each particle in ascending id byte order; an input error when two ids are equal.
Result<std::vector<std::uint32_t>> id_ranks(std::span<const ParticleId> ids, bool parallel) {
  const auto n = static_cast<std::uint32_t>(ids.size());
  std::vector<Keyed> keyed(n);
  for (std::uint32_t i = 0; i < n; ++i) keyed[i] = {id_prefix(ids[i]), i};
  // Equal ids (an input error) go by index, which keeps the order total.
  sort_total(
      keyed,
      [&](const Keyed& a, const Keyed& b) {
        if (a.key != b.key) return a.key < b.key;
        const ParticleId& ia = ids[a.index];
        const ParticleId& ib = ids[b.index];
        return ia != ib ? ia < ib : a.index < b.index;
      },
      parallel);
  std::vector<std::uint32_t> by_id(n);
  for (std::uint32_t r = 0; r < n; ++r) by_id[r] = keyed[r].index;
  std::vector<std::uint32_t> rank(n);
  for (std::uint32_t r = 0; r < n; ++r) {
    if (r > 0 && ids[by_id[r]] == ids[by_id[r - 1]])
      return Status::input("hierarchy: particles " + std::to_string(std::min(by_id[r], by_id[r - 1])) + " and " +
                           std::to_string(std::max(by_id[r], by_id[r - 1])) + " have the same id");
    rank[by_id[r]] = r;
  }
  return rank;
}

std::uint32_t pack(const Color& c) {
  return (std::uint32_t{c[0]} << 16) | (std::uint32_t{c[1]} << 8) | std::uint32_t{c[2]};
}

// R1-HIER-042 for every node of one level. `by_colour` lists the particles grouped by colour,
// each group in canonical particle order; rank_of gives that order.
void dominant_colours(std::vector<ClusterNode>& nodes, const std::vector<std::uint32_t>& cluster_of,
                      const std::vector<std::uint32_t>& by_colour, std::span<const Color> color,
                      std::span<const Q32> phi, const std::vector<std::uint32_t>& rank_of) {
  const std::size_t count = nodes.size();
  constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::int64_t> best_w(count, 0), acc(count, 0);
  std::vector<std::uint32_t> best_first(count, kNone), first(count, kNone), stamp(count, kNone);
  std::vector<std::uint32_t> touched;
  std::size_t i = 0;
  std::uint32_t group = 0;
  while (i < by_colour.size()) {
    const std::uint32_t key = pack(color[by_colour[i]]);
    touched.clear();
    std::size_t j = i;
    for (; j < by_colour.size() && pack(color[by_colour[j]]) == key; ++j) {
      const std::uint32_t p = by_colour[j];
      const std::uint32_t c = cluster_of[p];
      if (stamp[c] != group) {
        stamp[c] = group;
        acc[c] = 0;
        first[c] = rank_of[p];  // the group is in canonical order: its first member comes first
        touched.push_back(c);
      }
      acc[c] += phi[p].raw;
    }
    for (const std::uint32_t c : touched) {
      // Largest focus weight wins; ties go to the colour whose first particle is canonically first.
      if (acc[c] > best_w[c] || (acc[c] == best_w[c] && first[c] < best_first[c])) {
        best_w[c] = acc[c];
        best_first[c] = first[c];
        nodes[c].color = color[by_colour[i]];
      }
    }
    i = j;
    ++group;
  }
}

u128 isqrt_rounded(u128 v) {
  u128 s = fx::detail::isqrt(v);
  if (v - s * s > s) ++s;  // v >= s^2 + s + 1 <=> sqrt(v) >= s + 1/2 (never a tie for integers)
  return s;
}

Hierarchy assemble(const std::array<Level, kLevels>& levels, std::int64_t radius0_raw,
                   const std::vector<std::array<Q32, 3>>& pos, std::span<const Q32> phi, std::span<const Color> color,
                   const std::vector<std::uint32_t>& rank_of, bool parallel) {
  const auto n = static_cast<std::uint32_t>(pos.size());
  Hierarchy h;
  for (std::size_t l = 0; l < levels.size(); ++l) {
    const Level& lv = levels[l];
    const auto count = static_cast<std::uint32_t>(lv.clusters.size());
    auto& nodes = h.levels[l];
    nodes.resize(count);
    for (std::uint32_t id = 0; id < count; ++id) {
      nodes[id].level = static_cast<std::uint32_t>(l);
      nodes[id].id = id;
      nodes[id].phi_raw = lv.clusters.phi[id];
    }
    auto& of = h.cluster_of[l];
    of.resize(n);
    if (l == 0) {
      for (std::uint32_t p = 0; p < n; ++p) of[p] = lv.cluster_of_item[rank_of[p]];
      // Ascending p: children come out sorted by particle index (R1-HIER-040).
      for (std::uint32_t p = 0; p < n; ++p) {
        ClusterNode& node = nodes[of[p]];
        if (node.children.empty()) {
          node.lo = node.hi = pos[p];
        } else {
          for (std::size_t d = 0; d < 3; ++d) {
            node.lo[d] = std::min(node.lo[d], pos[p][d]);
            node.hi[d] = std::max(node.hi[d], pos[p][d]);
          }
        }
        node.children.push_back(p);
        ++node.particles;
      }
    } else {
      const auto& below = h.levels[l - 1];
      for (std::uint32_t p = 0; p < n; ++p) of[p] = lv.cluster_of_item[h.cluster_of[l - 1][p]];
      for (std::uint32_t c = 0; c < below.size(); ++c) {
        const std::uint32_t parent = lv.cluster_of_item[c];
        h.levels[l - 1][c].parent = parent;
        ClusterNode& node = nodes[parent];
        const ClusterNode& child = h.levels[l - 1][c];
        if (node.children.empty()) {
          node.lo = child.lo;
          node.hi = child.hi;
        } else {
          for (std::size_t d = 0; d < 3; ++d) {
            node.lo[d] = std::min(node.lo[d], child.lo[d]);
            node.hi[d] = std::max(node.hi[d], child.hi[d]);
          }
        }
        node.children.push_back(c);
        node.particles += child.particles;
      }
    }
  }
  for (ClusterNode& top : h.levels[kLevels - 1]) top.parent = kNoParent;

  // Colour groups: particles sorted by colour, then canonical rank (R1-HIER-042).
  // (colour, rank) packed in one key: ranks are distinct, so the order is total.
  std::vector<Keyed> keyed(n);
  for (std::uint32_t p = 0; p < n; ++p) keyed[p] = {(std::uint64_t{pack(color[p])} << 32) | rank_of[p], p};
  sort_total(keyed, [](const Keyed& a, const Keyed& b) { return a.key < b.key; }, parallel);
  std::vector<std::uint32_t> by_colour(n);
  for (std::uint32_t i = 0; i < n; ++i) by_colour[i] = keyed[i].index;
  // The levels are independent: each writes only its own nodes.
  auto colour_level = [&](std::size_t l) { dominant_colours(h.levels[l], h.cluster_of[l], by_colour, color, phi, rank_of); };
  if (parallel) {
    tbb::parallel_for(std::size_t{0}, levels.size(), colour_level);
  } else {
    for (std::size_t l = 0; l < levels.size(); ++l) colour_level(l);
  }

  for (int l = 0; l < kLevels; ++l) {
    const u128 r = isqrt_rounded(hier::radius2_at_level(radius0_raw, l));
    h.radius_raw[static_cast<std::size_t>(l)] =
        r > static_cast<u128>(std::numeric_limits<std::int64_t>::max()) ? std::numeric_limits<std::int64_t>::max()
                                                                       : static_cast<std::int64_t>(r);
  }
  // tau_0 = r0^2 / 4 in scene units squared (R1-HIER-020, R1-HIER-022): r0^2 < 2^126 converts to
  // the nearest double (round to nearest under R1-NUM-001), and the power-of-two scale is exact.
  const u128 r0sq = static_cast<u128>(radius0_raw) * static_cast<u128>(radius0_raw);
  h.tau0 = static_cast<double>(r0sq) * 0x1p-66;
  return h;
}

}  // namespace

Result<Hierarchy> build_hierarchy(const std::vector<std::array<Q32, 3>>& pos, std::span<const Q32> phi,
                                  std::span<const Color> color, std::span<const ParticleId> ids,
                                  const HierarchyOptions& options, const ProgressFn& progress) {
  R1_TRY(validate(pos, phi, color, ids, options));
  try {
    const bool parallel = options.parallel;
    R1_ASSIGN(const std::vector<std::uint32_t> id_rank, id_ranks(ids, parallel));
    const auto n = static_cast<std::uint32_t>(pos.size());
    // Canonical particle order (R1-HIER-012): phi descending, ties by id bytes ascending.
    // phi raws lie in (0, 2^32]: (2^32 - phi, id rank) packed in one key, distinct ranks keeping
    // the order total.
    std::vector<Keyed> keyed(n);
    for (std::uint32_t p = 0; p < n; ++p)
      keyed[p] = {(static_cast<std::uint64_t>(kPhiTotal - phi[p].raw) << 32) | id_rank[p], p};
    sort_total(keyed, [](const Keyed& a, const Keyed& b) { return a.key < b.key; }, parallel);
    std::vector<std::uint32_t> order(n);
    for (std::uint32_t r = 0; r < n; ++r) order[r] = keyed[r].index;
    std::vector<std::uint32_t> rank_of(n);
    Items particles;
    particles.pos.resize(n);
    particles.phi.resize(n);
    particles.min_id.resize(n);
    particles.moment.resize(n);
    auto fill = [&](std::uint32_t r) {  // writes rank r's entries only
      const std::uint32_t p = order[r];
      rank_of[p] = r;
      particles.phi[r] = phi[p].raw;
      particles.min_id[r] = id_rank[p];
      for (std::size_t d = 0; d < 3; ++d) {
        particles.pos[r][d] = pos[p][d].raw;
        particles.moment[r][d] = static_cast<i128>(phi[p].raw) * pos[p][d].raw;  // |.| <= 2^32 * 2^60
      }
    };
    if (parallel) {
      tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, n, 4096), [&](const tbb::blocked_range<std::uint32_t>& rr) {
        for (std::uint32_t r = rr.begin(); r < rr.end(); ++r) fill(r);
      });
    } else {
      for (std::uint32_t r = 0; r < n; ++r) fill(r);
    }
    hier::KdTree tree0(particles.pos, parallel);
    std::int64_t radius0 = 0;
    std::array<Level, kLevels> levels;
    if (options.radius0_raw) {
      radius0 = *options.radius0_raw;
      report(progress, "hierarchy", 0, 1);
      auto built = hier::cluster_levels(particles, tree0, radius0, std::numeric_limits<std::uint64_t>::max(), nullptr, parallel);
      if (!built) return Status::internal("hierarchy: unbounded level build stopped early");
      levels = std::move(*built);
      report(progress, "hierarchy", 1, 1);
    } else {
      hier::RadiusChoice choice = hier::choose_radius(particles, tree0, progress, parallel);
      radius0 = choice.radius0_raw;
      levels = std::move(choice.levels);
    }
    return assemble(levels, radius0, pos, phi, color, rank_of, parallel);
  } catch (const std::exception& e) {
    return Status::internal(std::string("hierarchy: ") + e.what());
  }
}

std::array<std::size_t, kLevels> hierarchy_counts(const Hierarchy& h) {
  std::array<std::size_t, kLevels> c{};
  for (std::size_t l = 0; l < c.size(); ++l) c[l] = h.levels[l].size();
  return c;
}

}  // namespace r1
