// r1 bench's chart (spec/bench.md R1-BEN-040): speedup per stage as bars, epoch time against
// |P| on log-log axes, drawn by hand into an image and written as a PNG.
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "r1/spec/status.hpp"

namespace r1::cli {

struct BenchChart {
  // Every backend, reference first; a backend's colour is its index here.
  std::vector<std::string> backends;
  // Left panel: bar groups (stage names) and, per backend other than the reference (backends[1..]),
  // its speedup per stage; NaN or <= 0 draws no bar.
  std::vector<std::string> stages;
  std::vector<std::vector<double>> speedup;  // [backend - 1][stage]
  std::string speedup_title;
  // Right panel: per backend, (particles, epoch seconds) points in input order.
  std::vector<std::vector<std::pair<double, double>>> scaling;
};

// Writes the chart to `png` (atomically). `warning` receives a note when the labels could not be
// drawn (no font); the chart is written without them.
Status write_bench_chart(const BenchChart& chart, const std::filesystem::path& png, std::string* warning);

}  // namespace r1::cli
