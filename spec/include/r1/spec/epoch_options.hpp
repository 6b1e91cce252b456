// What an epoch is asked to compute (R1-EPO-001, R1-ENC-014, R1-ENC-040, R1-HIER-030, R1-BKD-014):
// the options every epoch stage receives, as values. Stage-boundary types: backends and
// accelerated paths include this, never reference/.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "r1/spec/anchor.hpp"
#include "r1/spec/epoch.hpp"
#include "r1/spec/overlay.hpp"
#include "r1/spec/status.hpp"

namespace r1 {

// A display sRGB colour, 8 bits per channel (a particle's or a cluster's).
using Color = std::array<std::uint8_t, 3>;

struct BetweennessOptions {
  // Exact when n (n + nnz) <= budget; otherwise k = max(min_pivots, budget / (n + nnz)) pivots
  // (R1-ENC-014).
  std::uint64_t budget = std::uint64_t{1} << 30;
  std::uint32_t min_pivots = 32;
  // When set, exactly this many pivots (0 = every particle as a source, the exact computation).
  std::optional<std::uint32_t> pivots;
};

struct EncodingOptions {
  std::string overlay = "none";   // none | crystal-v5 | custom
  // The tables for overlay = custom, already read (R1-BKD-014: values, not paths); shared so that
  // copying the options does not copy a large overlay.
  std::shared_ptr<const CustomOverlay> custom;
  std::string custom_name;        // names the custom overlay in messages (its file, as given)
  bool role_shapes = true;        // shapes from roles (R1-ENC-019)
  BetweennessOptions betweenness; // exact size limit and pivots (R1-ENC-014)
  // Betweenness to use instead of computing it (one value per particle, R1-INC-037): an
  // incremental epoch's, carried from the earlier epoch. Unset: computed by R1-ENC-012..015.
  std::shared_ptr<const std::vector<double>> carried_betweenness;
  bool parallel = false;          // TBB for betweenness and the per-particle loops: bit-identical results (R1-ENC-020)
  // How r_0 is chosen (R1-ENC-007..008): "spacing" (from the layout, the default) or "scene"
  // (r_0 = R_scene, as before). The epoch fills r0_squared_raw from the frame's positions before
  // the stage runs, unless it arrives set with "spacing" (an incremental epoch keeps the earlier
  // epoch's, R1-INC-035); the stage itself uses r0_squared_raw, else R_scene^2.
  std::string radius_scale = "spacing";
  std::optional<std::int64_t> r0_squared_raw;  // r_0^2 as a Q32 raw, > 0
};

struct HierarchyOptions {
  // The finest clustering radius r_0 as a Q32 raw (scene units, >= 0). Unset: chosen from the data
  // by the search of R1-HIER-030..033.
  std::optional<std::int64_t> radius0_raw;
  bool parallel = false;  // TBB for the leader queries, the tree, the sorts and the radius search: bit-identical results (R1-HIER-070)
};

struct EpochOptions {
  NumericDomain domain = NumericDomain::kQ32;
  TriKernelParams trikernel;
  SpectralParams spectral;
  // The anchor of an earlier epoch to align to, already read (R1-BKD-014); unset: genesis epoch.
  std::optional<Anchor> anchor;
  std::string anchor_name = "anchor";  // names the anchor in messages (its file, as given)
  EncodingOptions encoding;
  HierarchyOptions hierarchy;
  bool parallel = false;    // TBB in spectral, focus, encoding and hierarchy: bit-identical results (R1-SPEC-071, R1-FOC-090, R1-ENC-020, R1-HIER-070)
  // The snapshot's digest (R1-IN-040) when the caller formed it already, with the seconds it took:
  // the epoch takes it as is. Nothing after the digest and the layout graph reads the snapshot's
  // link records, so a caller that formed both may release them before the stages (R1-EPO-005).
  // The epoch then has no record chunks: the caller attaches its own (Epoch::record_chunks,
  // R1-EPO-017) when the stages are done, so that they are not held twice meanwhile.
  std::optional<hemera::Digest> snapshot_digest;
  double snapshot_digest_seconds = 0;
  // The caller's hooks around the spectral solve, the epoch's peak of memory (R1-EPO-006):
  // `spectral_operator_ready` runs once the spectral stage has formed its operator, after which
  // the stage reads of the layout graph only n, row_ptr, col, degree and component_size until it
  // returns; `spectral_done` runs when the stage has returned (also on an error), before any
  // other stage reads the graph, and an error it returns ends the epoch. `r1 epoch` parks the
  // graph's other arrays between the two.
  std::function<void()> spectral_operator_ready;
  std::function<Status()> spectral_done;
};

}  // namespace r1
