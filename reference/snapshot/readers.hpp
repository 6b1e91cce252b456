// Internal entry points of the snapshot readers and writers (R1-IN-001..035).
#pragma once

#include <functional>
#include <string>
#include <string_view>

#include "r1/reference/graph_container.hpp"
#include "r1/reference/snapshot_io.hpp"

namespace r1::detail {

// `consumed`, when set, is told of record bytes the parse is done with (R1-IN-022), a part at a time.
Result<Snapshot> read_graph_file(std::string_view bytes, const std::string& file, const ProgressFn& progress,
                                 const std::function<void(std::string_view)>& consumed = {});
Result<Snapshot> read_edge_list(std::string_view bytes, const std::string& file, bool csv, const ProgressFn& progress);
Result<Snapshot> read_matrix_market(std::string_view bytes, const std::string& file, const ProgressFn& progress);

// Side files and the matching .graph extension sections.
enum class SideKind { kTitles, kCrystal };
// Side file: keys are particle names (text inputs) or 64-hex ids; unknown keys are counted in
// `unmatched` and otherwise ignored. Section: keys are hex ids and must all be particles.
Status apply_side_text(Snapshot& s, std::string_view text, const std::string& where, SideKind kind, bool strict,
                       std::size_t first_line, std::size_t* unmatched);
std::string format_titles_section(const Snapshot& s);
std::string format_crystal_section(const Snapshot& s);

std::string edge_list_bytes(const Snapshot& s, bool csv, Status& status);

}  // namespace r1::detail
