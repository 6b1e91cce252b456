// The conformance test suite T of 12.4 / 15 (spec/conformance.md R1-CONF-001..006): named
// generated graphs, each drawn from the suite's 16 fixed viewpoints at the suite's image size.
#pragma once

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

struct SuiteGraph {
  std::string name;      // [a-z0-9_-]+, unique in the suite: the golden folder's name
  std::string gen;       // `r1 gen` words: "torus --dims 5x5x5"
  std::string stresses;  // what this graph exercises (documentation)
  GenParams params;
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

// Reads a suite file (TOML, R1-CONF-002). Errors name the file and the key.
Result<Suite> read_suite(const std::string& path);
Result<Suite> parse_suite(std::string_view text, const std::string& name);
// The built-in default: spec/suites/small.toml, compiled in.
Result<Suite> default_suite();
std::string_view default_suite_text();

// "ring --n 64" -> GenParams (the options of `r1 gen`, R1-GEN-003).
Result<GenParams> parse_gen_words(std::string_view words, const std::string& where);

struct SuiteInput {
  Snapshot snapshot;
  Graph graph;
};
// Generates the graph's snapshot and builds its layout graph.
Result<SuiteInput> make_input(const SuiteGraph& g);

}  // namespace r1::conformance
