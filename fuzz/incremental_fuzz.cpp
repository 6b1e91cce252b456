// Fuzzing graph edits for incremental drift (spec/incremental.md R1-INC, spec/drift.md; R1-TEST-010):
// the bytes make a small graph and up to four edit batches; each batch's epoch from the one
// before must be deterministic, conserve focus exactly (and, updated locally, keep it outside N_h),
// give the same bytes on every conformant backend, and, when incremental, stay within its
// certificate of the full solve.
#include <cmath>
#include <set>
#include <string>

#include "fuzz_graph.hpp"
#include "fuzz_target.hpp"
#include "r1/backends/registry.hpp"
#include "r1/reference/edits.hpp"
#include "r1/reference/epoch.hpp"
#include "r1/reference/epoch_io.hpp"
#include "r1/reference/frame.hpp"
#include "r1/reference/graph_build.hpp"
#include "r1/reference/incremental.hpp"
#include "r1/solvers/spectral.hpp"

namespace {

constexpr std::size_t kMaxBatches = 4;
constexpr std::size_t kMaxEdits = 12;

// The edits of one batch from 4-byte groups: byte 0 picks the kind (low 7 bits % 3: add, remove, reweight)
// and, with its top bit, ends the batch after this edit; bytes 1-2 pick two particles (add) or a
// link (their 16 bits, remove and reweight); byte 3's low 6 bits the weight (1..64) / 16.
std::vector<r1::Edit> batch_of(const r1::Snapshot& s, const std::uint8_t*& p, const std::uint8_t* end) {
  std::vector<r1::Edit> out;
  std::set<std::pair<std::uint32_t, std::uint32_t>> used;
  const std::size_t n = s.particles.size(), m = s.links.size();
  while (p + 4 <= end && out.size() < kMaxEdits) {
    const std::uint8_t* b = p;
    p += 4;
    r1::Edit e;
    e.amount = static_cast<r1::u128>(1 + (b[3] & 0x3F)) << r1::fuzz::kWeightShift;
    std::uint32_t from = 0, to = 0;
    const int kind = (b[0] & 0x7F) % 3;
    if (kind == 0) {
      e.op = r1::EditOp::kAdd;
      from = b[1] % n;
      to = b[2] % n;
    } else {
      e.op = kind == 1 ? r1::EditOp::kRemove : r1::EditOp::kReweight;
      const r1::Link& l = s.links[((std::size_t{b[1]} << 8) | b[2]) % m];
      from = l.from;
      to = l.to;
    }
    if (from != to && used.insert({from, to}).second) {
      e.from = s.names[from];
      e.to = s.names[to];
      out.push_back(std::move(e));
    }
    if (b[0] & 0x80) break;
  }
  return out;
}

[[noreturn]] void finding(const std::string& what) { r1::fuzz::fail(__FILE__, __LINE__, what.c_str()); }

}  // namespace

R1_FUZZ_TARGET(incremental) {
  if (size < 8) return 0;
  // Byte 0: links of the graph (1..96); the graph's bytes follow, then the edits.
  const std::size_t links = 1 + data[0] % r1::fuzz::kMaxLinks;
  const std::size_t graph_size = std::min(size - 1, 1 + 3 * links);
  auto made = r1::fuzz::snapshot_of(data + 1, graph_size);
  if (!made.is_ok()) return 0;
  r1::Snapshot s = std::move(*made);
  auto graph = r1::build_graph(s);
  if (!graph.is_ok()) return 0;
  r1::ReferenceStages reference;
  const r1::EpochOptions options;
  auto first = r1::run_epoch(s, *graph, options, reference);
  if (!first.is_ok()) return 0;  // e.g. an isolated particle: the epoch's own input error
  r1::Epoch prev = std::move(*first);
  const r1::Anchor anchor = r1::make_anchor(s, prev.frame);
  // eps_X = R_scene / 2 accepts updates whose certificate is loose, so the check that the
  // certificate is a true bound runs on many inputs (small graphs rarely certify at 10^-3).
  r1::UpdateOptions uo;
  uo.hops = 2;
  uo.eps = 0.5;
  r1::UpdateOptions forced = uo;
  forced.force_full = true;
  const std::uint8_t* p = data + 1 + graph_size;
  const std::uint8_t* end = data + size;
  for (std::size_t k = 0; k < kMaxBatches && p + 4 <= end; ++k) {
    const std::vector<r1::Edit> batch = batch_of(s, p, end);
    auto next = r1::apply_edits(s, batch, "fuzz batch");
    if (!next.is_ok()) return 0;  // the edits leave no links
    auto g = r1::build_graph(*next);
    if (!g.is_ok()) return 0;
    auto inc = r1::run_epoch_from(prev, anchor, "fuzz epoch", *next, *g, options, uo, reference);
    if (!inc.is_ok()) {
      if (inc.status().kind() != r1::ErrorKind::kInput) finding("incremental epoch: " + inc.status().message());
      return 0;  // an input error: an anchor particle left (another chain), an isolated particle
    }
    // Deterministic: the same inputs, the same bytes.
    auto again = r1::run_epoch_from(prev, anchor, "fuzz epoch", *next, *g, options, uo, reference);
    if (!again.is_ok() || *r1::epoch_files(*again) != *r1::epoch_files(*inc)) finding("the same update gave other bytes");
    // Focus conserved exactly, every particle positive (A5).
    std::int64_t total = 0;
    for (const r1::Q32 phi : inc->focus.phi) {
      if (phi.raw <= 0) finding("a focus entry is not positive");
      total += phi.raw;
    }
    if (total != r1::Q32::kOneRaw) finding("focus does not sum to exactly 1");
    // A local focus update freezes every particle outside N_h (R1-INC-050).
    if (inc->update->focus_local) {
      auto batch_now = r1::edit_batch(prev, *next, *g, "fuzz epoch");
      if (!batch_now.is_ok()) finding("the edit batch failed where the update succeeded");
      std::vector<char> inside(g->n, 0);
      for (const std::uint32_t i : r1::neighbourhood(*g, batch_now->touched, inc->update->hops)) inside[i] = 1;
      for (std::uint32_t i = 0; i < g->n; ++i)
        if (!inside[i] && batch_now->prev_of[i] >= 0 &&
            inc->focus.phi[i] != prev.focus.phi[static_cast<std::size_t>(batch_now->prev_of[i])])
          finding("a frozen particle's focus moved");
    }
    // The carried image and sums are a pass over the whole graph, bit for bit (R1-INC-038).
    if (inc->update->incremental && inc->spectrum.sums_shift >= 0) {
      auto op = r1::spectral_operator_q32(*g, options.spectral);
      if (!op.is_ok()) finding("the operator failed where the update succeeded");
      std::vector<r1::i128> image;
      r1::spectral::ResidualSums sums;
      r1::spectral::image_and_sums(*op, inc->spectrum.u, op->e / 2, image, sums);
      if (inc->spectrum.sums_shift != op->e / 2 || image != inc->spectrum.image || sums != inc->spectrum.sums)
        finding("the carried image or sums differ from a pass over the whole graph");
    }
    // Every conformant backend gives the same epoch.
    for (const auto& info : r1::backends::registered_backends()) {
      if (!info.expected_conformant) continue;
      const auto backend = info.make();
      auto other = r1::run_epoch_from(prev, anchor, "fuzz epoch", *next, *g, options, uo, *backend);
      if (!other.is_ok() || *r1::epoch_files(*other) != *r1::epoch_files(*inc))
        finding("backend '" + info.name + "' differs from the reference on an incremental epoch");
    }
    // Within the certificate of the full solve (R1-INC-032, R1-DRF-021).
    if (inc->update->incremental) {
      auto full = r1::run_epoch_from(prev, anchor, "fuzz epoch", *next, *g, options, forced, reference);
      if (!full.is_ok()) finding("the full solve failed where the update succeeded: " + full.status().message());
      const double own = r1::full_solve_bound(*full, r1::frame_scale(inc->frame));
      const double drift = r1::vector_drift(*inc, *full);
      if (std::isfinite(own) && !(drift <= inc->update->certificate + own + 1e-9))
        finding("true drift " + std::to_string(drift) + " exceeds the certificate " + std::to_string(inc->update->certificate) +
                " plus the full solve's bound " + std::to_string(own));
    }
    s = std::move(*next);
    prev = std::move(*inc);
  }
  return 0;
}
