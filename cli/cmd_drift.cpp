// r1 drift SNAPSHOT --epochs K --batch B (spec/drift.md R1-DRF-001..030): K random edit batches,
// each epoch computed incrementally (r1 epoch --from) and in full, their drift against the
// certificate, a table, drift.tsv, drift.json and drift.png; exit 4 when a certified update's
// true drift exceeds its certificate.
#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>

#include "backend_option.hpp"
#include "r1/backends/backend.hpp"
#include "chart_canvas.hpp"
#include "commands.hpp"
#include "input_options.hpp"
#include "progress.hpp"
#include "r1/fixedpoint/counter_rng.hpp"
#include "r1/reference/atomic_dir.hpp"
#include "r1/reference/edits.hpp"
#include "r1/reference/epoch.hpp"
#include "r1/reference/frame.hpp"
#include "r1/reference/graph_build.hpp"
#include "r1/reference/incremental.hpp"
#include "r1/reference/snapshot_io.hpp"
#include "render/image.hpp"
#include "update_options.hpp"

namespace r1::cli {

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr std::string_view kDriftFormat = "r1-drift";
// "r1-drift" as the counter-based generator's seed mixer (R1-DRF-010).
constexpr std::uint64_t kDriftKey = 0x72312d6472696674ull;

struct DriftOptions {
  std::string snapshot, out;
  InputOptions input;
  BackendOption backend;
  std::uint32_t epochs = 8, batch = 10;
  std::uint64_t seed = 1;
  std::string kind = "mixed";
  double weight = 1, scale = 0.5;
  UpdateCliOptions update;
};

struct Row {
  std::uint32_t epoch = 0;
  UpdateInfo update;
  double true_drift = kInf;   // s ||u_inc - u_full|| over u_2..u_4 (the certified quantity), R_scene units... scene units
  double full_error = kInf;   // the full solve's own bound, scene units
  double max_pos = 0, mean_pos = 0;  // |X_inc - X_full|, R_scene units
  double focus_l1 = 0;
  std::array<std::uint64_t, kLevels> clusters{};
  double t_inc = 0, t_full = 0;
  std::string check;          // ok | VIOLATION | unchecked | -
};

double seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The particle reference an edit file uses for particle i (R1-EDT-010).
std::string ref(const Snapshot& s, std::uint32_t i) { return s.names.empty() ? hemera::to_hex(s.particles[i]) : s.names[i]; }

// Batch k (R1-DRF-010): edit j draws from counter item (k, j); dimensions pick the kind, the
// particles or link, and the weight. A pair is edited at most once per batch.
std::vector<Edit> draw_batch(const Snapshot& s, const DriftOptions& o, std::uint32_t k) {
  std::vector<Edit> out;
  std::set<std::pair<std::uint32_t, std::uint32_t>> used;
  const std::uint64_t seed = o.seed ^ kDriftKey;
  const std::uint64_t n = s.particles.size(), m = s.links.size();
  for (std::uint32_t j = 0; j < o.batch; ++j) {
    const std::uint64_t item = (std::uint64_t{k} << 32) | j;
    for (std::uint64_t attempt = 0; attempt < 64; ++attempt) {
      const std::uint64_t d = attempt * 8;
      std::string kind = o.kind;
      if (kind == "mixed") kind = std::array<const char*, 3>{"add", "remove", "reweight"}[rng::bits(seed, item, d) % 3];
      Edit e;
      if (kind == "add") {
        const auto a = static_cast<std::uint32_t>(rng::bits(seed, item, d + 1) % n);
        const auto b = static_cast<std::uint32_t>(rng::bits(seed, item, d + 2) % n);
        if (a == b || used.count({a, b})) continue;
        used.insert({a, b});
        e.op = EditOp::kAdd;
        e.from = ref(s, a);
        e.to = ref(s, b);
        e.amount = static_cast<u128>(std::llround(o.weight * 0x1p32));
      } else {
        const Link& l = s.links[rng::bits(seed, item, d + 1) % m];
        if (l.from == l.to || used.count({l.from, l.to})) continue;
        used.insert({l.from, l.to});
        e.from = ref(s, l.from);
        e.to = ref(s, l.to);
        if (kind == "remove") {
          e.op = EditOp::kRemove;
        } else {
          // amount (1 - scale u), u uniform in [0, 1): never above the old weight.
          const double u = static_cast<double>(rng::bits(seed, item, d + 3) >> 11) * 0x1p-53;
          const double f = 1 - o.scale * u;
          e.op = EditOp::kReweight;
          e.amount = static_cast<u128>(static_cast<double>(l.amount) * f);
          if (e.amount == 0) e.amount = 1;
        }
      }
      out.push_back(std::move(e));
      break;
    }
  }
  return out;
}

Row compare(std::uint32_t k, const Epoch& inc, const Epoch& full, double t_inc, double t_full) {
  Row r;
  r.epoch = k;
  r.update = *inc.update;
  r.t_inc = t_inc;
  r.t_full = t_full;
  const std::size_t n = inc.ids.size();
  double sum = 0;
  for (std::size_t p = 0; p < n; ++p) {
    double d2 = 0;
    for (std::size_t c = 0; c < 3; ++c) {
      const double d = (inc.frame.position[p][c].to_double() - full.frame.position[p][c].to_double());
      d2 += d * d;
    }
    const double d = std::sqrt(d2) / static_cast<double>(kSceneRadius);
    r.max_pos = std::max(r.max_pos, d);
    sum += d;
  }
  r.mean_pos = n ? sum / static_cast<double>(n) : 0;
  std::int64_t l1 = 0;
  for (std::size_t p = 0; p < n; ++p) l1 += std::llabs(inc.focus.phi[p].raw - full.focus.phi[p].raw);
  r.focus_l1 = static_cast<double>(l1) * 0x1p-32;
  for (std::size_t l = 0; l < kLevels; ++l)
    for (std::size_t p = 0; p < n; ++p) r.clusters[l] += inc.hierarchy.cluster_of[l][p] != full.hierarchy.cluster_of[l][p];
  if (!r.update.incremental) {
    r.true_drift = 0;
    r.full_error = 0;
    r.check = "-";
    return r;
  }
  // The certified quantity against the full solve's stored vectors (R1-INC-032, R1-DRF-020).
  r.true_drift = vector_drift(inc, full);
  r.full_error = full_solve_bound(full, frame_scale(inc.frame));
  if (!r.update.certified) {
    r.check = "uncertified";  // kept by --keep-local: nothing to hold it to (R1-INC-036)
  } else if (!std::isfinite(r.full_error)) {
    r.check = "unchecked";
  } else {
    // The stored vectors' own rounding (half a raw per entry) is inside both bounds already.
    r.check = r.true_drift <= r.update.certificate + r.full_error + 1e-9 ? "ok" : "VIOLATION";
  }
  return r;
}

// x with `digits` significant digits ("-" when not finite).
std::string num(double x, int digits = 3) {
  if (!std::isfinite(x)) return "-";
  char b[40];
  std::snprintf(b, sizeof b, "%.*g", digits, x);
  return b;
}

std::string tsv(const std::vector<Row>& rows) {
  std::string o =
      "epoch\tmode\treason\ttouched\thops\tregion\tdelta_norm\tcertificate\ttrue_drift\tfull_error\tmax_drift\tmean_drift\t"
      "focus_l1\tclusters0\tclusters1\tclusters2\tclusters3\tt_incremental\tt_full\tcheck\n";
  for (const Row& r : rows) {
    o += std::to_string(r.epoch) + "\t" + (r.update.incremental ? "incremental" : "full") + "\t" + r.update.reason + "\t" +
         std::to_string(r.update.touched) + "\t" + std::to_string(r.update.hops) + "\t" + std::to_string(r.update.region) +
         "\t" + num(r.update.delta_norm, 6) + "\t" + num(r.update.certificate, 6) + "\t" +
         num(r.true_drift, 6) + "\t" + num(r.full_error, 6) + "\t" + num(r.max_pos, 6) + "\t" +
         num(r.mean_pos, 6) + "\t" + num(r.focus_l1, 6);
    for (auto c : r.clusters) o += "\t" + std::to_string(c);
    o += "\t" + num(r.t_inc, 5) + "\t" + num(r.t_full, 5) + "\t" + r.check + "\n";
  }
  return o;
}

json to_json(const DriftOptions& o, const Snapshot& s, const std::vector<Row>& rows, std::size_t violations) {
  auto fin = [](double x) { return std::isfinite(x) ? json(x) : json(nullptr); };
  json ep = json::array();
  for (const Row& r : rows)
    ep.push_back({{"epoch", r.epoch},
                  {"mode", r.update.incremental ? "incremental" : "full"},
                  {"reason", r.update.reason},
                  {"touched", r.update.touched},
                  {"added", r.update.added},
                  {"dropped", r.update.dropped},
                  {"hops", r.update.hops},
                  {"region", r.update.region},
                  {"delta_norm", r.update.delta_norm},
                  {"certificate", fin(r.update.certificate)},
                  {"true_drift", fin(r.true_drift)},
                  {"full_error", fin(r.full_error)},
                  {"max_drift", r.max_pos},
                  {"mean_drift", r.mean_pos},
                  {"focus_l1", r.focus_l1},
                  {"clusters_differing", r.clusters},
                  {"seconds_incremental", r.t_inc},
                  {"seconds_full", r.t_full},
                  {"check", r.check}});
  return {{"format", kDriftFormat},
          {"snapshot", {{"source", o.snapshot}, {"particles", s.particles.size()}, {"links", s.links.size()}}},
          {"settings",
           {{"epochs", o.epochs}, {"batch", o.batch}, {"seed", o.seed}, {"kind", o.kind}, {"weight", o.weight},
            {"scale", o.scale}}},
          {"epochs", ep},
          {"violations", violations}};
}

// drift.png (R1-DRF-030): per epoch, on a log axis in scene units, the certificate, the true
// drift of the certified quantity, the largest position drift, and eps_X; full solves marked.
Status write_chart(const std::vector<Row>& rows, double eps_x, const fs::path& png, std::string* warning) {
  using namespace chart;
  constexpr int kW = 1000, kH = 560;
  Canvas cv(kW, kH, srgb(255, 255, 255));
  const Panel p{90, 90, kW - 40, kH - 60};
  std::vector<double> all{eps_x};
  for (const Row& r : rows)
    for (double v : {r.update.certificate, r.true_drift, r.max_pos * static_cast<double>(kSceneRadius)}) all.push_back(v);
  const auto [lo, hi] = decades(all, 0);
  cv.text(p.x0, 30, "drift against the full solve (scene units, log) per epoch", kTitle, kInk);
  const char* names[] = {"certificate", "true drift (certified quantity)", "max position drift", "eps_X"};
  double lx = p.x0;
  for (int k = 0; k < 4; ++k) {
    cv.rect(lx, 48, lx + 14, 62, series_colour(static_cast<std::size_t>(k)));
    cv.text(lx + 20, 60, names[k], kLabel, kInk);
    lx += 40 + 7.0 * static_cast<double>(std::string(names[k]).size());
  }
  cv.text(lx, 60, "grey band: full solve", kLabel, kInk);
  y_decades(cv, p, lo, hi, "");
  const std::size_t n = std::max<std::size_t>(rows.size(), 1);
  auto x_of = [&](std::size_t i) { return p.x0 + (static_cast<double>(i) + 0.5) * (p.x1 - p.x0) / static_cast<double>(n); };
  auto y_of = [&, lo = lo, hi = hi](double v) {
    return std::clamp(p.y1 - (std::log10(v) - lo) * (p.y1 - p.y0) / (hi - lo), p.y0, p.y1);
  };
  const double bw = (p.x1 - p.x0) / static_cast<double>(n);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (!rows[i].update.incremental) cv.rect(x_of(i) - bw / 2, p.y0, x_of(i) + bw / 2, p.y1, srgb(218, 218, 218));
    const std::size_t step = std::max<std::size_t>(1, rows.size() / 12);
    if (i % step == 0) cv.text(x_of(i), p.y1 + 20, std::to_string(rows[i].epoch), kLabel, kInk, 1);
  }
  cv.text((p.x0 + p.x1) / 2, p.y1 + 44, "epoch", kLabel, kInk, 1);
  cv.line(p.x0, y_of(eps_x), p.x1, y_of(eps_x), 1.5, series_colour(3));
  for (int series = 0; series < 3; ++series) {
    double px = -1, py = -1;
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const Row& r = rows[i];
      const double v = series == 0 ? r.update.certificate
                                   : series == 1 ? r.true_drift : r.max_pos * static_cast<double>(kSceneRadius);
      if (!(v > 0) || !std::isfinite(v) || (series < 2 && !r.update.incremental)) {
        px = -1;
        continue;
      }
      const double x = x_of(i), y = y_of(v);
      if (px >= 0) cv.line(px, py, x, y, 2, series_colour(static_cast<std::size_t>(series)));
      cv.dot(x, y, 3.5, series_colour(static_cast<std::size_t>(series)));
      px = x, py = y;
    }
  }
  cv.line(p.x0, p.y1, p.x1, p.y1, 1, kAxis);
  cv.line(p.x0, p.y0, p.x0, p.y1, 1, kAxis);
  if (warning && !cv.font_error().empty()) *warning = "drift.png has no labels: " + cv.font_error();
  return render::write_image(cv.image(), png, srgb(255, 255, 255));
}

bool is_drift_dir(const fs::path& dir) { return manifest_format_is(dir, kDriftFormat, "drift.json"); }

Status run_drift(const DriftOptions& o) {
  if (o.epochs == 0 || o.epochs > 100000) return Status::input("drift: --epochs must lie in 1..100000");
  if (o.batch == 0 || o.batch > 1000000) return Status::input("drift: --batch must lie in 1..1000000");
  if (o.kind != "add" && o.kind != "remove" && o.kind != "reweight" && o.kind != "mixed")
    return Status::input("drift: --kind '" + o.kind + "' is not add, remove, reweight or mixed");
  if (!(o.weight >= 0x1p-32 && o.weight < 0x1p30)) return Status::input("drift: --weight must lie in [2^-32, 2^30)");
  if (!(o.scale > 0 && o.scale < 1)) return Status::input("drift: --scale must lie in (0, 1)");
  R1_ASSIGN(const UpdateOptions uo, o.update.make("drift"));
  R1_ASSIGN(const ChosenBackend chosen, o.backend.make());
  ProgressLine progress;
  R1_ASSIGN(const ReadOptions ro, o.input.read_options(progress.sink()));
  R1_ASSIGN(Snapshot s, read_snapshot(o.snapshot, ro));
  UpdateOptions forced = uo;
  forced.force_full = true;
  const EpochOptions eo;

  // Epoch 0: the full solve that starts the chain; its anchor is the chain's frame.
  R1_ASSIGN(Graph g, build_graph(s));
  R1_ASSIGN(Epoch prev, backends::run_epoch(*chosen.backend, s, g, eo, {}));
  const Anchor anchor = make_anchor(s, prev.frame);
  std::vector<Row> rows;
  std::size_t violations = 0;
  const ProgressFn report = progress.sink();
  for (std::uint32_t k = 1; k <= o.epochs; ++k) {
    if (report) report("drift: epochs (incremental and full)", k - 1, o.epochs);
    const std::vector<Edit> batch = draw_batch(s, o, k);
    auto next = apply_edits(s, batch, "drift batch " + std::to_string(k));
    if (!next.is_ok()) return next.status();
    s = std::move(*next);
    R1_ASSIGN(g, build_graph(s));
    const std::string prev_name = "drift epoch " + std::to_string(k - 1);
    auto t0 = std::chrono::steady_clock::now();
    R1_ASSIGN(Epoch inc, run_epoch_from(prev, anchor, prev_name, s, g, eo, uo, *chosen.backend, {}));
    const double t_inc = seconds(t0);
    Row r;
    if (inc.update->incremental) {
      t0 = std::chrono::steady_clock::now();
      R1_ASSIGN(const Epoch full, run_epoch_from(prev, anchor, prev_name, s, g, eo, forced, *chosen.backend, {}));
      r = compare(k, inc, full, t_inc, seconds(t0));
    } else {
      r = compare(k, inc, inc, t_inc, t_inc);  // the fall-back is the full solve
    }
    violations += r.check == "VIOLATION";
    rows.push_back(std::move(r));
    prev = std::move(inc);
  }
  progress.finish();

  std::printf("drift      %s: %zu particles, %zu links after %u batches of %u (%s edits, seed %llu)\n", o.snapshot.c_str(),
              s.particles.size(), s.links.size(), o.epochs, o.batch, o.kind.c_str(),
              static_cast<unsigned long long>(o.seed));
  std::printf("%5s %-11s %7s %4s %8s %9s %9s %9s %9s %9s %9s %7s %7s  %s\n", "epoch", "mode", "touched", "h", "N_h", "||dL||",
              "cert", "true", "max", "mean", "focusL1", "t_inc", "t_full", "check / reason");
  for (const Row& r : rows) {
    std::printf("%5u %-11s %7llu %4u %8llu %9s %9s %9s %9s %9s %9s %7.3f %7.3f  %s\n", r.epoch,
                r.update.incremental ? "incremental" : "full", static_cast<unsigned long long>(r.update.touched), r.update.hops,
                static_cast<unsigned long long>(r.update.region), num(r.update.delta_norm).c_str(),
                num(r.update.certificate).c_str(), num(r.true_drift).c_str(), num(r.max_pos).c_str(),
                num(r.mean_pos).c_str(), num(r.focus_l1).c_str(), r.t_inc, r.t_full,
                r.update.incremental ? r.check.c_str() : r.update.reason.c_str());
  }
  std::size_t incremental = 0;
  for (const Row& r : rows) incremental += r.update.incremental;
  std::printf("summary    %zu of %u epochs incremental, %zu violations (true drift above certificate + the full solve's own bound)\n",
              incremental, o.epochs, violations);
  std::printf("units      cert, true: scene units (eps_X = %g); max, mean: position drift / R_scene; focusL1: sum |dphi|\n",
              uo.eps * static_cast<double>(kSceneRadius));
  if (!o.out.empty()) {
    AtomicDirectory out(o.out, is_drift_dir);
    R1_TRY(out.open());
    R1_TRY(out.write("drift.tsv", tsv(rows)));
    R1_TRY(out.write("drift.json", to_json(o, s, rows, violations).dump(2) + "\n"));
    std::string warning;
    R1_TRY(write_chart(rows, uo.eps * static_cast<double>(kSceneRadius), out.temp_path() / "drift.png",
                       &warning));
    R1_TRY(out.commit());
    if (!warning.empty()) std::fprintf(stderr, "r1: warning: %s\n", warning.c_str());
    std::printf("wrote      %s (drift.tsv, drift.json, drift.png)\n", o.out.c_str());
  }
  if (violations > 0) verdict_exit() = 4;
  return Status::ok();
}

}  // namespace

void add_drift(CLI::App& app, Runner& selected) {
  auto o = std::make_shared<DriftOptions>();
  auto* cmd = app.add_subcommand("drift", "fuzz random edit batches: incremental against full epochs, drift against the certificate");
  cmd->add_option("SNAPSHOT", o->snapshot, "the starting snapshot")->required();
  cmd->add_option("--epochs", o->epochs, "edit batches, one epoch each (8)");
  cmd->add_option("--batch", o->batch, "edits per batch (10)");
  cmd->add_option("--seed", o->seed, "counter-based draws (1)");
  cmd->add_option("--kind", o->kind, "add, remove, reweight or mixed (default)");
  cmd->add_option("--weight", o->weight, "weight of added links (1)");
  cmd->add_option("--scale", o->scale, "reweight: new weight = old (1 - scale u), u uniform in [0, 1) (0.5)");
  o->update.add_to(*cmd);
  cmd->add_option("-o,--out", o->out, "directory for drift.tsv, drift.json and drift.png (written atomically)");
  o->input.add_to(*cmd);
  o->backend.add_to(*cmd);
  cmd->callback([o, &selected] { selected = [o] { return run_drift(*o); }; });
}

}  // namespace r1::cli
