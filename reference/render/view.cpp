// The camera, projection and view files (R1-RND-001..012).
#include "view.hpp"

#include <charconv>
#include <cmath>
#include <sstream>

#include "r1/reference/input_file.hpp"
#include "snapshot/toml_subset.hpp"

namespace r1::render {

namespace {


std::string decimal(double v) {
  std::ostringstream o;
  o.precision(17);
  o << v;
  std::string s = o.str();
  // Only plain decimals read back (R1-RND-005); the view values never need an exponent, but keep
  // the writer honest if one appears.
  if (s.find_first_of("eE") != std::string::npos) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.6f", v);
    s = buf;
  }
  return "\"" + s + "\"";
}

}  // namespace

CameraFrame camera_frame(const View& v) {
  CameraFrame f;
  f.right = v.camera.orientation.rotate({1, 0, 0});
  f.up = v.camera.orientation.rotate({0, 1, 0});
  f.forward = v.camera.orientation.rotate({0, 0, -1});
  f.tan_half_fov = std::tan(v.camera.fov_deg * kPi / 360.0);
  f.focal_px = (v.height * 0.5) / f.tan_half_fov;
  return f;
}

Ray pixel_ray(const View& v, const CameraFrame& f, double px, double py) {
  // Pixel centres sit at integer + 0.5; the image plane is at unit depth.
  const double sx = (px - v.width * 0.5) / f.focal_px;
  const double sy = (v.height * 0.5 - py) / f.focal_px;
  return {v.camera.position, normalize(f.forward + f.right * sx + f.up * sy)};
}

Projected project(const View& v, const CameraFrame& f, const Vec3& p) {
  const Vec3 rel = p - v.camera.position;
  Projected out;
  out.depth = dot(rel, f.forward);
  if (out.depth <= 0) return out;
  out.px = v.width * 0.5 + dot(rel, f.right) / out.depth * f.focal_px;
  out.py = v.height * 0.5 - dot(rel, f.up) / out.depth * f.focal_px;
  return out;
}

Result<Quat> look_at(const Vec3& eye, const Vec3& target, const Vec3& up) {
  const Vec3 fwd = target - eye;
  if (!(length(fwd) > 0)) return Status::input("look-at: the eye and the target coincide");
  const Vec3 f = normalize(fwd);
  const Vec3 side = cross(f, up);
  if (!(length(side) > 1e-9 * length(up))) return Status::input("look-at: the up vector is parallel to the view direction");
  const Vec3 r = normalize(side);
  const Vec3 u = cross(r, f);
  // Columns of the camera-to-scene rotation: x -> r, y -> u, z -> -f. Shepperd's method.
  const double m00 = r.x, m01 = u.x, m02 = -f.x;
  const double m10 = r.y, m11 = u.y, m12 = -f.y;
  const double m20 = r.z, m21 = u.z, m22 = -f.z;
  const double trace = m00 + m11 + m22;
  Quat q;
  if (trace > 0) {
    const double s = std::sqrt(trace + 1.0) * 2;
    q = {0.25 * s, (m21 - m12) / s, (m02 - m20) / s, (m10 - m01) / s};
  } else if (m00 > m11 && m00 > m22) {
    const double s = std::sqrt(1.0 + m00 - m11 - m22) * 2;
    q = {(m21 - m12) / s, 0.25 * s, (m01 + m10) / s, (m02 + m20) / s};
  } else if (m11 > m22) {
    const double s = std::sqrt(1.0 + m11 - m00 - m22) * 2;
    q = {(m02 - m20) / s, (m01 + m10) / s, 0.25 * s, (m12 + m21) / s};
  } else {
    const double s = std::sqrt(1.0 + m22 - m00 - m11) * 2;
    q = {(m10 - m01) / s, (m02 + m20) / s, (m12 + m21) / s, 0.25 * s};
  }
  return q;
}

Status validate_view(View& v, const std::string& where) {
  const auto bad = [&](const std::string& why) { return Status::input(where + ": " + why); };
  const Camera& c = v.camera;
  for (double d : {c.position.x, c.position.y, c.position.z, c.orientation.w, c.orientation.x, c.orientation.y,
                   c.orientation.z, c.fov_deg, v.time, v.splat_stretch, v.tiers.t0, v.tiers.t1, v.tiers.t2, v.tiers.t3, v.tiers.band})
    if (!std::isfinite(d)) return bad("every number must be finite");
  if (std::fabs(c.position.x) > 1e9 || std::fabs(c.position.y) > 1e9 || std::fabs(c.position.z) > 1e9)
    return bad("camera position beyond 1e9 scene units");
  Quat& q = v.camera.orientation;
  const double norm = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  if (std::fabs(norm - 1) > 1e-6) return bad("orientation must be a unit quaternion (w, x, y, z)");
  q = {q.w / norm, q.x / norm, q.y / norm, q.z / norm};
  if (c.fov_deg < 30 || c.fov_deg > 110) return bad("fov must lie in [30, 110] degrees (R-1.0 9.1)");
  if (v.width < 1 || v.height < 1 || v.width > 16384 || v.height > 16384) return bad("image size must be 1..16384 per side");
  const Tiers& t = v.tiers;
  if (!(0 < t.t3 && t.t3 < t.t2 && t.t2 < t.t1 && t.t1 < t.t0)) return bad("tier thresholds need 0 < t3 < t2 < t1 < t0");
  if (!(t.band >= 0 && t.band < t.t3)) return bad("the handoff band needs 0 <= band < t3");
  if (v.time < 0 || v.time > 1e7) return bad("time must lie in [0, 1e7] seconds");
  if (v.splat_stretch < 0 || v.splat_stretch > 16) return bad("splat_stretch must lie in [0, 16]");
  return Status::ok();
}

Result<View> parse_view(std::string_view text, const std::string& name) {
  R1_ASSIGN(const toml::table root, toml_subset::parse(text, name));
  View v;
  const auto at = [&](const toml::node& n) { return name + ":" + std::to_string(n.source().begin.line); };
  const auto num = [&](const toml::node& n, double& out) -> Status {
    const auto d = toml_subset::decimal(n);
    if (!d) return Status::input(at(n) + ": expected a number (an integer or a decimal string such as \"12.5\")");
    out = *d;
    return Status::ok();
  };
  const auto vec = [&](const toml::node& n, std::size_t k, double* out) -> Status {
    const auto* a = n.as_array();
    if (!a || a->size() != k) return Status::input(at(n) + ": expected an array of " + std::to_string(k) + " numbers");
    for (std::size_t i = 0; i < k; ++i) R1_TRY(num(*a->get(i), out[i]));
    return Status::ok();
  };
  const auto integer = [&](const toml::node& n, int& out, std::int64_t lo, std::int64_t hi) -> Status {
    const auto* i = n.as_integer();
    if (!i || i->get() < lo || i->get() > hi)
      return Status::input(at(n) + ": expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    out = static_cast<int>(i->get());
    return Status::ok();
  };
  const auto boolean = [&](const toml::node& n, bool& out) -> Status {
    const auto* b = n.as_boolean();
    if (!b) return Status::input(at(n) + ": expected true or false");
    out = b->get();
    return Status::ok();
  };
  bool has_orientation = false, has_look = false;
  double target[3] = {0, 0, 0}, up[3] = {0, 0, 1};
  for (auto&& [key, node] : root) {
    const std::string k(key.str());
    const auto* t = node.as_table();
    if (!t) return Status::input(name + ":" + std::to_string(key.source().begin.line) + ": unknown key '" + k.substr(0, 80) +
                                 "' (tables: camera, image, tiers, render)");
    for (auto&& [fkey, f] : *t) {
      const std::string fk(fkey.str());
      Status st = Status::input(at(f) + ": unknown field '" + fk.substr(0, 80) + "' in [" + k + "]");
      if (k == "camera") {
        double q[4];
        if (fk == "position") { double p[3]; st = vec(f, 3, p); v.camera.position = {p[0], p[1], p[2]}; }
        if (fk == "orientation") { st = vec(f, 4, q); v.camera.orientation = {q[0], q[1], q[2], q[3]}; has_orientation = true; }
        if (fk == "look_at") { st = vec(f, 3, target); has_look = true; }
        if (fk == "up") st = vec(f, 3, up);
        if (fk == "fov") st = num(f, v.camera.fov_deg);
      } else if (k == "image") {
        if (fk == "width") st = integer(f, v.width, 1, 16384);
        if (fk == "height") st = integer(f, v.height, 1, 16384);
        if (fk == "background") {
          const auto* s = f.as_string();
          unsigned rgb = 0;
          if (s && s->get().size() == 7 && s->get()[0] == '#' &&
              std::from_chars(s->get().data() + 1, s->get().data() + 7, rgb, 16).ptr == s->get().data() + 7) {
            v.background = {static_cast<std::uint8_t>(rgb >> 16), static_cast<std::uint8_t>(rgb >> 8), static_cast<std::uint8_t>(rgb)};
            st = Status::ok();
          } else {
            st = Status::input(at(f) + ": background must be \"#rrggbb\"");
          }
        }
      } else if (k == "tiers") {
        if (fk == "t0") st = num(f, v.tiers.t0);
        if (fk == "t1") st = num(f, v.tiers.t1);
        if (fk == "t2") st = num(f, v.tiers.t2);
        if (fk == "t3") st = num(f, v.tiers.t3);
        if (fk == "band") st = num(f, v.tiers.band);
      } else if (k == "render") {
        if (fk == "time") st = num(f, v.time);
        if (fk == "edges") st = boolean(f, v.edges);
        if (fk == "labels") st = boolean(f, v.labels);
        if (fk == "field") st = boolean(f, v.field);
        if (fk == "splat_stretch") st = num(f, v.splat_stretch);
      } else {
        st = Status::input(name + ":" + std::to_string(key.source().begin.line) + ": unknown table [" + k.substr(0, 80) +
                           "] (camera, image, tiers, render)");
      }
      R1_TRY(st);
    }
  }
  if (has_orientation && has_look) return Status::input(name + ": give camera.orientation or camera.look_at, not both");
  if (has_look) {
    R1_ASSIGN(v.camera.orientation, look_at(v.camera.position, {target[0], target[1], target[2]}, {up[0], up[1], up[2]}));
  }
  R1_TRY(validate_view(v, name));
  return v;
}

Result<View> read_view_file(const std::string& path) {
  R1_ASSIGN(auto file, InputFile::open(path));
  return parse_view(file->text(), file->name());
}

std::string view_toml(const View& v) {
  const auto& c = v.camera;
  std::string o = "# r1 view (spec/render.md R1-RND-005)\n[camera]\n";
  o += "position = [" + decimal(c.position.x) + ", " + decimal(c.position.y) + ", " + decimal(c.position.z) + "]\n";
  o += "orientation = [" + decimal(c.orientation.w) + ", " + decimal(c.orientation.x) + ", " + decimal(c.orientation.y) + ", " +
       decimal(c.orientation.z) + "]\n";
  o += "fov = " + decimal(c.fov_deg) + "\n\n[image]\nwidth = " + std::to_string(v.width) + "\nheight = " + std::to_string(v.height) + "\n";
  char bg[8];
  std::snprintf(bg, sizeof bg, "#%02x%02x%02x", v.background[0], v.background[1], v.background[2]);
  o += std::string("background = \"") + bg + "\"\n\n[tiers]\n";
  o += "t0 = " + decimal(v.tiers.t0) + "\nt1 = " + decimal(v.tiers.t1) + "\nt2 = " + decimal(v.tiers.t2) + "\nt3 = " +
       decimal(v.tiers.t3) + "\nband = " + decimal(v.tiers.band) + "\n\n[render]\n";
  o += "time = " + decimal(v.time) + "\nedges = " + (v.edges ? "true" : "false") + "\nlabels = " + (v.labels ? "true" : "false") +
       "\nfield = " + (v.field ? "true" : "false") + "\nsplat_stretch = " + decimal(v.splat_stretch) + "\n";
  return o;
}

std::vector<View> orbit_views(const View& base, const Vec3& center, double distance, int k) {
  std::vector<View> out;
  const double elevation = 20.0 * kPi / 180.0;
  for (int i = 0; i < k; ++i) {
    const double az = 2.0 * kPi * i / k;
    View v = base;
    v.camera.position = center + Vec3{std::cos(az) * std::cos(elevation), std::sin(az) * std::cos(elevation), std::sin(elevation)} * distance;
    v.camera.orientation = *look_at(v.camera.position, center, {0, 0, 1});
    out.push_back(v);
  }
  return out;
}

}  // namespace r1::render
