// Builds the layout graph of a snapshot (decision 3, R1-IN-050..058).
#pragma once

#include "r1/spec/graph.hpp"
#include "r1/spec/progress.hpp"
#include "r1/spec/snapshot.hpp"
#include "r1/spec/status.hpp"

namespace r1 {

// Fails (bad input) when the snapshot has no link left after dropping self-loops, or when an
// exact weight sum overflows 128 bits. `parallel` runs the per-row passes (sorts, exact merges,
// Q32 values, degrees) on TBB workers: the same graph, bit for bit.
Result<Graph> build_graph(const Snapshot& s, const ProgressFn& progress = {}, bool parallel = true);
// The same graph for a caller that needs the link records no more (it formed the snapshot's
// digest already): they are released as soon as the graph's directed rows hold them, before the
// rest of the build, the load's peak of memory (R1-EPO-005). After a successful build `s.links`
// is empty.
Result<Graph> build_graph_releasing_links(Snapshot& s, const ProgressFn& progress = {}, bool parallel = true);

// round(value * 2^32 / scale), ties to even, for 0 <= value <= scale, scale > 0: the Q32 weight
// normalisation of R1-IN-052. Exact for every u128 input.
std::int64_t scale_to_q32(u128 value, u128 scale);

}  // namespace r1
