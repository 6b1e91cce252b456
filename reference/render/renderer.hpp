// The reference frame (spec/render.md R1-RND-060..079): cull, tiers, opaque impostors and edge
// tubes with a depth buffer, T3 splats and the T-infinity field composited front to back in
// linear light, T1 labels. fp64, single-threaded, deterministic: the oracle accelerated
// renderers are measured against.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "cull.hpp"
#include "field.hpp"
#include "image.hpp"
#include "passes.hpp"
#include "scene.hpp"
#include "view.hpp"
#include "r1/spec/progress.hpp"
#include "r1/spec/render_options.hpp"

namespace r1::render {

// Renders `view` of the scene into linear premultiplied RGBA (+ the field's flow channels), with
// the backend's passes where `passes` has them (passes.hpp) and the reference's elsewhere.
Result<Image> render_frame(const Scene& scene, const View& view, const RenderOptions& options, FrameStats* stats,
                           const ProgressFn& progress = {}, const FramePasses& passes = {});

// Edge bundling alone (R1-RND-064), for the README's reduction table and tests.
struct BundleStats {
  std::uint64_t in_view = 0;  // layout edges with both endpoints visible (what an unbundled renderer draws)
  std::uint64_t considered = 0, drawn = 0;
  double max_weight = 0;  // the largest combined weight of one tube
};
BundleStats bundle_counts(const Scene& scene, const View& view);

// The pixels an edge tube of radius rho between a and b may cover (R1-RND-065): per image row,
// the columns [x0, x1) whose centres lie within hw pixels of the projected segment, hw bounding
// the projection of any point within rho of the segment. The part of the segment nearer than
// 2 rho + kNear to the camera is left out; no rows when all of it is.
std::vector<RowSpan> tube_spans(const View& view, const CameraFrame& frame, const Vec3& a, const Vec3& b, double rho);

}  // namespace r1::render
