// The conformance harness (spec/conformance.md R1-CONF-030..064): runs a suite through a backend,
// writes and reads golden sets, and compares a backend's results with the reference's (fresh or
// golden) by the checks of section 15.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "r1/backends/backend.hpp"
#include "r1/conformance/compare.hpp"
#include "r1/conformance/suite.hpp"
#include "render/image_diff.hpp"

namespace r1::conformance {

// One suite graph through one backend: its epoch and the 16 views' display images.
struct GraphRun {
  std::string name;
  Epoch epoch;
  std::vector<std::vector<std::uint8_t>> display;  // per view: display sRGB, 3 bytes a pixel
  std::vector<render::Image> images;               // per view: linear RGBA (kept when asked)
  double epoch_s = 0, render_s = 0;
};

// Runs `g` through `b`: the epoch (default options: the genesis frame, no overlay) then, when
// `draw`, each view rendered and converted for display over the view's background.
Result<GraphRun> run_graph(backends::Backend& b, const Suite& suite, const SuiteGraph& g, bool keep_images,
                           const ProgressFn& progress = {}, bool draw = true);

// What a backend's results are compared with: the reference's topology, positions and display
// images for one graph, fresh or read from a golden set.
struct Expected {
  std::string name;
  Hierarchy hierarchy;  // topology only (parsed from topology bytes when golden)
  std::string topology;  // topology_bytes
  std::vector<std::array<Q32, 3>> positions;
  std::vector<std::vector<std::uint8_t>> display;
};
Expected expected_from(const GraphRun& reference_run);

struct GraphComparison {
  std::string name;
  bool topology_equal = false;
  std::string topology_difference;  // empty when equal
  bool positions_identical = false;  // same Q32 bytes
  PositionDeviation position;
  std::vector<render::DiffStats> views;  // per view
};
Result<GraphComparison> compare(const GraphRun& got, const Expected& want);

// ---- golden sets (R1-CONF-040..047) ---------------------------------------------------------

inline constexpr const char* kGoldenFormat = "r1-golden-1";

// Runs the suite with the reference backend and writes DIR atomically: suite.toml, manifest.json,
// and per graph NAME.topology.bin, NAME.positions.bin, NAME.VIEW.png and NAME.VIEW.exr; a file
// graph's files are copied to the paths the suite names (R1-CONF-043).
// `runs` receives the reference runs (for a change report against an earlier set).
// `backend` names the backend that made the runs in the manifest's generator line.
Status write_golden(const Suite& suite, const std::vector<GraphRun>& runs, const std::filesystem::path& dir,
                    const std::string& backend = "reference");

struct GoldenSet {
  Suite suite;
  std::vector<Expected> graphs;  // in suite order
};
// Reads DIR: its suite.toml, the manifest's digests checked against the files, topology, positions
// and PNG images; a file graph's copies checked by bytes and snapshot digest (R1-CONF-044). An
// input error names the file at fault.
Result<GoldenSet> read_golden(const std::filesystem::path& dir);

// One line per graph saying what differs between `got` and `want` ("same" when nothing does), for
// `r1 golden` and its regression test.
std::string describe(const GraphComparison& c);

// The golden regression rule (R1-CONF-045): topology and positions bit-identical, every view's
// mean CIEDE2000 within kPixelBound.
bool reproduces(const GraphComparison& c);

}  // namespace r1::conformance
