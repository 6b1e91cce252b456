// Exports an epoch as a 3D Gaussian Splatting .ply (R1-RND-095..097).
#include "r1/reference/ply_export.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "r1/fixedpoint/hemera.hpp"
#include "r1/format/bytes.hpp"

namespace r1 {

namespace {

static_assert(std::numeric_limits<float>::is_iec559, "the .ply rows are IEEE binary32");

constexpr std::size_t kRestCoefficients = 45;  // SH degrees 1..3, three channels: 3 * 15

std::string ply_header(std::size_t n, const hemera::Digest& snapshot) {
  std::string h = "ply\nformat binary_little_endian 1.0\n";
  h += "comment r1 epoch of snapshot " + hemera::to_hex(snapshot) + "\n";
  h += "element vertex " + std::to_string(n) + "\n";
  std::vector<std::string> names = {"x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2"};
  for (std::size_t k = 0; k < kRestCoefficients; ++k) names.push_back("f_rest_" + std::to_string(k));
  for (const char* s : {"opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"}) names.push_back(s);
  for (const auto& s : names) h += "property float " + s + "\n";
  h += "end_header\n";
  return h;
}

// Q32 to the nearest float: int64 -> float rounds once (to nearest, ties to even), and the scale
// by 2^-32 is exact for every Q32 magnitude, so there is no double rounding through fp64.
float q32_float(Q32 q) { return static_cast<float>(q.raw) * 0x1p-32f; }

}  // namespace

std::string ply_bytes(const Epoch& e) {
  const std::size_t n = e.frame.position.size();
  std::string out = ply_header(n, e.snapshot_digest);
  out.reserve(out.size() + n * kPlyFloatsPerVertex * 4);
  // The same for every particle: logit of the fixed opacity.
  const float opacity = static_cast<float>(std::log(kSplatOpacity / (1 - kSplatOpacity)));
  for (std::size_t i = 0; i < n; ++i) {
    for (Q32 c : e.frame.position[i]) format::put_f32(out, q32_float(c));
    for (int k = 0; k < 3; ++k) format::put_f32(out, 0.0f);  // normals: unused by splat viewers
    for (std::uint8_t c : e.encoding.color[i]) format::put_f32(out, static_cast<float>((c / 255.0 - 0.5) / kShC0));
    for (std::size_t k = 0; k < kRestCoefficients; ++k) format::put_f32(out, 0.0f);  // no view dependence
    format::put_f32(out, opacity);
    // Isotropic: the particle is a sphere. The clamp only guards ln(0) (see kSplatMinSigma).
    const double sigma = std::max(kSplatSigmaPerRadius * e.encoding.radius[i].to_double(), kSplatMinSigma);
    const float scale = static_cast<float>(std::log(sigma));
    for (int k = 0; k < 3; ++k) format::put_f32(out, scale);
    for (float r : {1.0f, 0.0f, 0.0f, 0.0f}) format::put_f32(out, r);  // quaternion (w, x, y, z): identity
  }
  return out;
}

}  // namespace r1
