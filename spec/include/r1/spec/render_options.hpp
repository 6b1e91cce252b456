// What the frame stage is asked and what it reports (spec/render.md R1-RND-050..058, R1-RND-090,
// R1-BKD-014): the T-infinity field parameters, the render options and the frame statistics, as
// stage-boundary values every backend shares.
#pragma once

#include <array>
#include <cstdint>
#include <string_view>

namespace r1::render {

struct FieldParams {
  int samples = 128;         // N of 7.2
  double kappa = 0.25;       // density gain (R1-RND-052)
  double cutoff = 5.0;       // nodes farther than cutoff * sigma are skipped (R1-RND-054)
  double theta = 0.25;       // a node with extent <= theta * sigma is one aggregate (R1-RND-054)
  double stop = 1e-3;        // the march ends when the field's transmittance falls below this
  // The neural field's literal march (R-1.0 7.2, R1-NRF-033): every pixel's `samples` samples
  // over its chord through the field's ball, no node walked, no sample skipped, no early end.
  // Its work is the image's pixels times the samples, whatever the graph (P_RENDER_TINF).
  bool literal = false;
};

// Options that do not belong in a view file.
struct RenderOptions {
  FieldParams field;
  bool timings = true;
  // The bytes of a trained T-infinity field of this epoch (field.nrf, spec/neural.md R1-NRF-030)
  // to draw pure T-infinity frames with; empty: the analytic field. The caller keeps them alive.
  std::string_view neural_field;
};

struct FrameStats {
  std::array<std::uint64_t, 5> tier_count{};  // visible particles per tier (T0..T-inf)
  std::uint64_t visible = 0, culled_nodes = 0, nodes_tested = 0;
  std::uint64_t edges_in_view = 0;     // layout edges with both endpoints visible
  std::uint64_t edges_considered = 0;  // layout edges with an endpoint at T2 or above
  std::uint64_t edges_drawn = 0;       // tube instances after bundling
  std::uint64_t splats = 0, labels = 0;
  std::uint64_t content = 0;  // T0 particles drawn with their content (R1-RND-135)
  std::uint64_t field_walked = 0, field_candidates = 0, field_samples = 0, field_evaluations = 0;
  std::uint64_t field_neural = 0;  // samples the neural field drew (R1-NRF-031)
  // Pixels a backend's field and composite pass left to the host (R1-RND-078).
  std::uint64_t host_pixels = 0;
  // Rays of a neural frame with more candidate nodes than a backend's pass holds, walked again at
  // each sample on the device instead (R1-BKD-076).
  std::uint64_t field_rewalked = 0;
  // Seconds per stage.
  double cull_s = 0, impostor_s = 0, edge_s = 0, splat_s = 0, field_s = 0, label_s = 0, total_s = 0;
};

}  // namespace r1::render
