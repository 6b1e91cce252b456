// The view of a frame as a stage-boundary value (R-1.0 9.1, 6; spec/render.md R1-RND-001..004,
// R1-BKD-014): a 6DOF pinhole camera, the image size, the tier thresholds and the frame switches.
// Reading, validating and making views is the renderer's (reference/render/view.hpp).
#pragma once

#include <array>
#include <cstdint>

#include "r1/spec/vec3.hpp"

namespace r1::render {

// A unit quaternion (w, x, y, z) rotating camera coordinates into scene coordinates. The camera
// looks along its -z axis with +y up and +x right (the OpenGL convention).
struct Quat {
  double w = 1, x = 0, y = 0, z = 0;
  // v + 2 w (q x v) + q x (2 q x v): the same operations in the same order on every backend.
  Vec3 rotate(const Vec3& v) const {
    const Vec3 q{x, y, z};
    const Vec3 t = cross(q, v) * 2.0;
    return v + t * w + cross(q, t);
  }
};

struct Camera {
  Vec3 position{0, 0, 2500};
  Quat orientation;      // unit
  double fov_deg = 50;   // vertical field of view, [30, 110]
};

// Tier thresholds in screen-pixel diameters (R-1.0 6 defaults) and the T3/T-inf handoff band.
struct Tiers {
  double t0 = 200, t1 = 40, t2 = 8, t3 = 1;
  double band = 0.5;  // epsilon of 6.5: [t3 - band, t3 + band] draws as both T3 and T-inf
};

struct View {
  Camera camera;
  int width = 1280, height = 720;
  Tiers tiers;
  double time = 0;                          // seconds, for the edge flow animation (R-1.0 8.2)
  std::array<std::uint8_t, 3> background{10, 12, 18};  // display sRGB behind the scene
  bool edges = true, labels = true, field = true;
  double splat_stretch = 0;                 // 0 = isotropic splats; s > 0 stretches along grad u5 (R1-RND-042)
};

}  // namespace r1::render
