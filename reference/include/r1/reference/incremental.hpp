// Incremental epochs (R-1.0 3.3; spec/incremental.md R1-INC-001..050): the edit batch between an
// earlier epoch and the next snapshot, the h-hop neighbourhood N_h, the local update of u_2..u_6
// with its a-posteriori certificate, and the decision to solve in full instead.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "r1/spec/epoch.hpp"
#include "r1/spec/epoch_options.hpp"
#include "r1/spec/graph.hpp"
#include "r1/spec/progress.hpp"
#include "r1/spec/snapshot.hpp"
#include "r1/spec/stages.hpp"
#include "r1/spec/status.hpp"

namespace r1 {

struct UpdateOptions {
  double eps = 1e-3;                    // eps_X / R_scene (R1-INC-020)
  std::optional<std::uint32_t> hops;    // h; unset: the rule of R1-INC-020
  std::uint32_t full_every = 64;        // a full solve at least every this many epochs (R1-INC-030)
  double full_norm = 0.05;              // ... or when the summed ||Delta L~|| bound exceeds this
  std::uint32_t krylov = 12;            // local basis vectors per eigenvector (R1-INC-031)
  bool force_full = false;              // always solve in full (r1 drift's oracle side)
  bool keep_local = false;              // keep the local update when the certificate fails (R1-INC-036)
};

// The edit batch at the level of the layout graph (R1-INC-010..013).
struct EditBatch {
  std::vector<std::int64_t> prev_of;       // per next particle: its index in the earlier epoch, or -1 (new)
  std::vector<std::uint32_t> touched;      // next particles whose A_sym / A2 row changed, ascending
  std::uint64_t added = 0, dropped = 0;
  std::vector<std::uint32_t> left;         // earlier particles not in next, ascending (dropped of them)
  double delta_norm = 0;                   // bound on ||L~_next - L~_prev||_2 (R1-INC-012)
  bool same_scale = true;                  // the Q32 weight normalisation is unchanged
};

// Compares the earlier epoch's layout graph (its edges.bin) with the next snapshot's. Input error
// when the earlier epoch is not of this chain (an anchor particle of it is missing, R1-INC-002).
Result<EditBatch> edit_batch(const Epoch& prev, const Snapshot& next, const Graph& graph, const std::string& prev_name);

// Per particle, the digest of its directed A0 row (R1-INC-011, outrows.u64 of R1-EPO-011): the sum
// modulo 2^64 of splitmix64(t ^ splitmix64(w)) over its out-links, t the first 8 bytes of the
// target's id (little-endian) and w the Q32 raw: independent of particle order, so rows of two
// snapshots compare by id.
std::vector<std::uint64_t> out_row_digests(const Graph& graph, std::span<const ParticleId> ids);

// h of R1-INC-020 for eps and the springs screening mu.
std::uint32_t hops_for(double eps, double mu);

// Particles within h hops of `seeds` in A_sym, ascending (R1-INC-021).
std::vector<std::uint32_t> neighbourhood(const Graph& graph, const std::vector<std::uint32_t>& seeds, std::uint32_t h);

// The certified quantity of R1-INC-032 measured (R1-DRF-020): s (sum_(c=2..4) ||u_c - sigma_c u*_c||^2)^(1/2)
// between an epoch's stored vectors and another's (sigma_c the sign that matches them), s the
// first epoch's frame scale (genesis times alignment).
double vector_drift(const Epoch& a, const Epoch& b);
// A full solve's own bound on the same quantity for its stored vectors: the certificate's
// Davis-Kahan argument on its own eigenvalues and residuals, times s; infinity when its wanted
// eigenvalues are not separated.
double full_solve_bound(const Epoch& full, double s);
// The frame scale s of R1-INC-032.
double frame_scale(const Frame& f);

// The epoch of `next` from `prev` (R1-INC-001..050): incremental when the batch allows it and the
// certificate holds, else every stage in full with the earlier epoch's anchor. `prev_anchor` is
// the earlier epoch's anchor file (as read); `options` must be the earlier epoch's parameters for
// an incremental update (else: a full solve, the reason recorded). `prev` is taken by value: a
// caller done with it moves it in, and when the batch adds and drops no particle its per-particle
// arrays are taken over instead of gathered (no copy of O(|P|)).
Result<Epoch> run_epoch_from(Epoch prev, const Anchor& prev_anchor, const std::string& prev_name,
                             const Snapshot& next, const Graph& graph, const EpochOptions& options,
                             const UpdateOptions& update, EpochStages& stages, const ProgressFn& progress = {});

}  // namespace r1
