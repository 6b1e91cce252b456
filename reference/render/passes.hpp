// The frame's passes (spec/render.md R1-RND-075..077): the reference frame of renderer.hpp as
// cull -> impostors -> edges -> splats -> field and composite -> labels, with the values that flow
// between them public, so that a backend can run the passes it accelerates and conformance can
// compare a pass's output with the reference's one by one. The first seam is the opaque impostor
// pass (T1/T2): its input is the list of impostors, its output the opaque layer.
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <span>
#include <vector>

#include "cull.hpp"
#include "scene.hpp"
#include "view.hpp"
#include "r1/spec/status.hpp"

namespace r1::render {

// The opaque layer: per pixel (row-major, width x height) the nearest opaque hit's ray parameter
// (infinity for none), its shaded linear colour and what owns it (a particle index, -2 for an
// edge tube, -1 for none).
struct OpaqueLayer {
  static constexpr std::int64_t kNone = -1, kEdge = -2;
  int width = 0, height = 0;
  std::vector<double> t;
  std::vector<Vec3> color;
  std::vector<std::int64_t> owner;
  OpaqueLayer(int w, int h)
      : width(w),
        height(h),
        t(static_cast<std::size_t>(w) * h, std::numeric_limits<double>::infinity()),
        color(static_cast<std::size_t>(w) * h),
        owner(static_cast<std::size_t>(w) * h, kNone) {}
};

// One T1/T2 analytic impostor (T0 draws as T1 until the content tier exists, R1-RND-024): the
// particle, its shape, centre, bounding radius and colour, and the pixel rectangle that holds
// every pixel whose centre can see it (project_box of its bounding cube).
struct Impostor {
  std::uint32_t particle = 0;
  Shape shape = Shape::kSphere;
  Vec3 center;
  double radius = 0;
  Vec3 color;
  Rect rect;
};

// The impostors of a frame, in ascending particle order (the culled list's order): every visible
// particle at T2 or above whose rectangle is not empty.
std::vector<Impostor> impostor_list(const Scene& s, const View& v, const CameraFrame& f, const CullResult& culled);

// The headlight shading of every opaque surface: ambient 0.25 plus 0.75 Lambert toward the
// camera (R1-RND-061).
Vec3 headlight(const Vec3& albedo, const Vec3& normal, const Vec3& dir);

// The reference impostor pass (R1-RND-030..036, 061): for each impostor in list order and each
// pixel of its rectangle, the ray through the pixel centre hits the shape nearer than the layer's
// t, which then takes the hit's t, shaded colour and the particle. So the nearest hit wins and an
// exact tie goes to the earlier impostor.
void draw_impostors(std::span<const Impostor> impostors, const View& v, const CameraFrame& f, OpaqueLayer& layer);

// A backend's impostor pass: the same contract as draw_impostors on a fresh layer (R1-RND-076).
using ImpostorPass = std::function<Status(std::span<const Impostor>, const View&, const CameraFrame&, OpaqueLayer&)>;

// The passes a backend runs in place of the reference's; an empty member is the reference's.
struct FramePasses {
  ImpostorPass impostors;
};

}  // namespace r1::render
