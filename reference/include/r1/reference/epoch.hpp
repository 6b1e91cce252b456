// The epoch pipeline (R1-EPO-001..004, R1-BKD-011): snapshot -> graph -> spectrum -> focus ->
// frame -> encoding -> hierarchy, in the canonical Q32 domain or fp64, over any implementation of
// the stage list (r1/spec/stages.hpp); the reference's own stages are ReferenceStages.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "r1/reference/encoding.hpp"
#include "r1/reference/hierarchy.hpp"
#include "r1/solvers/focus.hpp"
#include "r1/solvers/spectral.hpp"
#include "r1/spec/epoch.hpp"
#include "r1/spec/epoch_options.hpp"
#include "r1/spec/graph.hpp"
#include "r1/spec/progress.hpp"
#include "r1/spec/snapshot.hpp"
#include "r1/spec/stages.hpp"
#include "r1/spec/status.hpp"

namespace r1 {

// A backend's kernels for the reference's stages, each optional, each giving the same bits: the
// spectral solver's panel kernels (R1-SOL-002) and operator rows (R1-SPEC-073), and the full
// focus's exact products (R1-FOC-092).
struct StageKernels {
  Q32KernelFactory panel;
  Q32RowsFactory rows;
  ExactProductFactory focus;
};

// The cpu-reference's epoch stages. `parallel` turns on the TBB loops of the spectral, focus,
// encoding and hierarchy stages whatever options.parallel says (the same bits, R1-SPEC-071,
// R1-FOC-090, R1-ENC-020, R1-HIER-070); `fp64` runs those two stages in IEEE doubles whatever
// options.domain says (R1-EPO-003); `kernels` are a backend's (the same bits).
class ReferenceStages final : public EpochStages {
 public:
  explicit ReferenceStages(bool parallel = false, bool fp64 = false, StageKernels kernels = {})
      : parallel_(parallel), fp64_(fp64), kernels_(std::move(kernels)) {}

  Result<Spectrum<Q32>> spectral(const Graph& graph, const EpochOptions& options, const ProgressFn& progress) override;
  Result<Focus<Q32>> focus(const Graph& graph, const EpochOptions& options, double lambda2,
                           const ProgressFn& progress) override;
  Result<Focus<Q32>> focus_update(const Graph& graph, const EpochOptions& options, double lambda2,
                                  Focus<Q32> start, std::span<const std::uint32_t> region,
                                  const ProgressFn& progress) override;
  Result<Frame> frame(const Snapshot& snapshot, const Spectrum<Q32>& conventioned, const Anchor* anchor,
                      const std::string& anchor_name) override;
  Result<Encoding> encoding(const Snapshot& snapshot, const Graph& graph, const Focus<Q32>& focus,
                            const Spectrum<Q32>& conventioned, const EncodingOptions& options,
                            const ProgressFn& progress) override;
  Result<Hierarchy> hierarchy(const std::vector<std::array<Q32, 3>>& pos, std::span<const Q32> phi,
                              std::span<const Color> color, std::span<const ParticleId> ids,
                              const HierarchyOptions& options, const ProgressFn& progress) override;

 private:
  EpochOptions adjusted(const EpochOptions& options) const;
  bool parallel_, fp64_;
  StageKernels kernels_;
};

// Runs every stage of `stages` on a snapshot and its layout graph, in the one order of R1-EPO-001;
// `timings` are filled per stage. The digest, the layout edges and the sign convention are the
// pipeline's own (R1-BKD-011). A stage that returns data for the wrong number of particles is an
// internal error.
Result<Epoch> run_epoch(const Snapshot& snapshot, const Graph& graph, const EpochOptions& options, EpochStages& stages,
                        const ProgressFn& progress = {});
// The same with the reference's stages.
Result<Epoch> run_epoch(const Snapshot& snapshot, const Graph& graph, const EpochOptions& options,
                        const ProgressFn& progress = {});

// The parts every pipeline fills the same way (R1-BKD-011): the digest (its time is the first
// timing), counts and the parameters. `previous`: the record chunks of the epoch before in a
// chain, whose leaves the digest reuses (R1-EPO-017).
Epoch epoch_header(const Snapshot& snapshot, const Graph& graph, const EpochOptions& options,
                   const RecordChunks* previous = nullptr);
// The per-particle tables every pipeline fills the same way: ids, display titles and the rows'
// out-link digests (what the next epoch of a chain compares). run_epoch fills them after the
// spectral stage, whose basis is the epoch's peak of memory (R1-EPO-006).
void epoch_particles(Epoch& e, const Snapshot& snapshot, const Graph& graph);
// Encoding and hierarchy for an epoch whose focus, sign-conventioned spectrum and frame are set,
// then the check that every stage returned data of the epoch's shape.
Status epoch_tail(Epoch& e, const Snapshot& snapshot, const Graph& graph, const EpochOptions& options,
                  EpochStages& stages, const ProgressFn& progress);

// The reference stages alone, as ReferenceStages calls them (options.domain and options.parallel
// decide).
Result<Spectrum<Q32>> reference_spectral_stage(const Graph& graph, const EpochOptions& options, const ProgressFn& progress,
                                               const StageKernels& kernels = {});
Result<Focus<Q32>> reference_focus_stage(const Graph& graph, const EpochOptions& options, double lambda2,
                                         const ProgressFn& progress, const StageKernels& kernels = {});

}  // namespace r1
