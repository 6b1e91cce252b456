// r1 epoch SNAPSHOT [--backend NAME] [--content SIDE] -o DIR: the canonical epoch, through the chosen
// backend's stages, with its T0 content, and its summary (R1-EPO-001..013, R1-EPO-030..036, R1-BKD-016).
#include <chrono>
#include <cmath>
#include <filesystem>
#include <future>
#include <cstdio>
#include <optional>

#include "backend_option.hpp"
#include "commands.hpp"
#include "input_options.hpp"
#include "progress.hpp"
#include "timing.hpp"
#include "update_options.hpp"
#include "r1/reference/epoch.hpp"
#include "r1/reference/epoch_io.hpp"
#include "r1/reference/frame.hpp"
#include "r1/reference/graph_build.hpp"
#include "r1/reference/graph_park.hpp"
#include "r1/reference/incremental.hpp"
#include "r1/reference/input_file.hpp"
#include "render/content.hpp"
#include "render/neural_field.hpp"
#include "render/scene.hpp"

namespace r1::cli {

namespace {

struct EpochCliOptions {
  std::string snapshot, out;
  InputOptions input;
  BackendOption backend;
  std::string domain = "q32";
  // Tri-kernel parameters as decimal text, parsed exactly into Q32 (empty: default).
  std::string lambda_d, lambda_s, lambda_h, teleport, mu, tau, eps;
  std::optional<std::uint32_t> max_steps, chebyshev_degree;
  std::string rho = "auto";
  std::optional<double> tolerance;
  std::string anchor;
  std::string overlay = "none", overlay_file;
  std::string content;  // T0 content side file (R1-EPO-030)
  bool no_role_shapes = false;
  std::string radius_scale = "spacing";
  bool no_timings = false;
  bool field = true;  // train the neural field (R1-NRF-030); --no-field skips it
  std::uint32_t field_steps = render::NeuralConfig{}.steps;
  std::string field_block = "none";
  bool parallel = false;
  bool quiet = false;
  // Incremental epochs (spec/incremental.md): the earlier epoch and the update's settings.
  std::string from;
  UpdateCliOptions update;
  bool full = false;
};

Status parse_q32(const std::string& text, const char* option, Q32& out) {
  if (text.empty()) return Status::ok();
  const auto v = Q32::checked_from_decimal(text);
  if (!v) return Status::input(std::string(option) + " '" + text + "' is not a decimal number in the Q32 range");
  out = *v;
  return Status::ok();
}

Result<EpochOptions> epoch_options(const EpochCliOptions& c) {
  EpochOptions o;
  if (c.domain == "q32") {
    o.domain = NumericDomain::kQ32;
  } else if (c.domain == "fp64") {
    o.domain = NumericDomain::kFp64;
  } else {
    return Status::input("--domain '" + c.domain + "' is not q32 or fp64");
  }
  TriKernelParams& t = o.trikernel;
  R1_TRY(parse_q32(c.lambda_d, "--lambda-d", t.lambda_d));
  R1_TRY(parse_q32(c.lambda_s, "--lambda-s", t.lambda_s));
  R1_TRY(parse_q32(c.lambda_h, "--lambda-h", t.lambda_h));
  R1_TRY(parse_q32(c.teleport, "--teleport", t.teleport));
  R1_TRY(parse_q32(c.mu, "--mu", t.mu));
  R1_TRY(parse_q32(c.tau, "--tau", t.tau));
  R1_TRY(parse_q32(c.eps, "--eps", t.eps));
  if (c.max_steps) t.max_steps = *c.max_steps;
  if (c.chebyshev_degree) t.chebyshev_degree = *c.chebyshev_degree;
  if (c.rho != "auto") {
    char* end = nullptr;
    const double r = std::strtod(c.rho.c_str(), &end);
    if (c.rho.empty() || *end != '\0' || !std::isfinite(r) || r < 0)
      return Status::input("--rho '" + c.rho + "' is not 'auto' or a non-negative number");
    o.spectral.rho = r;
  }
  if (c.tolerance) o.spectral.tolerance = *c.tolerance;
  // The stages take values, not paths (R1-BKD-014): the anchor and the overlay are read here.
  R1_TRY(load_anchor(o, c.anchor));
  o.encoding.overlay = c.overlay;
  if (c.overlay == "custom") R1_TRY(load_custom_overlay(o.encoding, c.overlay_file));
  o.encoding.role_shapes = !c.no_role_shapes;
  o.encoding.radius_scale = c.radius_scale;
  o.parallel = c.parallel;
  return o;
}

void print_summary(const Epoch& e, const std::string& dir, double total_s) {
  const std::size_t n = e.ids.size();
  std::printf("epoch              %s (%s domain)\n", dir.c_str(), e.domain == NumericDomain::kQ32 ? "q32" : "fp64");
  std::printf("particles          %zu, %llu links, %llu component%s\n", n, static_cast<unsigned long long>(e.links),
              static_cast<unsigned long long>(e.components), e.components == 1 ? "" : "s");
  std::printf("eigenvalues        ");
  double worst = 0;
  for (std::size_t k = 0; k < 6; ++k) {
    std::printf("%.6g ", e.spectrum.eigenvalues[k]);
    worst = std::max(worst, e.spectrum.residuals[k]);
  }
  std::printf("(rho %g, max residual %.2e)\n", e.spectrum.rho, worst);
  std::printf("scale              %.6g (R_scene / max |X|)%s\n", e.frame.scale,
              e.frame.alignment.genesis ? ", genesis frame" : ", aligned to the anchor");
  if (!e.frame.alignment.genesis)
    std::printf("alignment          %u anchor particles matched, rms %.3g, scale %.6g%s\n", e.frame.alignment.matched,
                e.frame.alignment.rms, e.frame.alignment.scale, e.frame.alignment.reflected ? ", reflection absorbed (SC-R)" : "");
  std::printf("focus              %u tri-kernel steps, kappa %.4f, syntropy %.4f nats\n", e.focus.steps, e.focus.kappa,
              e.focus.syntropy);
  for (std::size_t k = 0; k < e.focus.cyberank.size() && k < 5; ++k) {
    const std::uint32_t i = e.focus.cyberank[k];
    const std::string name = e.titles[i].empty() ? hemera::to_hex(e.ids[i]).substr(0, 16) : e.titles[i];
    std::printf("  %zu. %-40.40s %.6f\n", k + 1, name.c_str(), e.focus.phi[i].to_double());
  }
  std::printf("radius             r_0 %.6g scene units (%s)\n",
              std::sqrt(Q32::from_raw(e.encoding.r0_squared_raw).to_double()),
              e.encoding.radius_scale == "spacing" ? "from the layout's spacing" : "R_scene");
  std::printf("clusters           level 0: %zu, level 1: %zu, level 2: %zu, level 3: %zu\n", e.hierarchy.levels[0].size(),
              e.hierarchy.levels[1].size(), e.hierarchy.levels[2].size(), e.hierarchy.levels[3].size());
  if (e.update) {
    const UpdateInfo& u = *e.update;
    // The record chunks the digest hashed; the rest were PREV's (R1-EPO-017).
    if (!e.record_chunks.leaves.empty())
      std::printf("digest             %zu of %zu record chunks hashed, the others unchanged since the earlier epoch\n",
                  e.record_chunks.hashed, e.record_chunks.leaves.size());
    std::printf("update             %s: %llu touched (%llu new, %llu left), N_h %llu particles (%u hops), ||dL|| %.3g\n",
                u.incremental ? "incremental" : "full solve", static_cast<unsigned long long>(u.touched),
                static_cast<unsigned long long>(u.added), static_cast<unsigned long long>(u.dropped),
                static_cast<unsigned long long>(u.region), u.hops, u.delta_norm);
    if (u.incremental) {
      std::printf("certificate        %.3g scene units %s eps_X %.3g%s; %u epochs since the full solve; focus %s\n",
                  u.certificate, u.certified ? "<=" : "above", u.eps_x, u.certified ? "" : " (uncertified, --keep-local)",
                  u.epochs_since_full, u.focus_local ? "updated on N_h" : "in full");
    } else {
      std::printf("full because       %s\n", u.reason.c_str());
    }
  }
  std::printf("time per stage    ");
  for (const auto& t : e.timings) std::printf(" %s %.2f s,", t.stage.c_str(), t.seconds);
  std::printf(" total %.2f s\n", total_s);
}

Status run_epoch_cli(const EpochCliOptions& c) {
  if (c.out.empty()) return Status::input("epoch: say where to write the epoch (-o DIR)");
  if (c.from.empty() && (c.update.any() || c.full))
    return Status::input("epoch: --hops, --eps-x, --full-every, --full-norm, --keep-local and --full need --from PREV_EPOCH_DIR");
  if (!c.from.empty() && !c.anchor.empty())
    return Status::input("epoch: --from aligns to the earlier epoch's anchor; leave out --anchor");
  R1_ASSIGN(UpdateOptions uo, c.update.make("epoch"));
  R1_ASSIGN(EpochOptions o, epoch_options(c));
  R1_ASSIGN(const ChosenBackend chosen, c.backend.make());
  ProgressLine progress;
  const auto t0 = std::chrono::steady_clock::now();
  // The earlier epoch (R1-INC-001) is read and checked while the snapshot is read: the snapshot's
  // parse runs on one thread, and PREV's check fills the other cores (through its chunk table at
  // SHA-256 speed, R1-EPO-018). Its files' tree leaves and chunk SHA-256s let the new epoch's
  // digests hash only what changed (R1-EPO-016). Errors come in the order of
  // the reads one after the other (the snapshot's first); an early return waits for the task.
  EpochLeaves prev_leaves;
  std::future<Result<Epoch>> prev_read;
  if (!c.from.empty())
    prev_read = std::async(std::launch::async,
                           [&c, &prev_leaves] { return read_epoch(c.from, &prev_leaves, DigestCheck::kChunkTable); });
  R1_ASSIGN(const ReadOptions ro, c.input.read_options(progress.sink()));
  R1_ASSIGN(Snapshot s, read_snapshot(c.snapshot, ro));
  // T0 content (R1-EPO-030..033): read before the stages, so a bad side file costs no solve.
  std::optional<render::ContentSet> content;
  if (!c.content.empty()) {
    R1_ASSIGN(content, render::read_content_side_file(c.content, s.particles));
  }
  // The snapshot's digest and its record chunks come before the layout graph, with PREV's chunk
  // leaves where the chunks are PREV's (R1-EPO-017): the graph's build then lets the link records
  // go as soon as it holds them (nothing after it reads them), so records and graph are never
  // whole at once, the load's peak (R1-EPO-005). PREV's chunks are read by themselves for it
  // while PREV's read goes on beside the build, and compared with what that read checked
  // (R1-EPO-019).
  RecordChunks chunks;
  RecordChunks prev_chunks = c.from.empty() ? RecordChunks{} : peek_record_chunks(c.from);
  {
    const auto td = std::chrono::steady_clock::now();
    o.snapshot_digest = snapshot_digest(s, chunks, c.from.empty() ? nullptr : &prev_chunks);
    o.snapshot_digest_seconds = seconds_since(td);
  }
  Graph g;
  R1_ASSIGN(g, build_graph_releasing_links(s, progress.sink()));
  const double read_s = seconds_since(t0) - o.snapshot_digest_seconds;  // the digest has a lap of its own
  Epoch e;
  double previous_s = 0;
  // What a local update of the neural field needs of the earlier epoch (R1-NRF-050): its field,
  // and each particle's id and far-field inputs (position, phi, colour).
  std::optional<render::NeuralField> prev_field;
  std::vector<hemera::Digest> prev_ids;
  render::Scene prev_scene;
  if (c.from.empty()) {
    // R1-EPO-006: while the spectral stage solves, the graph's arrays it does not read wait
    // compressed. A failure to park leaves them in place (the epoch only needs more memory).
    ParkedGraph parked;
    o.spectral_operator_ready = [&] {
      if (auto p = ParkedGraph::park(g, true)) parked = std::move(*p);
    };
    o.spectral_done = [&] { return parked.restore(g, true); };
    R1_ASSIGN(e, backends::run_epoch(*chosen.backend, s, g, o, progress.sink()));
  } else {
    // The earlier epoch and its anchor: the chain's frame (R1-INC-001, R1-INC-034). `previous`
    // is the wait for PREV beyond the snapshot's read.
    const auto t1 = std::chrono::steady_clock::now();
    R1_ASSIGN(Epoch prev, prev_read.get());
    R1_ASSIGN(const Anchor anchor, read_anchor((std::filesystem::path(c.from) / "anchor.bin").string()));
    previous_s = seconds_since(t1);
    // The digest's reused leaves must be the ones PREV's read checked.
    if (!prev_chunks.leaves.empty() &&
        (prev_chunks.sha != prev.record_chunks.sha || prev_chunks.leaves != prev.record_chunks.leaves))
      return Status::input((std::filesystem::path(c.from) / "records.chunks").string() +
                           ": changed while the epoch was read; run the command again");
    prev_chunks = RecordChunks{};  // PREV's read holds the same rows (20 MB at 10^7 links)
    const std::string prev_nrf = (std::filesystem::path(c.from) / "field.nrf").string();
    if (c.field && std::filesystem::exists(prev_nrf)) {
      R1_ASSIGN(const auto in, InputFile::open(prev_nrf));
      R1_ASSIGN(prev_field, render::decode_neural_field(in->text(), prev_nrf, prev.snapshot_digest));
      prev_ids = prev.ids;
      prev_scene = render::make_scene(prev);
      prev_scene.hierarchy = nullptr;  // the epoch moves on below; only the per-particle arrays are kept
    }
    uo.force_full = c.full;
    R1_ASSIGN(e, run_epoch_from(std::move(prev), anchor, c.from, s, g, o, uo, *chosen.backend, progress.sink()));
  }
  // Nothing after the stages reads the layout graph or the snapshot: they go before the field's
  // training and the writing, whose serialised files would otherwise be the epoch's peak
  // (R1-EPO-005).
  g = Graph{};
  s = Snapshot{};
  e.record_chunks = std::move(chunks);
  e.timings.insert(e.timings.begin(), {"read", read_s});
  // Reading and checking the earlier epoch (every file against its digest) is part of the update.
  if (!c.from.empty()) e.timings.insert(e.timings.begin() + 1, {"previous", previous_s});
  EpochWriteOptions wo;
  std::string field_note;
  if (c.field) {
    // The T-infinity neural field (R1-NRF-030): trained on the epoch's analytic far field, written
    // with the epoch and listed in its manifest.
    const auto t3 = std::chrono::steady_clock::now();
    const render::Scene scene = render::make_scene(e);
    render::NeuralConfig nc;
    nc.steps = c.field_steps;
    nc.block = c.field_block == "clifford" ? nc.hidden / 2 : 0;
    const std::uint64_t seed = render::neural_seed(e.snapshot_digest);
    std::optional<render::NeuralField> f;
    if (prev_field && e.update && e.update->incremental) {
      const render::SceneChange change = render::scene_change(prev_ids, prev_scene, e.ids, scene);
      if (change.comparable && change.changed == 0) {
        f = *prev_field;  // nothing the far field sees moved
        field_note = "field.nrf carried: no particle's position, phi or colour changed";
      } else if (change.comparable) {
        // A quarter of the samples and steps (R1-NRF-050).
        const std::uint32_t local_steps = std::max(1u, c.field_steps / 4);
        R1_ASSIGN(f, render::update_neural_field(scene, *prev_field, change.lo, change.hi, seed, std::max(1u, nc.samples / 4),
                                                 local_steps, progress.sink()));
        field_note = "field.nrf updated locally: " + std::to_string(change.changed) + " particles changed, " +
                     std::to_string(local_steps) + " steps in their box (update " +
                     std::to_string(f->local_updates) + " since the field was trained whole)";
      } else {
        field_note = "field.nrf trained whole: " + change.reason;
      }
    } else if (!c.from.empty()) {
      field_note = prev_field ? "field.nrf trained whole: the positions were solved in full"
                              : "field.nrf trained whole: the earlier epoch has no field.nrf";
    }
    if (!f) {
      R1_ASSIGN(f, render::train_neural_field(scene, nc, seed, progress.sink()));
    }
    wo.extra.emplace_back("field.nrf", render::encode_neural_field(*f, e.snapshot_digest));
    e.timings.push_back({"field", seconds_since(t3)});
  }
  if (content)
    for (auto& f : render::content_epoch_files(*content)) wo.extra.push_back(std::move(f));
  const auto t2 = std::chrono::steady_clock::now();
  wo.timings = !c.no_timings;
  if (!c.from.empty()) wo.previous = &prev_leaves;
  R1_TRY(write_epoch(e, c.out, wo));
  e.timings.push_back({"write", seconds_since(t2)});
  progress.finish();
  if (!c.quiet) print_summary(e, c.out, seconds_since(t0));
  if (!c.quiet && !field_note.empty()) std::printf("field              %s\n", field_note.c_str());
  if (!c.quiet && content) std::printf("content            %s\n", render::content_summary(*content).c_str());
  return Status::ok();
}

}  // namespace

void add_epoch(CLI::App& app, Runner& selected) {
  auto c = std::make_shared<EpochCliOptions>();
  auto* cmd = app.add_subcommand("epoch", "compute an epoch: focus, spectral layout, frame, encoding, hierarchy");
  cmd->add_option("SNAPSHOT", c->snapshot, "snapshot: .graph, TSV/CSV edge list or Matrix Market")->required();
  cmd->add_option("-o,--out", c->out, "output directory (written atomically)");
  c->input.add_to(*cmd);
  c->backend.add_to(*cmd);
  cmd->add_option("--domain", c->domain, "numeric domain: q32 (canonical, default) or fp64");
  cmd->add_option("--lambda-d", c->lambda_d, "diffusion weight (0.5)");
  cmd->add_option("--lambda-s", c->lambda_s, "springs weight (0.3)");
  cmd->add_option("--lambda-h", c->lambda_h, "heat weight (0.2)");
  cmd->add_option("--teleport", c->teleport, "diffusion teleport (0.15)");
  cmd->add_option("--mu", c->mu, "springs screening (1)");
  cmd->add_option("--tau", c->tau, "heat time (1)");
  cmd->add_option("--eps", c->eps, "target error that fixes the step count T(eps) (0.000001)");
  cmd->add_option("--max-steps", c->max_steps, "cap on T(eps) (500)");
  cmd->add_option("--chebyshev-degree", c->chebyshev_degree, "heat kernel polynomial degree (8)");
  cmd->add_option("--rho", c->rho, "Laplacian regularisation: auto (0 when connected) or a value");
  cmd->add_option("--tolerance", c->tolerance, "eigen-residual target (1e-9)");
  cmd->add_option("--anchor", c->anchor, "anchor file of an earlier epoch: align to it (Procrustes)");
  cmd->add_option("--overlay", c->overlay, "none (default), crystal-v5 or custom");
  cmd->add_option("--overlay-file", c->overlay_file, "TOML lookup tables for --overlay custom");
  cmd->add_option("--content", c->content, "T0 content side file: lines PARTICLE<TAB>PATH, paths under its folder");
  cmd->add_option("--radius-scale", c->radius_scale,
                  "r_0 from the layout's spacing (spacing, default) or r_0 = R_scene (scene)")
      ->check(CLI::IsMember({"spacing", "scene"}));
  cmd->add_flag("--no-role-shapes", c->no_role_shapes, "all spheres instead of hub/bridge/leaf shapes");
  cmd->add_flag("--field,!--no-field", c->field,
                "train the T-infinity neural field (field.nrf, for r1 render --field neural; the default), or not");
  cmd->add_option("--field-steps", c->field_steps, "the neural field's Adam steps (120)")->check(CLI::Range(1u, 1000000u));
  cmd->add_option("--field-block", c->field_block, "the neural field's network: none (default) or clifford (R-1.0 7.1's render block)")
      ->check(CLI::IsMember({"none", "clifford"}));
  cmd->add_flag("--no-timings", c->no_timings, "leave timings out of the manifest: every byte reproducible");
  cmd->add_flag("--parallel", c->parallel, "reference stages on every core: spectral, focus, encoding, hierarchy (same bits)");
  cmd->add_flag("-q,--quiet", c->quiet, "no summary");
  cmd->add_option("--from", c->from, "earlier epoch of this chain: update it incrementally where the certificate allows");
  c->update.add_to(*cmd, "with --from: ");
  cmd->add_flag("--full", c->full, "with --from: solve in full (the update's record still written)");
  cmd->callback([c, &selected] { selected = [c] { return run_epoch_cli(*c); }; });
}

}  // namespace r1::cli
