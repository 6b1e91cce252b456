// The epoch pipeline (R1-EPO-001..004): snapshot -> graph -> spectrum -> focus -> frame ->
// encoding -> hierarchy, in the canonical Q32 domain or fp64.
#pragma once

#include <string>

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

// Runs every stage on a snapshot and its layout graph; `timings` are filled per stage.
Result<Epoch> run_epoch(const Snapshot& snapshot, const Graph& graph, const EpochOptions& options,
                        const ProgressFn& progress = {});

}  // namespace r1
