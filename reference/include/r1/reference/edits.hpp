// Edit files: add, remove and reweight cyberlinks of a snapshot (spec/edits.md R1-EDT-001..030).
// `r1 edit` applies one to a snapshot; `r1 drift` draws random ones.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "r1/spec/snapshot.hpp"
#include "r1/spec/status.hpp"

namespace r1 {

enum class EditOp { kAdd, kRemove, kReweight };

// One edit. Particles are named as in edge lists (R1-EDT-010): a name in a snapshot read from
// text, else (or for an existing particle, always) a 64-hex-digit id.
struct Edit {
  EditOp op = EditOp::kAdd;
  std::string from, to;
  u128 amount = u128{1} << 32;  // add and reweight: weight x 2^32 (R1-IN-013)
  std::int8_t valence = 0;       // add only
  std::size_t line = 0;          // 1-based line in its file, for messages (0: not from a file)
};

struct EditCounts {
  std::size_t added = 0, removed = 0, reweighted = 0;  // edits applied, by kind
  std::size_t links_removed = 0;                      // link records deleted (remove, reweight's parallels)
  std::size_t new_particles = 0, dropped_particles = 0;
};

// Parses an edit file's text (R1-EDT-001..005); `where` names it in messages ("FILE:LINE: ...").
Result<std::vector<Edit>> parse_edits(std::string_view text, const std::string& where);

// The edit file line of one edit (parse_edits reads it back to the same edit).
std::string format_edit(const Edit& e);

// Applies the edits in order (R1-EDT-020..030): each sees the links the ones before it left.
// Particles are renumbered by first appearance; particles left without links leave the snapshot;
// titles and crystal tags follow their particles. `where` names the edit file in messages.
Result<Snapshot> apply_edits(const Snapshot& s, const std::vector<Edit>& edits, const std::string& where,
                             EditCounts* counts = nullptr);

}  // namespace r1
