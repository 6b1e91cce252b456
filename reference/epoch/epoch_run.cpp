// The epoch pipeline and the reference's stages: stages in order, domains, timings (R1-EPO-001..004,
// R1-BKD-011).
#include "r1/reference/epoch.hpp"

#include <chrono>
#include <cmath>
#include <string_view>

#include "r1/solvers/focus.hpp"
#include "r1/reference/frame.hpp"
#include "r1/reference/incremental.hpp"
#include "r1/solvers/spectral.hpp"

namespace r1 {

namespace {

class Stopwatch {
 public:
  explicit Stopwatch(std::vector<StageTiming>& out) : out_(out), t_(std::chrono::steady_clock::now()) {}
  void lap(std::string_view stage) {
    const auto now = std::chrono::steady_clock::now();
    out_.push_back({std::string(stage), std::chrono::duration<double>(now - t_).count()});
    t_ = now;
  }

 private:
  std::vector<StageTiming>& out_;
  std::chrono::steady_clock::time_point t_;
};

// fp64 vectors enter the Q32 stages rounded entry by entry, to nearest, ties to even (R1-EPO-003).
Result<Spectrum<Q32>> to_q32(const Spectrum<double>& s) {
  Spectrum<Q32> q;
  q.n = s.n;
  q.rho = s.rho;
  q.eigenvalues = s.eigenvalues;
  q.residuals = s.residuals;
  q.found = s.found;
  q.restarts = s.restarts;
  q.matvecs = s.matvecs;
  q.passes = s.passes;
  for (std::size_t k = 0; k < 5; ++k) {
    q.u[k].reserve(s.u[k].size());
    for (double x : s.u[k]) {
      const auto v = Q32::checked_from_double(x);
      if (!v) return Status::internal("fp64 eigenvector entry is not finite or out of the Q32 range");
      q.u[k].push_back(*v);
    }
  }
  return q;
}

}  // namespace

Result<Spectrum<Q32>> reference_spectral_stage(const Graph& graph, const EpochOptions& o, const ProgressFn& progress,
                                               const StageKernels& kernels) {
  SpectralOptions so;
  so.parallel = o.parallel;
  so.q32_kernels = kernels.panel;
  so.q32_rows = kernels.rows;
  so.operator_ready = o.spectral_operator_ready;
  if (o.domain == NumericDomain::kQ32) return spectral_embedding_q32(graph, o.spectral, progress, so);
  R1_ASSIGN(const Spectrum<double> s, spectral_embedding_f64(graph, o.spectral, progress, so));
  return to_q32(s);
}

Result<Focus<Q32>> reference_focus_stage(const Graph& graph, const EpochOptions& o, double lambda2, const ProgressFn& progress,
                                         const StageKernels& kernels) {
  FocusOptions fo;
  fo.parallel = o.parallel;
  fo.products = kernels.focus;
  if (o.domain == NumericDomain::kQ32) return compute_focus_q32(graph, o.trikernel, lambda2, progress, fo);
  R1_ASSIGN(const Focus<double> f, compute_focus_f64(graph, o.trikernel, lambda2, progress, fo));
  Focus<Q32> q;
  q.steps = f.steps;
  q.kappa = f.kappa;
  q.lambda_max = f.lambda_max;
  q.syntropy = f.syntropy;
  q.cyberank = f.cyberank;
  R1_ASSIGN(q.phi, simplex_from_f64(f.phi));  // R1-EPO-004
  return q;
}

EpochOptions ReferenceStages::adjusted(const EpochOptions& o) const {
  EpochOptions mine = o;
  mine.parallel = o.parallel || parallel_;
  if (fp64_) mine.domain = NumericDomain::kFp64;
  return mine;
}

Result<Spectrum<Q32>> ReferenceStages::spectral(const Graph& g, const EpochOptions& o, const ProgressFn& p) {
  if (!parallel_ && !fp64_) return reference_spectral_stage(g, o, p, kernels_);
  return reference_spectral_stage(g, adjusted(o), p, kernels_);
}

Result<Focus<Q32>> ReferenceStages::focus(const Graph& g, const EpochOptions& o, double lambda2, const ProgressFn& p) {
  if (!parallel_ && !fp64_) return reference_focus_stage(g, o, lambda2, p, kernels_);
  return reference_focus_stage(g, adjusted(o), lambda2, p, kernels_);
}

Result<Focus<Q32>> ReferenceStages::focus_update(const Graph& g, const EpochOptions& o, double lambda2,
                                                 Focus<Q32> start, std::span<const std::uint32_t> region,
                                                 const ProgressFn& p) {
  if (fp64_ || o.domain != NumericDomain::kQ32) return Status::input("focus update: the fp64 domain has no local update");
  FocusOptions fo;
  fo.parallel = o.parallel || parallel_;  // R1-FOC-090: the same bits
  return update_focus_q32(g, o.trikernel, lambda2, std::move(start), region, p, fo);
}

Result<Frame> ReferenceStages::frame(const Snapshot& s, const Spectrum<Q32>& c, const Anchor* a, const std::string& name) {
  return compute_frame(s, c, a, name);
}

Result<Encoding> ReferenceStages::encoding(const Snapshot& s, const Graph& g, const Focus<Q32>& f, const Spectrum<Q32>& c,
                                           const EncodingOptions& o, const ProgressFn& p) {
  if (!parallel_ || o.parallel) return encode(s, g, f, c, o, nullptr, p);
  EncodingOptions mine = o;
  mine.parallel = true;  // R1-ENC-020: the same bytes
  return encode(s, g, f, c, mine, nullptr, p);
}

Result<Hierarchy> ReferenceStages::hierarchy(const std::vector<std::array<Q32, 3>>& pos, std::span<const Q32> phi,
                                             std::span<const Color> color, std::span<const ParticleId> ids,
                                             const HierarchyOptions& o, const ProgressFn& p) {
  if (!parallel_ || o.parallel) return build_hierarchy(pos, phi, color, ids, o, p);
  HierarchyOptions mine = o;
  mine.parallel = true;  // R1-HIER-070: the same bytes
  return build_hierarchy(pos, phi, color, ids, mine, p);
}

Result<Epoch> run_epoch(const Snapshot& snapshot, const Graph& graph, const EpochOptions& o, const ProgressFn& progress) {
  ReferenceStages reference;
  return run_epoch(snapshot, graph, o, reference, progress);
}

Epoch epoch_header(const Snapshot& snapshot, const Graph& graph, const EpochOptions& o, const RecordChunks* previous) {
  Epoch e;
  Stopwatch clock(e.timings);
  e.domain = o.domain;
  e.source = snapshot.source;
  if (o.snapshot_digest) {  // formed by the caller: its time stands for the lap
    e.snapshot_digest = *o.snapshot_digest;
    e.timings.push_back({"digest", o.snapshot_digest_seconds});
  } else {
    // Hemera over every record, or over the chunks that differ from PREV's (R1-EPO-017): its own lap.
    e.snapshot_digest = snapshot_digest(snapshot, e.record_chunks, previous);
    clock.lap("digest");
  }
  e.links = graph.links;
  e.components = graph.component_size.size();
  e.trikernel = o.trikernel;
  e.spectral_params = o.spectral;
  return e;
}

void epoch_particles(Epoch& e, const Snapshot& snapshot, const Graph& graph) {
  e.ids = snapshot.particles;
  e.titles.resize(snapshot.particles.size());
  for (std::size_t i = 0; i < e.titles.size(); ++i) {
    // A display title: the title, else the name of a text input (R1-EPO-011 titles.tsv).
    if (i < snapshot.titles.size() && !snapshot.titles[i].empty()) {
      e.titles[i] = snapshot.titles[i];
    } else if (i < snapshot.names.size()) {
      e.titles[i] = snapshot.names[i];
    }
  }
  e.out_rows = out_row_digests(graph, snapshot.particles);  // what the next epoch of the chain compares
}

Status epoch_tail(Epoch& e, const Snapshot& snapshot, const Graph& graph, const EpochOptions& o, EpochStages& st,
                  const ProgressFn& progress) {
  Stopwatch clock(e.timings);
  // EpochOptions::parallel reaches the encoding and hierarchy stages through their own options
  // (R1-ENC-020, R1-HIER-070): how they run, never what they compute.
  EncodingOptions encoding_options = o.encoding;
  encoding_options.parallel = o.encoding.parallel || o.parallel;
  // r_0 from the positions the frame stage just made (R1-ENC-007), the same on every backend,
  // unless the caller kept an earlier epoch's (R1-INC-035).
  if (encoding_options.radius_scale == "spacing") {
    if (!encoding_options.r0_squared_raw)
      encoding_options.r0_squared_raw =
          radius_scale_from_layout(e.frame.position, e.focus.phi, encoding_options.parallel).r0_squared_raw;
  } else if (encoding_options.radius_scale == "scene") {
    encoding_options.r0_squared_raw.reset();
  } else {
    return Status::input("unknown radius scale '" + encoding_options.radius_scale.substr(0, 80) + "' (spacing, scene)");
  }
  R1_ASSIGN(e.encoding, st.encoding(snapshot, graph, e.focus, e.spectrum, encoding_options, progress));
  clock.lap(stage_name(Stage::kEncoding));

  HierarchyOptions hierarchy_options = o.hierarchy;
  hierarchy_options.parallel = o.hierarchy.parallel || o.parallel;
  R1_ASSIGN(e.hierarchy,
            st.hierarchy(e.frame.position, e.focus.phi, e.encoding.color, e.ids, hierarchy_options, progress));
  clock.lap(stage_name(Stage::kHierarchy));
  // The pairs the renderer draws: the upper triangle of A_sym, rows ascending, columns ascending.
  // Formed last, after every stage, so that they are not alive beside the spectral stage's basis
  // or the encoding's and hierarchy's work (R1-EPO-005).
  e.edges.clear();
  e.edges.reserve((graph.col.size() + graph.n) / 2);
  for (std::uint32_t i = 0; i < graph.n; ++i)
    for (std::uint64_t k = graph.row_ptr[i]; k < graph.row_ptr[i + 1]; ++k)
      if (graph.col[k] > i) e.edges.push_back({i, graph.col[k], graph.w[k], graph.a2[k]});
  // A stage from elsewhere must hand back data of the epoch's shape (R1-BKD-011).
  const std::size_t n = e.ids.size();
  if (e.focus.phi.size() != n || e.frame.position.size() != n || e.encoding.color.size() != n ||
      e.hierarchy.cluster_of[0].size() != n)
    return Status::internal("an epoch stage returned data for the wrong number of particles");
  return Status::ok();
}

Result<Epoch> run_epoch(const Snapshot& snapshot, const Graph& graph, const EpochOptions& o, EpochStages& st,
                        const ProgressFn& progress) {
  Epoch e = epoch_header(snapshot, graph, o);
  Stopwatch clock(e.timings);
  {
    Result<Spectrum<Q32>> spectrum = st.spectral(graph, o, progress);
    if (o.spectral_done) R1_TRY(o.spectral_done());  // R1-EPO-006: the graph is whole again
    R1_ASSIGN(e.spectrum, std::move(spectrum));
  }
  clock.lap(stage_name(Stage::kSpectral));
  // The per-particle tables after the solve, the epoch's peak of memory (R1-EPO-006).
  epoch_particles(e, snapshot, graph);

  // R1-EPO-002: lambda_2 for T(eps); 0 for a disconnected graph.
  const double lambda2 = e.components == 1 && e.spectrum.found >= 1 ? e.spectrum.eigenvalues[1] : 0.0;
  R1_ASSIGN(e.focus, st.focus(graph, o, lambda2, progress));
  clock.lap(stage_name(Stage::kFocus));

  apply_sign_convention(e.spectrum);
  // The anchor arrives as a value (R1-BKD-014); the caller read the file.
  const Anchor* anchor = o.anchor ? &*o.anchor : nullptr;
  R1_ASSIGN(e.frame, st.frame(snapshot, e.spectrum, anchor, anchor ? o.anchor_name : std::string()));
  clock.lap(stage_name(Stage::kFrame));
  R1_TRY(epoch_tail(e, snapshot, graph, o, st, progress));
  return e;
}

}  // namespace r1
