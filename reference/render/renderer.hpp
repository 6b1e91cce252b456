// The reference frame (spec/render.md R1-RND-060..079): cull, tiers, opaque impostors and edge
// tubes with a depth buffer, T3 splats and the T-infinity field composited front to back in
// linear light, T1 labels. fp64, single-threaded, deterministic: the oracle accelerated
// renderers are measured against.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "cull.hpp"
#include "field.hpp"
#include "image.hpp"
#include "scene.hpp"
#include "view.hpp"
#include "r1/spec/progress.hpp"

namespace r1::render {

struct FrameStats {
  std::array<std::uint64_t, 5> tier_count{};  // visible particles per tier (T0..T-inf)
  std::uint64_t visible = 0, culled_nodes = 0, nodes_tested = 0;
  std::uint64_t edges_considered = 0;  // layout edges with an endpoint at T2 or above
  std::uint64_t edges_drawn = 0;       // tube instances after bundling
  std::uint64_t splats = 0, labels = 0;
  std::uint64_t field_candidates = 0, field_evaluations = 0;
  // Seconds per stage.
  double cull_s = 0, impostor_s = 0, edge_s = 0, splat_s = 0, field_s = 0, label_s = 0, total_s = 0;
};

// Options that do not belong in a view file.
struct RenderOptions {
  FieldParams field;
  bool timings = true;
};

// Renders `view` of the scene into linear premultiplied RGBA (+ the field's flow channels).
Result<Image> render_frame(const Scene& scene, const View& view, const RenderOptions& options, FrameStats* stats,
                           const ProgressFn& progress = {});

// Edge bundling alone (R1-RND-064), for the README's reduction table and tests.
struct BundleStats {
  std::uint64_t considered = 0, drawn = 0;
};
BundleStats bundle_counts(const Scene& scene, const View& view);

}  // namespace r1::render
