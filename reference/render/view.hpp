// The view of a frame (R-1.0 9.1, 6; spec/render.md R1-RND-001..012): a 6DOF pinhole camera,
// the image size, the tier thresholds and the frame options, read from a small TOML view file or
// made on the command line (look-at, orbit).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "r1/spec/status.hpp"
#include "r1/spec/vec3.hpp"
#include "r1/spec/view.hpp"

namespace r1::render {

// The camera basis in scene coordinates.
struct CameraFrame {
  Vec3 right, up, forward;  // forward = -z of the camera
  double tan_half_fov = 0;  // tan(fov / 2)
  double focal_px = 0;      // (height / 2) / tan(fov / 2): pixels per unit at unit depth
};
CameraFrame camera_frame(const View& v);

// The primary ray through the centre of pixel (x, y) (plus an offset in pixels), unit direction.
Ray pixel_ray(const View& v, const CameraFrame& f, double px, double py);

// Depth along the view axis and pixel coordinates of a scene point (depth <= 0: behind).
struct Projected {
  double depth = 0;
  double px = 0, py = 0;
};
Projected project(const View& v, const CameraFrame& f, const Vec3& p);

// The quaternion of a camera at `eye` looking at `target` with `up` roughly up. Fails when eye
// and target coincide or up is parallel to the view direction.
Result<Quat> look_at(const Vec3& eye, const Vec3& target, const Vec3& up);

// Checks a view: finite values, unit-length orientation (renormalised if within 1e-6), fov in
// [30, 110], image 1..16384 per side, 0 < t3 < t2 < t1 < t0, 0 <= band < t3. `where` prefixes errors.
Status validate_view(View& v, const std::string& where);

// Reads a view file (R1-RND-005): TOML of r1's subset, decimals as strings ("12.5") or integers.
Result<View> read_view_file(const std::string& path);
Result<View> parse_view(std::string_view text, const std::string& name);
std::string view_toml(const View& v);  // writes a view file that reads back to `v`

// K views on a circle around `center` (R1-RND-007): radius `distance`, elevation 20 degrees,
// each looking at the centre, azimuths 360 k / K degrees starting on +x.
std::vector<View> orbit_views(const View& base, const Vec3& center, double distance, int k);

}  // namespace r1::render
