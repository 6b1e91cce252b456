// The epoch pipeline (R1-EPO-001..004): snapshot -> graph -> spectrum -> focus -> frame ->
// encoding -> hierarchy, in the canonical Q32 domain or fp64.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "r1/reference/encoding.hpp"
#include "r1/reference/hierarchy.hpp"
#include "r1/spec/epoch.hpp"
#include "r1/spec/graph.hpp"
#include "r1/spec/progress.hpp"
#include "r1/spec/snapshot.hpp"
#include "r1/spec/status.hpp"

namespace r1 {

struct EpochOptions {
  NumericDomain domain = NumericDomain::kQ32;
  TriKernelParams trikernel;
  SpectralParams spectral;
  std::string anchor_path;  // empty: genesis epoch
  EncodingOptions encoding;
  HierarchyOptions hierarchy;
  bool parallel = false;    // TBB row loops in spectral and focus: bit-identical results (R1-SPEC-071, R1-FOC-090)
};

struct Anchor;

// The five computing stages of an epoch, as replaceable functions: a backend (backends/) runs the
// same pipeline with its own stage implementations through them (R1-BKD-010). An empty function
// is the reference stage. Each receives exactly what the reference stage receives.
struct EpochStages {
  // The spectrum in the domain of `options.domain`, as Q32 (fp64 rounded entry by entry), before
  // the sign convention.
  std::function<Result<Spectrum<Q32>>(const Graph&, const EpochOptions&, const ProgressFn&)> spectral;
  // phi* in Q32 (an fp64 focus projected onto the Q32 simplex, R1-EPO-004).
  std::function<Result<Focus<Q32>>(const Graph&, const EpochOptions&, double lambda2, const ProgressFn&)> focus;
  std::function<Result<Frame>(const Snapshot&, const Spectrum<Q32>& conventioned, const Anchor*,
                              const std::string& anchor_name)> frame;
  std::function<Result<Encoding>(const Snapshot&, const Graph&, const Focus<Q32>&, const Spectrum<Q32>& conventioned,
                                 const EncodingOptions&, const ProgressFn&)> encoding;
  std::function<Result<Hierarchy>(const std::vector<std::array<Q32, 3>>& pos, std::span<const Q32> phi,
                                  std::span<const Color> color, std::span<const ParticleId> ids,
                                  const HierarchyOptions&, const ProgressFn&)> hierarchy;
};

// Runs every stage on a snapshot and its layout graph; `timings` are filled per stage. `stages`
// replaces stages (nullptr or an empty member: the reference's).
Result<Epoch> run_epoch(const Snapshot& snapshot, const Graph& graph, const EpochOptions& options,
                        const ProgressFn& progress = {}, const EpochStages* stages = nullptr);

// The reference stages alone, as run_epoch calls them.
Result<Spectrum<Q32>> reference_spectral_stage(const Graph& graph, const EpochOptions& options, const ProgressFn& progress);
Result<Focus<Q32>> reference_focus_stage(const Graph& graph, const EpochOptions& options, double lambda2,
                                         const ProgressFn& progress);

}  // namespace r1
