// The conformance test suite T of 12.4 / 15 (spec/conformance.md R1-CONF-001..007): named
// graphs, generated or read from snapshot files, each drawn from the suite's 16 fixed viewpoints
// at the suite's image size.
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "r1/reference/generate.hpp"
#include "r1/spec/graph.hpp"
#include "r1/spec/snapshot.hpp"
#include "r1/spec/status.hpp"
#include "render/view.hpp"

namespace r1::conformance {

inline constexpr std::size_t kSuiteViews = 16;  // 15.3: a 16-viewpoint fixed test set

// One file a suite graph reads (R1-CONF-006): its path as written in the suite (relative to the
// suite file's directory, R1-CONF-007) and, once loaded, its bytes.
struct SuiteFile {
  std::string path;   // "graphs/mine.tsv"; empty when the entry has no such file
  std::string bytes;  // filled by load_suite_files
};

// A snapshot graph's files once read: the bytes (a golden set copies them, R1-CONF-043) and the
// snapshot the readers of `r1 epoch` made of them.
struct LoadedSnapshot {
  SuiteFile file, titles, crystal;
  Snapshot snapshot;
};

struct SuiteGraph {
  std::string name;      // [a-z0-9_-]+, unique in the suite: the golden folder's name
  std::string gen;       // `r1 gen` words: "torus --dims 5x5x5"; empty for a snapshot graph
  std::string stresses;  // what this graph exercises (documentation)
  GenParams params;
  // A snapshot graph (R1-CONF-006): `file`, optional `format`, `titles`, `crystal`.
  std::string file, format, titles, crystal;
  std::size_t line = 0;  // the line of its [[graph]] header in the suite file
  std::shared_ptr<const LoadedSnapshot> loaded;  // set by load_suite_files; shared by copies

  bool is_file() const { return !file.empty(); }
  // "SUITE:LINE: graph 'NAME'": where an error about this entry is placed.
  std::string where(const std::string& suite_source) const;
};

struct SuiteView {
  std::string name;
  render::View view;  // camera from eye, target, fov; the suite's image size
};

struct Suite {
  std::string name;
  std::string source;  // the file it came from, or "(built-in small suite)"
  int width = 0, height = 0;
  std::vector<SuiteGraph> graphs;
  std::vector<SuiteView> views;  // exactly kSuiteViews
  std::string text;  // the suite file's bytes, as recorded in golden manifests
};

// Reads a suite file (TOML, R1-CONF-002) and loads its snapshot graphs' files relative to the
// file's directory (load_suite_files). Errors name the file and the key.
Result<Suite> read_suite(const std::string& path);
// Parses the text only: snapshot graphs are not loaded.
Result<Suite> parse_suite(std::string_view text, const std::string& name);
// Reads every snapshot graph's files under `base` with the readers of `r1 epoch` (R1-CONF-044),
// before anything is computed. A missing, unreadable or malformed file is an input error of one
// line naming the suite file, the line and the graph entry. `check_bytes`, when given, sees each
// graph's files as read, before they are parsed (a golden set's digests, R1-CONF-044).
using SuiteFilesCheck = std::function<Status(std::size_t graph, const LoadedSnapshot& files)>;
Status load_suite_files(Suite& suite, const std::filesystem::path& base, const SuiteFilesCheck& check_bytes = {});
// The path rule of R1-CONF-007: relative, '/'-separated, no '..', '.' or empty component.
Status check_suite_path(std::string_view path, const std::string& where);
// The built-in default: spec/suites/small.toml, compiled in.
Result<Suite> default_suite();
std::string_view default_suite_text();

// "ring --n 64" -> GenParams (the options of `r1 gen`, R1-GEN-003).
Result<GenParams> parse_gen_words(std::string_view words, const std::string& where);

struct SuiteInput {
  Snapshot snapshot;
  Graph graph;
};
// Generates the graph's snapshot (or takes the loaded one) and builds its layout graph.
Result<SuiteInput> make_input(const SuiteGraph& g);

}  // namespace r1::conformance
