// Differential fuzzing of the backends (R1-TEST-010, R1-TEST-054): the bytes make a small graph;
// every registered backend that is expected to conform runs the epoch, and any difference from
// the reference (success or failure, topology bytes, position bytes) is a finding.
#include <string>

#include "fuzz_target.hpp"
#include "r1/backends/registry.hpp"
#include "r1/conformance/compare.hpp"
#include "r1/reference/graph_build.hpp"
#include "r1/reference/snapshot_builder.hpp"

namespace {

// Particles a graph may name: 48 keeps the three conformant epochs of an input near 50 ms under
// ASan + UBSan (about 20 inputs a second) and still gives the hierarchy several level-0 clusters.
constexpr std::uint32_t kMaxParticles = 48;
// Links read from the input, 3 bytes each: enough for a 48-particle ring plus chords.
constexpr std::size_t kMaxLinks = 96;
// Link weights are (1 + the low 6 bits of the weight byte) / 16: 1/16 to 4, so weight ratios of
// up to 64 reach the focus and the frame without any weight being zero.
constexpr int kWeightShift = 28;

// The graph of the bytes. Byte 0: the particle count n = 1 + byte % 48 (names p0..p{n-1}). Then
// per link 3 bytes: source % n, target % n, and a byte whose low 6 bits give the weight and whose
// top 2 the valence (0: -1, 1: 0, 2: +1, 3: 0). Particles exist by appearing in a link, so small,
// disconnected graphs and particles known only from a self-loop (isolated) all occur.
r1::Result<r1::Snapshot> snapshot_of(const std::uint8_t* data, std::size_t size) {
  if (size < 4) return r1::Status::input("fewer than 4 bytes");
  const std::uint32_t n = 1 + data[0] % kMaxParticles;
  r1::SnapshotBuilder b("fuzz");
  b.snapshot().config = r1::text_input_config();
  for (std::size_t k = 0; k < kMaxLinks && 1 + 3 * k + 2 < size; ++k) {
    const std::uint8_t* l = data + 1 + 3 * k;
    r1::Link link;
    link.height = 1;
    link.amount = static_cast<r1::u128>(1 + (l[2] & 0x3F)) << kWeightShift;
    const int v = l[2] >> 6;
    link.valence = static_cast<std::int8_t>(v == 0 ? -1 : (v == 2 ? 1 : 0));
    link.from = b.particle_by_name("p" + std::to_string(l[0] % n));  // source before target: decision 2
    link.to = b.particle_by_name("p" + std::to_string(l[1] % n));
    b.add_link(link);
  }
  return b.finish();
}

[[noreturn]] void differs(const std::string& backend, const std::string& what) {
  const std::string msg = "backend '" + backend + "' differs from the reference: " + what;
  r1::fuzz::fail(__FILE__, __LINE__, msg.c_str());
}

}  // namespace

R1_FUZZ_TARGET(backend_diff) {
  auto snapshot = snapshot_of(data, size);
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
