// Differential fuzzing of the backends (R1-TEST-010, R1-TEST-054): the bytes make a small graph;
// every registered backend that is expected to conform runs the epoch, and any difference from
// the reference (success or failure, topology bytes, position bytes) is a finding.
#include <string>

#include "fuzz_graph.hpp"
#include "fuzz_target.hpp"
#include "r1/backends/registry.hpp"
#include "r1/conformance/compare.hpp"
#include "r1/reference/graph_build.hpp"

namespace {

[[noreturn]] void differs(const std::string& backend, const std::string& what) {
  const std::string msg = "backend '" + backend + "' differs from the reference: " + what;
  r1::fuzz::fail(__FILE__, __LINE__, msg.c_str());
}

}  // namespace

R1_FUZZ_TARGET(backend_diff) {
  auto snapshot = r1::fuzz::snapshot_of(data, size);
  if (!snapshot.is_ok()) return 0;
  auto graph = r1::build_graph(*snapshot);
  if (!graph.is_ok()) return 0;  // only self-loops: no layout graph
  auto reference = r1::backends::make_backend("reference");
  R1_FUZZ_CHECK(reference.is_ok());
  const auto want = r1::backends::run_epoch(**reference, *snapshot, *graph, {});
  // Every conformant backend, the reference's own adapter included (a fresh one: the same bits
  // twice), through the same pipeline.
  for (const auto& info : r1::backends::registered_backends()) {
    if (!info.expected_conformant) continue;
    const auto backend = info.make();
    const auto got = r1::backends::run_epoch(*backend, *snapshot, *graph, {});
    if (got.is_ok() != want.is_ok())
      differs(info.name, got.is_ok() ? "succeeded where the reference failed: " + want.status().message()
                                     : "failed where the reference succeeded: " + got.status().message());
    if (!want.is_ok()) continue;
    if (r1::conformance::topology_bytes(got->hierarchy) != r1::conformance::topology_bytes(want->hierarchy))
      differs(info.name, "topology: " + r1::conformance::topology_difference(got->hierarchy, want->hierarchy));
    // A backend that promises deterministic Q32 must give the same position bytes; another
    // (fp64) must stay within 12.2's bound.
    if (backend->deterministic_mode() && backend->numeric_domain() == r1::backends::Domain::kFixedQ32) {
      if (r1::conformance::position_bytes(got->frame.position) != r1::conformance::position_bytes(want->frame.position))
        differs(info.name, "position bytes");
    } else {
      const auto d = r1::conformance::position_deviation(got->frame.position, want->frame.position);
      if (!d.is_ok() || d->max_over_r > r1::conformance::kPositionBound)
        differs(info.name, "positions beyond 1e-3 R_scene");
    }
  }
  return 0;
}
