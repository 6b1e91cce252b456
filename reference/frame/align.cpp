// The frame stage: genesis positions, anchor matching by id, alignment of every particle, RMS (R1-FRM-030..038).
#include <algorithm>
#include <cmath>
#include <string>

#include "r1/fixedpoint/int128.hpp"
#include "r1/reference/frame.hpp"
#include "frame_internal.hpp"

namespace r1 {

namespace {

// Anchor entry index of each snapshot particle (-1 when not in the anchor), by binary search in
// the anchor ids sorted as bytes: O(|P| log C), independent of any hash-table order.
std::vector<std::int64_t> match(const Snapshot& snapshot, const Anchor& anchor) {
  std::vector<std::uint32_t> order(anchor.entries.size());
  for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](std::uint32_t a, std::uint32_t b) { return anchor.entries[a].id < anchor.entries[b].id; });
  std::vector<std::int64_t> entry_of(snapshot.particles.size(), -1);
  for (std::size_t p = 0; p < snapshot.particles.size(); ++p) {
    const auto it = std::lower_bound(order.begin(), order.end(), snapshot.particles[p],
                                     [&](std::uint32_t e, const ParticleId& id) { return anchor.entries[e].id < id; });
    if (it != order.end() && anchor.entries[*it].id == snapshot.particles[p]) entry_of[p] = *it;
  }
  return entry_of;
}

Status align(const Snapshot& snapshot, const Anchor& anchor, const std::string& name, Frame& f) {
  const auto entry_of = match(snapshot, anchor);
  // Matched pairs in anchor-file order (R1-FRM-030).
  std::vector<std::int64_t> particle_of(anchor.entries.size(), -1);
  for (std::size_t p = 0; p < entry_of.size(); ++p)
    if (entry_of[p] >= 0) particle_of[static_cast<std::size_t>(entry_of[p])] = static_cast<std::int64_t>(p);
  std::vector<std::array<Q32, 3>> from, to;
  std::vector<std::size_t> matched;
  for (std::size_t e = 0; e < anchor.entries.size(); ++e) {
    if (particle_of[e] < 0) continue;
    matched.push_back(static_cast<std::size_t>(particle_of[e]));
    from.push_back(f.position[matched.back()]);
    to.push_back(anchor.entries[e].position);
  }
  if (matched.size() < kMinAnchorMatches)
    return Status::input(name + ": only " + std::to_string(matched.size()) + " of " + std::to_string(anchor.entries.size()) +
                         " anchor particles are in this snapshot; alignment needs at least " +
                         std::to_string(kMinAnchorMatches));

  auto sim = similarity_procrustes(from, to);
  if (!sim) return sim.status().with_prefix(name + ": ");
  for (auto& x : f.position) {
    const auto y = apply_similarity(*sim, x);
    if (!y) return Status::input(name + ": the alignment moves a particle outside the Q32 range");
    x = *y;
  }

  // RMS over the matched pairs, the squared distances exact (R1-FRM-037). Each |d| < 2^64, so a
  // square fits u128; the sum carries into a second word and is exact for any input (in
  // practice the anchor's 2^52 bound keeps it below 2^118 and the carry at 0).
  u128 e2 = 0;
  std::uint64_t carry = 0;
  for (std::size_t k = 0; k < matched.size(); ++k)
    for (int c = 0; c < 3; ++c) {
      const i128 d = static_cast<i128>(f.position[matched[k]][c].raw) - to[k][c].raw;
      const u128 ud = d < 0 ? u128{0} - static_cast<u128>(d) : static_cast<u128>(d);
      const u128 sq = ud * ud;
      e2 += sq;
      if (e2 < sq) ++carry;
    }
  const double e2d = frame_detail::to_double_rne(e2) + static_cast<double>(carry) * 0x1p128;
  Alignment& a = f.alignment;
  a.genesis = false;
  a.rotation = sim->rotation;
  a.scale = sim->scale;
  a.translation = sim->translation;
  a.reflected = sim->reflected;
  a.matched = static_cast<std::uint32_t>(matched.size());
  a.rms = std::sqrt(e2d * 0x1p-64 / static_cast<double>(matched.size()));
  return Status::ok();
}

}  // namespace

Result<Frame> compute_frame(const Snapshot& snapshot, const Spectrum<Q32>& conventioned, const Anchor* anchor,
                            const std::string& anchor_name) {
  const auto n = static_cast<std::uint32_t>(snapshot.particles.size());
  R1_ASSIGN(Frame f, genesis_frame(conventioned, n));
  if (anchor == nullptr) return f;
  R1_TRY(align(snapshot, *anchor, anchor_name, f));
  return f;
}

}  // namespace r1
