// The spatial hierarchy: four nested heat-kernel levels with canonical labels, its canonical bytes
// and topology digest, and an invariant checker (R-1.0 section 10, 12.1; R1-HIER-001..061).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "r1/fixedpoint/hemera.hpp"
#include "r1/format/hierarchy.hpp"
#include "r1/spec/epoch.hpp"
#include "r1/spec/epoch_options.hpp"
#include "r1/spec/progress.hpp"
#include "r1/spec/snapshot.hpp"
#include "r1/spec/status.hpp"

namespace r1 {

using Color = std::array<std::uint8_t, 3>;

// Builds the hierarchy of R1-HIER-001..043. pos, phi, color and ids are per particle in canonical
// order (all the same length, at least 1); phi raws are > 0 and sum to exactly 2^32; ids are
// distinct; every coordinate lies in (-2^30, 2^30) scene units. Violations are input errors;
// an arithmetic failure inside is an internal error. Same inputs, same result on every machine.
Result<Hierarchy> build_hierarchy(const std::vector<std::array<Q32, 3>>& pos, std::span<const Q32> phi,
                                  std::span<const Color> color, std::span<const ParticleId> ids,
                                  const HierarchyOptions& options = {}, const ProgressFn& progress = {});

// The canonical bytes (hierarchy_bytes, parse_hierarchy_bytes, hierarchy_digest) are the format
// library's: r1/format/hierarchy.hpp, included here.

// Clusters per level, finest first.
std::array<std::size_t, kLevels> hierarchy_counts(const Hierarchy& h);

// Checks every structural invariant of R1-HIER-040..043 against the inputs: partition and
// nesting, parent/children agreement, at most 16 children, tight AABBs, exact phi sums, member
// counts, the canonical id order and the dominant colour. OK or an internal error naming the
// first violation. Does not re-run the clustering (R1-HIER-010..033 are checked by tests).
Status check_hierarchy(const Hierarchy& h, const std::vector<std::array<Q32, 3>>& pos, std::span<const Q32> phi,
                       std::span<const Color> color, std::span<const ParticleId> ids);

}  // namespace r1
