// The epoch through a backend's stages (R1-BKD-011): the one pipeline of r1::run_epoch
// (R1-EPO-001), with the backend as its stage list. A driver beside the registry: it binds the
// reference's pipeline, so it may include reference/ (spec/backends.md R1-BKD-015).
#include "r1/backends/backend.hpp"
#include "r1/reference/epoch.hpp"

namespace r1::backends {

Result<Epoch> run_epoch(Backend& b, const Snapshot& snapshot, const Graph& graph, const EpochOptions& options,
                        const ProgressFn& progress) {
  return r1::run_epoch(snapshot, graph, options, b, progress);
}

}  // namespace r1::backends
