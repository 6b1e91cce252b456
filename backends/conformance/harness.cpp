// Suite runs, comparisons and golden sets (R1-CONF-030..047).
#include "r1/conformance/harness.hpp"

#include <chrono>
#include <cstdio>
#include <set>

#include <nlohmann/json.hpp>

#include "r1/reference/atomic_dir.hpp"
#include "r1/reference/hierarchy.hpp"
#include "r1/reference/epoch.hpp"
#include "r1/reference/input_file.hpp"
#include "render/image.hpp"

namespace r1::conformance {

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

Result<std::string> read_all(const fs::path& p) {
  R1_ASSIGN(const auto in, InputFile::open(p.string()));
  return std::string(in->text());
}

std::string hex(const hemera::Digest& d) { return hemera::to_hex(d); }

bool is_golden_dir(const fs::path& dir) { return manifest_format_is(dir, kGoldenFormat); }

// The manifest keys of a snapshot graph's files (R1-CONF-043), with the part of LoadedSnapshot each names.
struct FileKey {
  const char* key;
  const SuiteFile LoadedSnapshot::*file;
};
constexpr FileKey kFileKeys[] = {{"snapshot_file", &LoadedSnapshot::file},
                                 {"titles_file", &LoadedSnapshot::titles},
                                 {"crystal_file", &LoadedSnapshot::crystal}};

// A golden set's copy of a snapshot graph's files (R1-CONF-043): the same relative paths under
// the set, so its suite.toml finds them there.
Status copy_files(const SuiteGraph& g, AtomicDirectory& out, std::set<std::string>& written, json& entry) {
  if (!g.loaded) return Status::internal("suite graph " + g.name + ": its snapshot file was not loaded");
  for (const FileKey& k : kFileKeys) {
    const SuiteFile& f = (*g.loaded).*k.file;
    if (f.path.empty()) continue;
    entry[k.key] = {{"file", f.path}, {"digest", hex(hemera::hash(f.bytes))}};
    if (!written.insert(f.path).second) continue;  // two entries may share a file
    std::error_code ec;
    fs::create_directories((out.temp_path() / f.path).parent_path(), ec);
    if (ec) return Status::output((out.temp_path() / f.path).parent_path().string() + ": cannot create: " + ec.message());
    R1_TRY(out.write(f.path, f.bytes));
  }
  return Status::ok();
}

// Before anything is computed (R1-CONF-044): a snapshot graph's files under the set match the
// manifest byte for byte (checked as read, before they are parsed)...
Status check_file_bytes(const SuiteGraph& g, const LoadedSnapshot& files, const std::string& suite_source, const json& entry) {
  const std::string at = g.where(suite_source);
  for (const FileKey& k : kFileKeys) {
    const SuiteFile& f = files.*k.file;
    if (f.path.empty() != !entry.contains(k.key))
      return Status::input(at + ": " + k.key + " of the manifest does not match suite.toml");
    if (f.path.empty()) continue;
    if (entry.at(k.key).at("file").get<std::string>() != f.path)
      return Status::input(at + ": " + f.path + ": the manifest names another file");
    if (hex(hemera::hash(f.bytes)) != entry.at(k.key).at("digest").get<std::string>())
      return Status::input(at + ": " + f.path + ": digest does not match the manifest (the file was changed)");
  }
  return Status::ok();
}

// ...and the snapshot read from them has the recorded snapshot digest (R1-IN-040).
Status check_snapshot_digest(const SuiteGraph& g, const std::string& suite_source, const json& entry) {
  const std::string at = g.where(suite_source);
  const std::string want = entry.at("snapshot_digest").get<std::string>();
  const std::string got = hex(snapshot_digest(g.loaded->snapshot));
  if (got != want)
    return Status::input(at + ": " + g.file + ": snapshot digest " + got.substr(0, 16) + " does not match the manifest's " +
                         want.substr(0, 16));
  return Status::ok();
}

}  // namespace

Result<GraphRun> run_graph(backends::Backend& b, const Suite& suite, const SuiteGraph& g, bool keep_images,
                           const ProgressFn& progress, bool draw) {
  GraphRun run;
  run.name = g.name;
  R1_ASSIGN(const SuiteInput in, make_input(g));
  auto t0 = std::chrono::steady_clock::now();
  R1_ASSIGN(run.epoch, backends::run_epoch(b, in.snapshot, in.graph, {}, progress));
  run.epoch_s = seconds_since(t0);
  t0 = std::chrono::steady_clock::now();
  render::RenderOptions ro;
  ro.timings = false;
  for (const SuiteView& sv : suite.views) {
    if (!draw) break;
    R1_ASSIGN(render::Image img, b.render(run.epoch, sv.view, ro, nullptr, {}));
    if (img.width != sv.view.width || img.height != sv.view.height)
      return Status::internal(std::string(b.name()) + " rendered " + std::to_string(img.width) + "x" +
                              std::to_string(img.height) + " for a " + std::to_string(sv.view.width) + "x" +
                              std::to_string(sv.view.height) + " view");
    R1_ASSIGN(auto bytes, render::display_srgb8(img, render::srgb8_to_linear(sv.view.background)));
    run.display.push_back(std::move(bytes));
    if (keep_images) run.images.push_back(std::move(img));
  }
  run.render_s = seconds_since(t0);
  return run;
}

Expected expected_from(const GraphRun& r) {
  Expected e;
  e.name = r.name;
  e.hierarchy = r.epoch.hierarchy;
  e.topology = topology_bytes(r.epoch.hierarchy);
  e.positions = r.epoch.frame.position;
  e.display = r.display;
  return e;
}

Result<GraphComparison> compare(const GraphRun& got, const Expected& want) {
  GraphComparison c;
  c.name = got.name;
  c.topology_equal = topology_bytes(got.epoch.hierarchy) == want.topology;
  if (!c.topology_equal) {
    c.topology_difference = topology_difference(got.epoch.hierarchy, want.hierarchy);
    if (c.topology_difference.empty()) c.topology_difference = "the topology bytes differ";
  }
  if (got.epoch.frame.position.size() == want.positions.size()) {
    c.positions_identical = got.epoch.frame.position == want.positions;
    R1_ASSIGN(c.position, position_deviation(got.epoch.frame.position, want.positions));
  } else {
    // A different particle count cannot meet any position bound.
    c.position.max_over_r = std::numeric_limits<double>::infinity();
  }
  if (got.display.empty()) return c;  // not drawn: topology and positions only
  if (got.display.size() != want.display.size())
    return Status::internal(got.name + ": " + std::to_string(got.display.size()) + " views, expected " +
                            std::to_string(want.display.size()));
  for (std::size_t v = 0; v < got.display.size(); ++v) {
    if (got.display[v].size() != want.display[v].size())
      return Status::input(got.name + ": view " + std::to_string(v + 1) + ": image sizes differ");
    const int pixels = static_cast<int>(got.display[v].size() / 3);
    // Every suite image is width x height; the stats only need the pixel count, so 1 row suffices
    // when the width is unknown here.
    c.views.push_back(render::diff_srgb8(got.display[v], want.display[v], pixels, 1, {}, nullptr));
  }
  return c;
}

std::string describe(const GraphComparison& c) {
  char buf[256];
  double worst = 0, max_px = 0;
  for (const auto& v : c.views) {
    worst = std::max(worst, v.mean_2000);
    max_px = std::max(max_px, v.max_2000);
  }
  std::string s = c.name + ": topology " + (c.topology_equal ? "same" : "CHANGED (" + c.topology_difference + ")");
  std::snprintf(buf, sizeof buf, "; positions %s (max %.3g R_scene); images: worst view mean dE00 %.3f, max pixel %.2f",
                c.positions_identical ? "same" : "CHANGED", c.position.max_over_r, worst, max_px);
  return s + buf;
}

bool reproduces(const GraphComparison& c) {
  if (!c.topology_equal || !c.positions_identical) return false;
  for (const auto& v : c.views)
    if (v.mean_2000 > kPixelBound) return false;
  return true;
}

Status write_golden(const Suite& suite, const std::vector<GraphRun>& runs, const fs::path& dir, const std::string& backend) {
  AtomicDirectory out(dir, is_golden_dir);
  R1_TRY(out.open());
  json m;
  m["format"] = kGoldenFormat;
  m["generator"] = "r1 golden (backend " + backend + ")";
  m["suite"] = {{"name", suite.name}, {"file", "suite.toml"}, {"digest", hex(hemera::hash(suite.text))},
                {"width", suite.width}, {"height", suite.height}};
  R1_TRY(out.write("suite.toml", suite.text));
  std::set<std::string> copied;
  json graphs = json::array();
  for (std::size_t gi = 0; gi < runs.size(); ++gi) {
    const GraphRun& r = runs[gi];
    const std::string topo = topology_bytes(r.epoch.hierarchy);
    const std::string pos = position_bytes(r.epoch.frame.position);
    R1_TRY(out.write(r.name + ".topology.bin", topo));
    R1_TRY(out.write(r.name + ".positions.bin", pos));
    json g = {{"name", r.name},
              {"particles", r.epoch.ids.size()},
              {"snapshot_digest", hex(r.epoch.snapshot_digest)},
              {"topology", {{"file", r.name + ".topology.bin"}, {"digest", hex(hemera::hash(topo))}}},
              {"hierarchy_digest", hex(hierarchy_digest(r.epoch.hierarchy))},
              {"positions", {{"file", r.name + ".positions.bin"}, {"digest", hex(hemera::hash(pos))}}}};
    if (suite.graphs[gi].is_file()) {
      R1_TRY(copy_files(suite.graphs[gi], out, copied, g));
    } else {
      g["gen"] = suite.graphs[gi].gen;
    }
    json views = json::array();
    for (std::size_t v = 0; v < suite.views.size(); ++v) {
      const std::string base = r.name + "." + suite.views[v].name;
      const render::View& view = suite.views[v].view;
      R1_TRY(render::write_image(r.images.at(v), out.temp_path() / (base + ".png"), render::srgb8_to_linear(view.background)));
      R1_TRY(render::write_image(r.images.at(v), out.temp_path() / (base + ".exr"), render::srgb8_to_linear(view.background)));
      R1_ASSIGN(const std::string png, read_all(out.temp_path() / (base + ".png")));
      views.push_back({{"name", suite.views[v].name},
                       {"png", base + ".png"},
                       {"png_digest", hex(hemera::hash(png))},
                       {"exr", base + ".exr"}});
    }
    g["views"] = std::move(views);
    graphs.push_back(std::move(g));
  }
  m["graphs"] = std::move(graphs);
  R1_TRY(out.write("manifest.json", m.dump(2) + "\n"));
  return out.commit();
}

Result<GoldenSet> read_golden(const fs::path& dir) {
  GoldenSet set;
  const std::string mpath = (dir / "manifest.json").string();
  R1_ASSIGN(const std::string mtext, read_all(dir / "manifest.json"));
  json m;
  try {
    m = json::parse(mtext);
  } catch (const json::exception& e) {
    return Status::input(mpath + ": malformed manifest: " + e.what());
  }
  if (!m.is_object() || m.value("format", "") != kGoldenFormat) return Status::input(mpath + ": not an r1 golden manifest");
  try {
    R1_ASSIGN(const std::string stext, read_all(dir / "suite.toml"));
    if (hex(hemera::hash(stext)) != m.at("suite").at("digest").get<std::string>())
      return Status::input((dir / "suite.toml").string() + ": digest does not match the manifest");
    R1_ASSIGN(set.suite, parse_suite(stext, (dir / "suite.toml").string()));
    const json& graphs = m.at("graphs");
    if (!graphs.is_array() || graphs.size() != set.suite.graphs.size())
      return Status::input(mpath + ": graphs do not match suite.toml");
    for (std::size_t gi = 0; gi < graphs.size(); ++gi)
      if (graphs[gi].at("name").get<std::string>() != set.suite.graphs[gi].name)
        return Status::input(mpath + ": graph " + graphs[gi].at("name").get<std::string>() + " is not the suite's");
    // Snapshot graphs: their copies under DIR, checked against the manifest (R1-CONF-044).
    R1_TRY(load_suite_files(set.suite, dir, [&](std::size_t gi, const LoadedSnapshot& files) {
      return check_file_bytes(set.suite.graphs[gi], files, set.suite.source, graphs[gi]);
    }));
    for (std::size_t gi = 0; gi < graphs.size(); ++gi)
      if (set.suite.graphs[gi].is_file()) R1_TRY(check_snapshot_digest(set.suite.graphs[gi], set.suite.source, graphs[gi]));
    for (std::size_t gi = 0; gi < graphs.size(); ++gi) {
      const json& g = graphs[gi];
      Expected e;
      e.name = g.at("name").get<std::string>();
      if (e.name != set.suite.graphs[gi].name) return Status::input(mpath + ": graph " + e.name + " is not the suite's");
      const std::string tfile = g.at("topology").at("file").get<std::string>();
      R1_ASSIGN(e.topology, read_all(dir / tfile));
      if (hex(hemera::hash(e.topology)) != g.at("topology").at("digest").get<std::string>())
        return Status::input((dir / tfile).string() + ": digest does not match the manifest");
      R1_ASSIGN(e.hierarchy, format::parse_topology_bytes(e.topology, (dir / tfile).string()));
      const std::string pfile = g.at("positions").at("file").get<std::string>();
      R1_ASSIGN(const std::string pos, read_all(dir / pfile));
      if (hex(hemera::hash(pos)) != g.at("positions").at("digest").get<std::string>())
        return Status::input((dir / pfile).string() + ": digest does not match the manifest");
      R1_ASSIGN(e.positions, parse_position_bytes(pos, (dir / pfile).string()));
      const json& views = g.at("views");
      if (!views.is_array() || views.size() != set.suite.views.size())
        return Status::input(mpath + ": " + e.name + ": views do not match suite.toml");
      for (std::size_t v = 0; v < views.size(); ++v) {
        const fs::path png = dir / views[v].at("png").get<std::string>();
        R1_ASSIGN(const std::string bytes, read_all(png));
        if (hex(hemera::hash(bytes)) != views[v].at("png_digest").get<std::string>())
          return Status::input(png.string() + ": digest does not match the manifest");
        int w = 0, h = 0;
        R1_ASSIGN(auto px, render::read_srgb8(png, &w, &h, set.suite.views[v].view.background));
        if (w != set.suite.width || h != set.suite.height)
          return Status::input(png.string() + ": " + std::to_string(w) + "x" + std::to_string(h) + ", expected " +
                               std::to_string(set.suite.width) + "x" + std::to_string(set.suite.height));
        e.display.push_back(std::move(px));
      }
      set.graphs.push_back(std::move(e));
    }
  } catch (const json::exception& ex) {
    return Status::input(mpath + ": malformed manifest: " + ex.what());
  }
  return set;
}

}  // namespace r1::conformance
