// The property library for backend authors (spec/testing.md R1-TEST-050..053; 12, 13, 15):
// RapidCheck properties that hold a candidate Backend against the reference on random graphs and
// random views, one result per property with RapidCheck's counterexample when it fails.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "r1/backends/backend.hpp"

namespace r1::conformance {

// The properties, in the order check_backend runs and returns them.
inline constexpr std::string_view kTopologyProperty = "topology bit-exact on random graphs";
inline constexpr std::string_view kPositionsProperty = "positions";
inline constexpr std::string_view kFocusProperty = "focus conservation";
inline constexpr std::string_view kLabelsProperty = "canonical labels";
inline constexpr std::string_view kNestingProperty = "hierarchy nesting";
inline constexpr std::string_view kPixelProperty = "pixel bound on random views";

struct PropertyOptions {
  // Cases per property. 25 small graphs run all six properties against the reference in a few
  // seconds; a failing property stops at its first counterexample (then shrinks it).
  int tests = 25;
  // RapidCheck's seed. 0: the seed of RC_PARAMS when it names one, else a fixed seed, so that a
  // run is reproducible by default; the seed used is in every result's message.
  std::uint64_t seed = 0;
  // Largest generated graph. 160 particles reach level 1 of the hierarchy with several level-0
  // clusters (16 children at most each) while an epoch stays in milliseconds.
  std::uint32_t max_particles = 160;
  // Runs the pixel property (rendering is the slowest part of a case).
  bool pixels = true;
  // The image of the pixel property. 64 x 36 (16:9) resolves the particles of a small graph
  // seen from 1500..6000 scene units at a cost of a few milliseconds a frame.
  int image_width = 64, image_height = 36;
};

struct PropertyResult {
  std::string name;
  bool passed = false;
  // Failed: RapidCheck's counterexample text (the `r1 gen` command of the graph, the view) and
  // the first failing assertion. Passed: a one-line summary (cases run, the largest deviation).
  std::string message;
};

// Runs every property (the pixel property only when options.pixels) with `candidate` against a
// fresh reference backend on the same inputs. RapidCheck prints nothing; its output is in the
// results. Each property's cases are the same graphs (same seed), each graph's two epochs are
// computed once per call and shared by the properties.
std::vector<PropertyResult> check_backend(backends::Backend& candidate, const PropertyOptions& options = {});

}  // namespace r1::conformance
