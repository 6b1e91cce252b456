// Suite files (R1-CONF-001..007): TOML with a name, an image size, [[graph]] entries of `r1 gen`
// words or snapshot files, and exactly 16 [[view]] entries (eye, target, fov; up is +z as in
// `r1 render`).
#include "r1/conformance/suite.hpp"

#include <charconv>
#include <fstream>
#include <set>
#include <sstream>

#include "r1/reference/graph_build.hpp"
#include "r1/reference/snapshot_io.hpp"
#include "snapshot/toml_subset.hpp"

namespace r1::conformance {

namespace {

bool valid_name(std::string_view s) {
  if (s.empty() || s.size() > 64) return false;
  for (char c : s)
    if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-' || c == '_')) return false;
  return true;
}

Result<std::int64_t> int_word(std::string_view w, const std::string& where) {
  std::int64_t v = 0;
  const auto [p, ec] = std::from_chars(w.data(), w.data() + w.size(), v);
  if (ec != std::errc() || p != w.data() + w.size()) return Status::input(where + ": '" + std::string(w) + "' is not an integer");
  return v;
}

Result<double> real_word(std::string_view w, const std::string& where) {
  double v = 0;
  const auto [p, ec] = std::from_chars(w.data(), w.data() + w.size(), v);
  if (ec != std::errc() || p != w.data() + w.size()) return Status::input(where + ": '" + std::string(w) + "' is not a number");
  return v;
}

Result<render::Vec3> vec3_of(const toml::node* node, const std::string& where) {
  const toml::array* a = node ? node->as_array() : nullptr;
  const std::string what = where + ": expected an array of 3 decimals (\"12.5\" or integers)";
  if (!a || a->size() != 3) return Status::input(what);
  double v[3];
  for (std::size_t i = 0; i < 3; ++i) {
    const auto x = toml_subset::decimal((*a)[i]);
    if (!x) return Status::input(what);
    v[i] = *x;
  }
  return render::Vec3{v[0], v[1], v[2]};
}

}  // namespace

std::string SuiteGraph::where(const std::string& suite_source) const {
  return suite_source + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": graph '" + name + "'";
}

Result<GenParams> parse_gen_words(std::string_view words, const std::string& where) {
  std::vector<std::string> w;
  std::istringstream in{std::string(words)};
  for (std::string t; in >> t;) w.push_back(t);
  if (w.empty()) return Status::input(where + ": empty generator");
  GenParams p;
  R1_ASSIGN(p.kind, gen_kind_from_name(w[0]));
  for (std::size_t i = 1; i < w.size(); i += 2) {
    const std::string& opt = w[i];
    if (i + 1 >= w.size()) return Status::input(where + ": option " + opt + " needs a value");
    const std::string& val = w[i + 1];
    const std::string at = where + ": " + opt;
    if (opt == "--n") {
      R1_ASSIGN(p.n, int_word(val, at));
    } else if (opt == "--m") {
      R1_ASSIGN(p.m, int_word(val, at));
    } else if (opt == "--k") {
      R1_ASSIGN(p.k, int_word(val, at));
    } else if (opt == "--seed") {
      R1_ASSIGN(const std::int64_t s, int_word(val, at));
      if (s < 0) return Status::input(at + ": must be >= 0");
      p.seed = static_cast<std::uint64_t>(s);
    } else if (opt == "--dims") {
      R1_ASSIGN(p.dims, parse_dims(val));
    } else if (opt == "--sizes") {
      std::istringstream parts(val);
      for (std::string part; std::getline(parts, part, ',');) {
        R1_ASSIGN(const std::int64_t s, int_word(part, at));
        p.sizes.push_back(s);
      }
    } else if (opt == "--p-in") {
      R1_ASSIGN(p.p_in, real_word(val, at));
    } else if (opt == "--p-out") {
      R1_ASSIGN(p.p_out, real_word(val, at));
    } else if (opt == "--p-triad") {
      R1_ASSIGN(p.p_triad, real_word(val, at));
    } else if (opt == "--radius") {
      R1_ASSIGN(p.radius, real_word(val, at));
    } else {
      return Status::input(where + ": unknown generator option '" + opt + "'");
    }
  }
  // The generator's own validation (ranges, options the kind does not take), without the work.
  // The generator's own message, placed in the suite file.
  const Result<std::string> line = gen_command_line(p);
  if (!line.is_ok()) return Status::input(where + ": " + line.status().message());
  return p;
}

Result<Suite> parse_suite(std::string_view text, const std::string& name) {
  R1_ASSIGN(const toml::table t, toml_subset::parse(text, name));
  Suite s;
  s.source = name;
  s.text = std::string(text);
  const auto sname = t["name"].value<std::string>();
  if (!sname || !valid_name(*sname)) return Status::input(name + ": name: expected a name of a-z, 0-9, '-', '_'");
  s.name = *sname;
  const auto w = t["width"].value<std::int64_t>(), h = t["height"].value<std::int64_t>();
  // The same image limits as a view file (R1-RND-004).
  if (!w || !h || *w < 1 || *h < 1 || *w > 16384 || *h > 16384)
    return Status::input(name + ": width, height: expected integers in 1..16384");
  s.width = static_cast<int>(*w);
  s.height = static_cast<int>(*h);
  const toml::array* graphs = t["graph"].as_array();
  if (!graphs || graphs->empty()) return Status::input(name + ": expected at least one [[graph]]");
  std::set<std::string> names;
  for (std::size_t i = 0; i < graphs->size(); ++i) {
    const toml::table* g = (*graphs)[i].as_table();
    const std::string where = name + ": graph " + std::to_string(i + 1);
    if (!g) return Status::input(where + ": expected a table");
    SuiteGraph sg;
    sg.line = static_cast<std::size_t>(g->source().begin.line);
    const auto gname = (*g)["name"].value<std::string>();
    if (!gname || !valid_name(*gname)) return Status::input(where + ": name: expected a name of a-z, 0-9, '-', '_'");
    if (!names.insert(*gname).second) return Status::input(where + ": name '" + *gname + "' is used twice");
    sg.name = *gname;
    const std::string at = sg.where(name);
    for (const char* key : {"gen", "file", "format", "titles", "crystal"})
      if ((*g)[key].node() && !(*g)[key].is_string()) return Status::input(at + ": " + key + ": expected a string");
    const auto gen = (*g)["gen"].value<std::string>();
    const auto file = (*g)["file"].value<std::string>();
    if (gen.has_value() == file.has_value())
      return Status::input(at + ": expected exactly one of gen (the words of `r1 gen`) and file (a snapshot file)");
    if (gen) {
      for (const char* key : {"format", "titles", "crystal"})
        if ((*g)[key].node()) return Status::input(at + ": " + key + " is only for a file graph");
      sg.gen = *gen;
      R1_ASSIGN(sg.params, parse_gen_words(sg.gen, where + ": gen"));
    } else {
      // A snapshot file and its side files, as `r1 epoch FILE --format --titles --crystal` takes them.
      sg.file = *file;
      sg.format = (*g)["format"].value_or(std::string());
      sg.titles = (*g)["titles"].value_or(std::string());
      sg.crystal = (*g)["crystal"].value_or(std::string());
      R1_TRY(check_suite_path(sg.file, at + ": file"));
      if (!sg.titles.empty()) R1_TRY(check_suite_path(sg.titles, at + ": titles"));
      if (!sg.crystal.empty()) R1_TRY(check_suite_path(sg.crystal, at + ": crystal"));
      if (!sg.format.empty() && format_from_name(sg.format) == SnapshotFormat::kAuto)
        return Status::input(at + ": format: '" + sg.format + "' is not one of graph, tsv, csv, mtx");
    }
    sg.stresses = (*g)["stresses"].value_or(std::string());
    s.graphs.push_back(std::move(sg));
  }
  const toml::array* views = t["view"].as_array();
  if (!views || views->size() != kSuiteViews)
    return Status::input(name + ": expected exactly " + std::to_string(kSuiteViews) + " [[view]] entries");
  for (std::size_t i = 0; i < views->size(); ++i) {
    const toml::table* v = (*views)[i].as_table();
    const std::string where = name + ": view " + std::to_string(i + 1);
    if (!v) return Status::input(where + ": expected a table");
    SuiteView sv;
    const auto vname = (*v)["name"].value<std::string>();
    if (!vname || !valid_name(*vname)) return Status::input(where + ": name: expected a name of a-z, 0-9, '-', '_'");
    sv.name = *vname;
    R1_ASSIGN(const render::Vec3 eye, vec3_of((*v)["eye"].node(), where + ": eye"));
    R1_ASSIGN(const render::Vec3 target, vec3_of((*v)["target"].node(), where + ": target"));
    sv.view.width = s.width;
    sv.view.height = s.height;
    sv.view.camera.position = eye;
    if (const toml::node* fov = (*v)["fov"].node()) {
      const auto f = toml_subset::decimal(*fov);
      if (!f) return Status::input(where + ": fov: expected a decimal");
      sv.view.camera.fov_deg = *f;
    }
    // Up is +z, as for `r1 render --eye/--target` and orbits (R1-RND-007).
    auto q = render::look_at(eye, target, {0, 0, 1});
    if (!q.is_ok()) return Status::input(where + ": " + q.status().message());
    sv.view.camera.orientation = *q;
    R1_TRY(render::validate_view(sv.view, where));
    s.views.push_back(std::move(sv));
  }
  // A golden set copies the files beside its own (R1-CONF-043): none may take one of their names.
  std::set<std::string> own = {"suite.toml", "manifest.json"};
  for (const SuiteGraph& g : s.graphs) {
    own.insert(g.name + ".topology.bin");
    own.insert(g.name + ".positions.bin");
    for (const SuiteView& v : s.views) {
      own.insert(g.name + "." + v.name + ".png");
      own.insert(g.name + "." + v.name + ".exr");
    }
  }
  for (const SuiteGraph& g : s.graphs)
    for (const std::string* p : {&g.file, &g.titles, &g.crystal})
      if (own.count(*p)) return Status::input(g.where(name) + ": '" + *p + "' is the name of a golden set's own file");
  return s;
}

Result<Suite> read_suite(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return Status::input(path + ": cannot open the suite file");
  std::ostringstream ss;
  ss << f.rdbuf();
  R1_ASSIGN(Suite s, parse_suite(ss.str(), path));
  R1_TRY(load_suite_files(s, std::filesystem::path(path).parent_path()));
  return s;
}

Result<Suite> default_suite() {
  R1_ASSIGN(Suite s, parse_suite(default_suite_text(), "spec/suites/small.toml"));
  s.source = "(built-in small suite, spec/suites/small.toml)";
  return s;
}

Result<SuiteInput> make_input(const SuiteGraph& g) {
  SuiteInput in;
  if (g.is_file()) {
    if (!g.loaded) return Status::internal("suite graph " + g.name + ": its snapshot file was not loaded");
    in.snapshot = g.loaded->snapshot;
  } else {
    R1_ASSIGN(in.snapshot, generate(g.params));
  }
  R1_ASSIGN(in.graph, build_graph(in.snapshot));
  return in;
}

}  // namespace r1::conformance
