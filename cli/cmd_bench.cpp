// r1 bench SNAPSHOT... [--backend NAME]... [--gen KIND:SIZE,...] [-o DIR]: the reference and other
// backends side by side on the same inputs, each run in its own child process; agreement with
// the reference, per-stage times, speedups, peak memory, scaling with |P| (spec/bench.md
// R1-BEN-001..050).
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <thread>

#include "bench_chart.hpp"
#include "bench_child.hpp"
#include "commands.hpp"
#include "image_size.hpp"
#include "r1/backends/registry.hpp"
#include "r1/conformance/compare.hpp"
#include "r1/reference/atomic_dir.hpp"
#include "r1/reference/epoch_io.hpp"
#include "r1/reference/generate.hpp"
#include "r1/reference/snapshot_io.hpp"
#include "render/image_diff.hpp"
#include "render/renderer.hpp"

namespace r1::cli {

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

inline constexpr const char* kBenchFormat = "r1-bench";
// The epoch stages of the table and chart (R1-BEN-030); "epoch" is the sum of every timed member
// of the manifest's timings_s (read and digest included), "render" the frame stage.
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
const std::vector<std::string> kStages = {"spectral", "focus", "frame", "encoding", "hierarchy", "epoch", "render"};

struct BenchOptions {
  std::vector<std::string> snapshots, backends, gens;
  std::string out = "bench-out", size = "480x270";
};

struct Input {
  std::string name, path, gen;  // gen: the --gen item ("ba:1000"), empty for a file
  std::optional<GenParams> params;
  std::uint64_t particles = 0, links = 0;
};

struct BackendEntry {
  std::string name, summary, domain;
  bool deterministic = false;
  bool bytes = false;  // compared byte for byte (deterministic FixedQ32), else by positions
};

struct Run {
  std::size_t input = 0, backend = 0;
  ChildRun epoch, frame;
  std::map<std::string, double> times;  // every timings_s member, "epoch" (their sum), "render"
  std::string error;                    // a child that failed: what it said
  std::string png;                      // the frame, relative to DIR
  // Agreement with the reference (R1-BEN-010..013); not for the reference itself.
  bool epoch_agrees = false, frame_agrees = false;
  std::vector<std::string> differing;  // bytes: the files that differ
  double deviation = kNaN;             // positions: max deviation / R_scene
  render::DiffStats frame_diff;
  bool agrees() const { return error.empty() && epoch_agrees && frame_agrees; }
};

// ---- options ------------------------------------------------------------------------------

// One --gen item: KIND (the kind's defaults), KIND:N for kinds that take --n, KIND:WxH or
// KIND:AxBxC for grid and torus (R1-BEN-003).
Result<Input> parse_gen(const std::string& item) {
  const std::string where = "bench: --gen '" + item + "': ";
  const auto colon = item.find(':');
  const std::string kind_name = item.substr(0, colon);
  const auto kind = gen_kind_from_name(kind_name);
  if (!kind.is_ok()) return Status::input(where + kind.status().message());
  const GenKindInfo& info = gen_kind_info(*kind);
  Input in;
  in.gen = item;
  in.name = kind_name;
  GenParams p;
  p.kind = *kind;
  if (colon != std::string::npos) {
    const std::string size = item.substr(colon + 1);
    if (info.options & kGenOptN) {
      std::int64_t n = 0;
      const auto r = std::from_chars(size.data(), size.data() + size.size(), n);
      if (size.empty() || r.ec != std::errc() || r.ptr != size.data() + size.size() || n < 1)
        return Status::input(where + "SIZE must be a particle count, e.g. " + kind_name + ":1000");
      p.n = n;
    } else if (info.options & kGenOptDims) {
      auto dims = parse_dims(size);
      if (!dims.is_ok()) return Status::input(where + dims.status().message());
      p.dims = *dims;
    } else {
      return Status::input(where + kind_name + " takes no size");
    }
    in.name += "-" + size;
  }
  // Validates every parameter without generating anything.
  const auto cmd = gen_command_line(p);
  if (!cmd.is_ok()) return Status::input(where + cmd.status().message());
  in.params = p;
  return in;
}

// The backends to run (R1-BEN-002): the reference first, then the named ones in order (each once),
// or every registered backend that is expected to conform.
Result<std::vector<BackendEntry>> choose_backends(const std::vector<std::string>& named) {
  std::vector<std::string> names{"reference"};
  if (named.empty()) {
    for (const auto& b : backends::registered_backends())
      if (b.expected_conformant && b.name != "reference") names.push_back(b.name);
  } else {
    for (const auto& n : named)
      if (std::find(names.begin(), names.end(), n) == names.end()) names.push_back(n);
  }
  std::vector<BackendEntry> out;
  for (const auto& n : names) {
    auto made = backends::make_backend(n);
    if (!made.is_ok()) return Status::input("bench: " + made.status().message());
    const backends::Backend& b = **made;
    BackendEntry e;
    e.name = n;
    e.summary = std::string(b.summary());
    e.domain = std::string(backends::domain_name(b.numeric_domain()));
    e.deterministic = b.deterministic_mode();
    e.bytes = b.deterministic_mode() && b.numeric_domain() == backends::Domain::kFixedQ32;
    out.push_back(std::move(e));
  }
  return out;
}

// ---- agreement ----------------------------------------------------------------------------

Result<std::string> read_whole(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  if (!f) return Status::internal("bench: cannot read " + p.string());
  return std::string(std::istreambuf_iterator<char>(f), {});
}

// The manifest as `r1 epoch --no-timings` writes it: timings_s is the one member that may differ
// between runs (R1-EPO-013); nlohmann keeps keys sorted, so dump(2) is the writer's layout.
Result<std::string> manifest_without_timings(const fs::path& p) {
  R1_ASSIGN(const std::string text, read_whole(p));
  try {
    json m = json::parse(text);
    m.erase("timings_s");
    return m.dump(2) + "\n";
  } catch (const json::exception& e) {
    return Status::internal("bench: " + p.string() + ": " + e.what());
  }
}

bool same_file_bytes(const fs::path& a, const fs::path& b) {
  std::error_code ea, eb;
  if (fs::file_size(a, ea) != fs::file_size(b, eb) || ea || eb) return false;
  std::ifstream fa(a, std::ios::binary), fb(b, std::ios::binary);
  std::vector<char> ba(1 << 20), bb(1 << 20);
  while (fa && fb) {
    fa.read(ba.data(), static_cast<std::streamsize>(ba.size()));
    fb.read(bb.data(), static_cast<std::streamsize>(bb.size()));
    if (fa.gcount() != fb.gcount() || !std::equal(ba.begin(), ba.begin() + fa.gcount(), bb.begin())) return false;
  }
  return fa.eof() && fb.eof();
}

// R1-BEN-011: every file of the two epoch directories, by name; the files that differ.
Result<std::vector<std::string>> differing_files(const fs::path& got, const fs::path& want) {
  std::vector<std::string> names, out;
  for (const fs::path& d : {got, want})
    for (const auto& f : fs::directory_iterator(d)) names.push_back(f.path().filename().string());
  std::sort(names.begin(), names.end());
  names.erase(std::unique(names.begin(), names.end()), names.end());
  for (const auto& n : names) {
    const fs::path a = got / n, b = want / n;
    bool same = fs::is_regular_file(a) && fs::is_regular_file(b);
    if (same && n == "manifest.json") {
      R1_ASSIGN(const std::string ma, manifest_without_timings(a));
      R1_ASSIGN(const std::string mb, manifest_without_timings(b));
      same = ma == mb;
    } else if (same) {
      same = same_file_bytes(a, b);
    }
    if (!same) out.push_back(n);
  }
  return out;
}

Status compare_epochs(Run& r, const BackendEntry& b, const fs::path& got, const fs::path& want) {
  if (b.bytes) {
    R1_ASSIGN(r.differing, differing_files(got, want));
    r.epoch_agrees = r.differing.empty();
    return Status::ok();
  }
  // R1-BEN-012: the conformance harness's position deviation and bound.
  auto a = read_epoch(got);
  if (!a.is_ok()) {  // the backend wrote an epoch r1 cannot read: a disagreement, not a bench error
    r.error += (r.error.empty() ? "" : "; ") + std::string("epoch unreadable: ") + a.status().message();
    return Status::ok();
  }
  R1_ASSIGN(const Epoch e, read_epoch(want));
  const auto d = conformance::position_deviation(a->frame.position, e.frame.position);
  if (!d.is_ok()) {
    r.error = "positions: " + d.status().message();
    return Status::ok();
  }
  r.deviation = d->max_over_r;
  r.epoch_agrees = r.deviation <= conformance::kPositionBound;
  return Status::ok();
}

Status compare_frames(Run& r, const fs::path& got, const fs::path& want) {
  int wa = 0, ha = 0, wb = 0, hb = 0;
  R1_ASSIGN(const auto a, render::read_srgb8(got, &wa, &ha));
  R1_ASSIGN(const auto b, render::read_srgb8(want, &wb, &hb));
  if (wa != wb || ha != hb) return Status::internal("bench: frames of different sizes: " + got.string());
  r.frame_diff = render::diff_srgb8(a, b, wa, ha, {}, nullptr);
  // R1-BEN-013: the P_RENDER_PIX rule of the conformance harness, per view.
  r.frame_agrees = r.frame_diff.mean_2000 <= conformance::kPixelBound;
  return Status::ok();
}

// ---- runs ---------------------------------------------------------------------------------

std::string strip_r1(std::string s) { return s.rfind("r1: ", 0) == 0 ? s.substr(4) : s; }

Result<std::map<std::string, double>> read_timings(const fs::path& epoch) {
  R1_ASSIGN(const std::string text, read_whole(epoch / "manifest.json"));
  std::map<std::string, double> t;
  try {
    const json m = json::parse(text);
    double sum = 0;
    for (const auto& [k, v] : m.at("timings_s").items()) {
      t[k] = v.get<double>();
      sum += t[k];
    }
    t["epoch"] = sum;
  } catch (const json::exception& e) {
    return Status::internal("bench: " + epoch.string() + "/manifest.json: no timings: " + e.what());
  }
  return t;
}

// One (input, backend) run: `r1 epoch` then `r1 bench-frame` on that epoch, each a child. The
// epoch without the neural field: its training is no backend's stage (spec/bench.md R1-BEN-020).
Status run_one(Run& r, const Input& in, const BackendEntry& b, const fs::path& work, const fs::path& dir,
               const std::string& size) {
  const std::string stem = in.name + "." + b.name;
  const fs::path epoch = work / (stem + ".epoch");
  R1_ASSIGN(r.epoch, run_self({"epoch", in.path, "--backend", b.name, "--no-field", "-q", "-o", epoch.string()},
                              work / (stem + ".epoch.out"), work / (stem + ".epoch.err")));
  if (!r.epoch.ok()) {
    r.error = "epoch " + strip_r1(r.epoch.failure());
    return Status::ok();
  }
  R1_ASSIGN(r.times, read_timings(epoch));
  r.png = "frames/" + stem + ".png";
  const fs::path stats = work / (stem + ".frame.json");
  R1_ASSIGN(r.frame,
            run_self({"bench-frame", epoch.string(), "--backend", b.name, "--size", size, "-o", (dir / r.png).string()},
                     stats, work / (stem + ".frame.err")));
  if (!r.frame.ok()) {
    r.error = "render " + strip_r1(r.frame.failure());
    return Status::ok();
  }
  R1_ASSIGN(const std::string text, read_whole(stats));
  try {
    r.times["render"] = json::parse(text).at("frame_s").get<double>();
  } catch (const json::exception& e) {
    return Status::internal("bench: " + stats.string() + ": " + e.what());
  }
  return Status::ok();
}

// ---- reporting ----------------------------------------------------------------------------

std::string secs(double v) {
  if (!std::isfinite(v)) return "-";
  char b[32];
  if (v >= 100)
    std::snprintf(b, sizeof b, "%.0f", v);
  else if (v >= 10)
    std::snprintf(b, sizeof b, "%.1f", v);
  else if (v >= 1)
    std::snprintf(b, sizeof b, "%.2f", v);
  else if (v >= 0.001)
    std::snprintf(b, sizeof b, "%.3f", v);
  else
    std::snprintf(b, sizeof b, "<0.001");
  return b;
}

// A time of the map, NaN when the run has none (it failed before).
double time_of(const Run& r, const std::string& stage) {
  const auto it = r.times.find(stage);
  return it == r.times.end() ? kNaN : it->second;
}

std::string fixed(double v, int decimals) {
  char b[64];
  std::snprintf(b, sizeof b, "%.*f", decimals, v);
  return b;
}

std::string sig2(double v) {
  char b[64];
  std::snprintf(b, sizeof b, "%.2g", v);
  return b;
}

std::string times_x(double s) { return std::isfinite(s) ? fixed(s, s >= 100 ? 0 : 2) + "x" : "-"; }

// reference time / backend time for one stage; NaN when either is missing or zero.
double speedup(const Run& ref, const Run& r, const std::string& stage) {
  const auto a = ref.times.find(stage), b = r.times.find(stage);
  if (a == ref.times.end() || b == r.times.end() || !(b->second > 0) || !(a->second > 0)) return kNaN;
  return a->second / b->second;
}

std::string epoch_check(const Run& r, const BackendEntry& b, bool is_ref) {
  if (is_ref) return "oracle";
  if (!r.epoch.ok()) return "FAILED";
  if (b.bytes) {
    if (r.differing.empty()) return "bytes identical";
    return "DIFFER: " + r.differing.front() +
           (r.differing.size() > 1 ? " +" + std::to_string(r.differing.size() - 1) : "");
  }
  if (!std::isfinite(r.deviation)) return "FAILED";
  return "pos " + sig2(r.deviation) + (r.epoch_agrees ? " <= 1e-3" : " > 1e-3 DIFFER");
}

std::string frame_check(const Run& r, bool is_ref) {
  if (is_ref) return "oracle";
  if (!r.frame.ok()) return "FAILED";
  return fixed(r.frame_diff.mean_2000, 3) + (r.frame_agrees ? "" : " > 2 DIFFER");
}

// Columns padded to their widest cell; the columns in `left` left-aligned (text), the rest
// right-aligned (numbers).
void print_table(const std::vector<std::vector<std::string>>& rows, const std::vector<std::size_t>& left) {
  std::vector<std::size_t> w;
  for (const auto& row : rows)
    for (std::size_t c = 0; c < row.size(); ++c) {
      if (w.size() <= c) w.push_back(0);
      w[c] = std::max(w[c], row[c].size());
    }
  for (const auto& row : rows) {
    std::string line;
    for (std::size_t c = 0; c < row.size(); ++c) {
      const bool l = std::find(left.begin(), left.end(), c) != left.end();
      const std::string pad(w[c] - row[c].size(), ' ');
      line += (c ? "  " : "") + (l ? row[c] + (c + 1 < row.size() ? pad : "") : pad + row[c]);
    }
    std::printf("%s\n", line.c_str());
  }
}

// Least-squares slope of log(epoch s) against log(|P|) over the inputs a backend ran; NaN with
// fewer than two distinct sizes.
double scaling_exponent(const std::vector<std::pair<double, double>>& pts) {
  double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (const auto& [p, t] : pts) {
    if (!(p > 0 && t > 0)) continue;
    const double x = std::log(p), y = std::log(t);
    n += 1, sx += x, sy += y, sxx += x * x, sxy += x * y;
  }
  const double den = n * sxx - sx * sx;
  if (n < 2 || !(den > 1e-12)) return kNaN;
  return (n * sxy - sx * sy) / den;
}

json num(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

std::string machine() {
  std::ifstream f("/proc/cpuinfo");
  std::string line, model = "unknown CPU";
  while (std::getline(f, line))
    if (line.rfind("model name", 0) == 0 && line.find(':') != std::string::npos) {
      model = line.substr(line.find(':') + 2);
      break;
    }
  return model + " (" + std::to_string(std::thread::hardware_concurrency()) + " threads)";
}

bool is_bench_dir(const fs::path& dir) { return manifest_format_is(dir, kBenchFormat, "bench.json"); }

Status run_bench(const BenchOptions& o) {
  // Everything that can be wrong with the command line is found before any work (R1-BEN-004).
  R1_ASSIGN(const auto size, parse_image_size(o.size, "bench: --size"));
  std::vector<Input> inputs;
  for (const auto& path : o.snapshots) {
    Input in;
    in.path = path;
    in.name = fs::path(path).stem().string();
    inputs.push_back(std::move(in));
  }
  for (const auto& g : o.gens) {
    R1_ASSIGN(Input in, parse_gen(g));
    inputs.push_back(std::move(in));
  }
  if (inputs.empty()) return Status::input("bench: give a snapshot or --gen KIND:SIZE (e.g. --gen ba:1000,ba:10000)");
  // Unique names, since they name the files: the second "ba-1000" becomes "ba-1000.2".
  std::map<std::string, int> seen;
  for (auto& in : inputs)
    if (const int k = ++seen[in.name]; k > 1) in.name += "." + std::to_string(k);
  R1_ASSIGN(const std::vector<BackendEntry> bes, choose_backends(o.backends));
  for (auto& in : inputs) {
    if (in.params) continue;
    R1_ASSIGN(const Snapshot s, read_snapshot(in.path));
    in.particles = s.particles.size();
    in.links = s.links.size();
  }

  AtomicDirectory out(o.out, is_bench_dir);
  R1_TRY(out.open());
  const fs::path dir = out.temp_path(), work = dir / "work";
  fs::create_directories(work);
  fs::create_directories(dir / "frames");
  for (auto& in : inputs) {
    if (!in.params) continue;
    auto made = generate(*in.params);
    if (!made.is_ok()) return made.status().with_prefix("bench: --gen '" + in.gen + "': ");
    const Snapshot& s = *made;
    fs::create_directories(dir / "inputs");
    in.path = (dir / "inputs" / (in.name + ".graph")).string();
    R1_TRY(write_snapshot(s, in.path));
    in.particles = s.particles.size();
    in.links = s.links.size();
    std::fprintf(stderr, "bench: generated %s: %llu particles, %llu links\n", in.name.c_str(),
                 static_cast<unsigned long long>(in.particles), static_cast<unsigned long long>(in.links));
  }

  std::vector<Run> runs;
  const std::size_t total = inputs.size() * bes.size();
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    const std::size_t ref = runs.size();
    for (std::size_t b = 0; b < bes.size(); ++b) {
      Run r;
      r.input = i, r.backend = b;
      R1_TRY(run_one(r, inputs[i], bes[b], work, dir, o.size));
      const std::string stem = inputs[i].name + "." + bes[b].name;
      if (b == 0 && !r.error.empty()) {
        // Nothing to compare with: the bench stops with the reference's own error kind.
        const ChildRun& failed = r.epoch.ok() ? r.frame : r.epoch;
        const ErrorKind kind = failed.exit_code == 2   ? ErrorKind::kInput
                               : failed.exit_code == 3 ? ErrorKind::kOutput
                                                       : ErrorKind::kInternal;
        return Status::error(kind, "bench: the reference failed on " + inputs[i].path + ": " + r.error);
      }
      // Each check runs when its child ran: an epoch that does not render is still compared.
      if (b > 0 && r.epoch.ok())
        R1_TRY(compare_epochs(r, bes[b], work / (stem + ".epoch"),
                              work / (inputs[i].name + "." + bes[0].name + ".epoch")));
      if (b > 0 && r.frame.ok()) R1_TRY(compare_frames(r, dir / r.png, dir / runs[ref].png));
      std::fprintf(stderr, "bench: [%zu/%zu] %s on %s: epoch %s s (peak %.0f MiB), render %s s (peak %.0f MiB)%s%s\n",
                   runs.size() + 1, total, inputs[i].name.c_str(), bes[b].name.c_str(),
                   secs(time_of(r, "epoch")).c_str(), r.epoch.peak_rss_mib, secs(time_of(r, "render")).c_str(),
                   r.frame.peak_rss_mib, b == 0 ? "" : (", epoch " + epoch_check(r, bes[b], false)).c_str(),
                   b == 0 ? "" : (", frame dE00 " + frame_check(r, false)).c_str());
      if (!r.error.empty()) std::fprintf(stderr, "bench:   %s: %s\n", bes[b].name.c_str(), r.error.c_str());
      runs.push_back(std::move(r));
    }
  }
  fs::remove_all(work);

  // ---- the report: table, bench.json, bench.png (R1-BEN-030..042) ----
  auto ref_of = [&](const Run& r) -> const Run& { return runs[r.input * bes.size()]; };
  bool all_agree = true;
  std::vector<std::vector<std::string>> table{{"input", "particles", "backend", "spectral", "focus", "frame",
                                               "encoding", "hierarchy", "epoch", "render", "epoch MiB", "render MiB",
                                               "speedup", "epoch check", "render dE00"}};
  json jruns = json::array();
  for (const Run& r : runs) {
    const bool is_ref = r.backend == 0;
    const Input& in = inputs[r.input];
    const BackendEntry& b = bes[r.backend];
    if (!is_ref) all_agree = all_agree && r.agrees();
    std::vector<std::string> row{in.name, std::to_string(in.particles), b.name};
    for (const auto& st : kStages) row.push_back(secs(time_of(r, st)));
    row.push_back(r.epoch.peak_rss_mib > 0 ? fixed(r.epoch.peak_rss_mib, 0) : "-");
    row.push_back(r.frame.peak_rss_mib > 0 ? fixed(r.frame.peak_rss_mib, 0) : "-");
    const double total_speedup = speedup(ref_of(r), r, "epoch");
    row.push_back(times_x(total_speedup));
    row.push_back(epoch_check(r, b, is_ref));
    row.push_back(frame_check(r, is_ref));
    table.push_back(std::move(row));

    json j = {{"input", in.name}, {"backend", b.name}};
    json times = json::object(), sp = json::object();
    for (const auto& [k, v] : r.times) times[k] = v;
    for (const auto& st : kStages) sp[st] = num(speedup(ref_of(r), r, st));
    j["times_s"] = times;
    j["speedup"] = sp;
    j["epoch_run"] = {{"wall_s", r.epoch.wall_s}, {"peak_rss_mib", r.epoch.peak_rss_mib}, {"exit", r.epoch.exit_code}};
    j["render_run"] = {{"wall_s", r.frame.wall_s},
                       {"peak_rss_mib", r.frame.peak_rss_mib},
                       {"exit", r.frame.exit_code},
                       {"png", r.frame.ok() ? json(r.png) : json(nullptr)}};
    if (!r.error.empty()) j["error"] = r.error;
    if (!is_ref && r.epoch.ok() && (b.bytes || std::isfinite(r.deviation))) {
      json e = {{"method", b.bytes ? "bytes" : "positions"}, {"agrees", r.epoch_agrees}};
      if (b.bytes) {
        e["differing_files"] = r.differing;
      } else {
        e["max_deviation_r_scene"] = num(r.deviation);
        e["bound_r_scene"] = conformance::kPositionBound;
      }
      j["epoch_agreement"] = e;
    }
    if (!is_ref && r.frame.ok()) {
      j["frame_agreement"] = {{"mean_de2000", r.frame_diff.mean_2000},
                              {"p99_de2000", r.frame_diff.p99_2000},
                              {"max_de2000", r.frame_diff.max_2000},
                              {"bound_mean_de2000", conformance::kPixelBound},
                              {"agrees", r.frame_agrees}};
    }
    j["agrees"] = is_ref || r.agrees();
    jruns.push_back(j);
  }

  BenchChart chart;
  json jbackends = json::array(), jscaling = json::array();
  // The chart's bars and the speedup table: the largest input (most particles; the first of equals).
  std::size_t largest = 0;
  for (std::size_t i = 1; i < inputs.size(); ++i)
    if (inputs[i].particles > inputs[largest].particles) largest = i;
  chart.speedup_title = "speedup against the reference per stage: " + inputs[largest].name + " (" +
                        std::to_string(inputs[largest].particles) + " particles)";
  chart.stages = kStages;
  std::string scaling_line;
  for (std::size_t b = 0; b < bes.size(); ++b) {
    chart.backends.push_back(bes[b].name);
    std::vector<std::pair<double, double>> pts;
    json jp = json::array();
    for (const Run& r : runs)
      if (r.backend == b && r.epoch.ok()) {
        pts.emplace_back(static_cast<double>(inputs[r.input].particles), r.times.at("epoch"));
        jp.push_back({{"particles", inputs[r.input].particles}, {"epoch_s", r.times.at("epoch")}});
      }
    const double expo = scaling_exponent(pts);
    chart.scaling.push_back(pts);
    jscaling.push_back({{"backend", bes[b].name}, {"points", jp}, {"exponent", num(expo)}});
    if (std::isfinite(expo))
      scaling_line += (scaling_line.empty() ? "" : ", ") + bes[b].name + " |P|^" + fixed(expo, 2);
    if (b > 0) {
      std::vector<double> row;
      for (const auto& st : kStages)
        row.push_back(speedup(runs[largest * bes.size()], runs[largest * bes.size() + b], st));
      chart.speedup.push_back(row);
    }
    jbackends.push_back({{"name", bes[b].name},
                         {"summary", bes[b].summary},
                         {"deterministic", bes[b].deterministic},
                         {"domain", bes[b].domain},
                         {"epoch_check", b == 0         ? "oracle"
                                         : bes[b].bytes ? "bytes"
                                                        : "positions"}});
  }
  json jinputs = json::array();
  double parent_rss = 0;
  for (const Run& r : runs) parent_rss = std::max({parent_rss, r.epoch.parent_rss_mib, r.frame.parent_rss_mib});
  for (const auto& in : inputs)
    jinputs.push_back({{"name", in.name},
                       {"path", in.gen.empty() ? in.path : "inputs/" + in.name + ".graph"},
                       {"generated", in.gen.empty() ? json(nullptr) : json(in.gen)},
                       {"particles", in.particles},
                       {"links", in.links}});
  const json report = {{"format", kBenchFormat},
                       {"version", 1},
                       {"machine", machine()},
                       {"render_view",
                        {{"width", size.first},
                         {"height", size.second},
                         {"camera", "default: the first orbit view, the whole scene in view"}}},
                       {"stages", kStages},
                       {"backends", jbackends},
                       {"inputs", jinputs},
                       {"runs", jruns},
                       {"scaling", jscaling},
                       {"bench_rss_mib", parent_rss},
                       {"agree", all_agree}};
  R1_TRY(out.write("bench.json", report.dump(2) + "\n"));
  std::string warning;
  R1_TRY(write_bench_chart(chart, dir / "bench.png", &warning));
  if (!warning.empty()) std::fprintf(stderr, "bench: %s\n", warning.c_str());
  R1_TRY(out.commit());

  std::printf(
      "r1 bench: %zu input%s x %zu backend%s on %s; seconds per stage (r1 epoch's timings_s; epoch = their "
      "sum; render = one %dx%d frame); peak resident MiB per child process\n",
      inputs.size(), inputs.size() == 1 ? "" : "s", bes.size(), bes.size() == 1 ? "" : "s", machine().c_str(),
      size.first, size.second);
  print_table(table, {0, 2, 13, 14});
  if (bes.size() > 1) {
    std::printf("\nspeedup against the reference (reference time / backend time)\n");
    std::vector<std::vector<std::string>> sp{{"input", "backend"}};
    sp[0].insert(sp[0].end(), kStages.begin(), kStages.end());
    for (const Run& r : runs) {
      if (r.backend == 0) continue;
      std::vector<std::string> row{inputs[r.input].name, bes[r.backend].name};
      for (const auto& st : kStages) {
        const double s = speedup(ref_of(r), r, st);
        row.push_back(times_x(s));
      }
      sp.push_back(std::move(row));
    }
    print_table(sp, {0, 1});
  }
  if (!scaling_line.empty())
    std::printf("\nepoch time against |P| (least squares, log-log): %s\n", scaling_line.c_str());
  std::vector<std::string> bad;
  for (const Run& r : runs)
    if (r.backend > 0 && !r.agrees()) bad.push_back(bes[r.backend].name + " on " + inputs[r.input].name);
  if (bad.empty()) {
    std::printf("bench: AGREE: every backend agrees with the reference; wrote %s/bench.json and bench.png\n",
                o.out.c_str());
  } else {
    std::string list;
    for (const auto& s : bad) list += (list.empty() ? "" : ", ") + s;
    std::printf("bench: DISAGREE: %s; wrote %s/bench.json and bench.png\n", list.c_str(), o.out.c_str());
    verdict_exit() = 4;
  }
  return Status::ok();
}

// ---- the measured frame: r1 bench-frame (hidden), run as a child by r1 bench -------------

struct FrameOptions {
  std::string dir, out, backend, size = "480x270";
};

// The default view of `r1 render EPOCH --size WxH`, through the backend's frame stage; prints
// {"frame_s": ...} with the frame stage's own time at full precision (R1-BEN-021).
Status run_bench_frame(const FrameOptions& o) {
  R1_ASSIGN(const auto size, parse_image_size(o.size, "bench: --size"));
  R1_ASSIGN(auto backend, backends::make_backend(o.backend));
  R1_ASSIGN(const Epoch e, read_epoch(o.dir));
  if (e.ids.empty()) return Status::input(o.dir + ": the epoch has no particles");
  const render::Scene scene = render::make_scene(e);
  render::View base;
  base.width = size.first, base.height = size.second;
  const double distance = render::fit_distance(scene, base.camera.fov_deg);
  render::View v = render::orbit_views(base, scene.centroid, distance, 1).front();
  R1_TRY(render::validate_view(v, "bench"));
  render::FrameStats st;
  R1_ASSIGN(const render::Image img, backend->render(e, v, {}, &st, {}));
  R1_TRY(render::write_image(img, o.out, render::srgb8_to_linear(v.background)));
  std::printf("%s\n", json({{"frame_s", st.total_s}}).dump().c_str());
  return Status::ok();
}

}  // namespace

void add_bench(CLI::App& app, Runner& selected) {
  auto o = std::make_shared<BenchOptions>();
  auto* cmd = app.add_subcommand(
      "bench", "run the reference and other backends side by side: agreement, time per stage, speedup, memory");
  cmd->add_option("SNAPSHOT", o->snapshots, "snapshots to run (.graph, TSV/CSV edge list, Matrix Market)");
  cmd->add_option("--backend", o->backends,
                  "backend to compare with the reference (repeatable or comma-separated; default: every backend "
                  "expected to conform)")
      ->delimiter(',');
  cmd->add_option("--gen", o->gens,
                  "generated inputs KIND[:SIZE], comma-separated: ba:1000,ba:10000, grid:32x32, crystal")
      ->delimiter(',');
  cmd->add_option("-o,--out", o->out, "output directory (default bench-out): bench.json, bench.png, frames/, inputs/");
  cmd->add_option("--size", o->size, "size of the rendered frame, WIDTHxHEIGHT (480x270)");
  cmd->callback([o, &selected] { selected = [o] { return run_bench(*o); }; });

  // The child r1 bench runs to time one frame; hidden from the help (group "").
  auto f = std::make_shared<FrameOptions>();
  auto* fc = app.add_subcommand("bench-frame", "one timed frame for r1 bench")->group("");
  fc->add_option("EPOCH_DIR", f->dir)->required();
  fc->add_option("-o", f->out)->required();
  fc->add_option("--backend", f->backend)->required();
  fc->add_option("--size", f->size);
  fc->callback([f, &selected] { selected = [f] { return run_bench_frame(*f); }; });
}

}  // namespace r1::cli
