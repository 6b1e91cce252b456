// T-infinity without the neural field (R-1.0 7.2, 7.3, 9.5; spec/render.md R1-RND-050..058): the
// ground-truth field of section 7.3 evaluated through the hierarchy, and the ray march.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "cull.hpp"
#include "scene.hpp"
#include "view.hpp"

namespace r1::render {

struct FieldParams {
  int samples = 128;         // N of 7.2
  double kappa = 0.25;       // density gain (R1-RND-052)
  double cutoff = 4.0;       // nodes farther than cutoff * sigma are skipped (R1-RND-054)
  double theta = 0.25;       // a node with extent <= theta * sigma is one aggregate (R1-RND-054)
  double stop = 1e-3;        // the march ends when the field's transmittance falls below this
};

struct FieldValue {
  double density = 0;  // rho, per scene unit
  Vec3 color;          // linear light
  Vec3 flow;           // mean-shift vector (R1-RND-053), scene units
  double weight = 0;   // sum of weight * kernel (for tests)
};

// What the field of one frame depends on: per particle its T-inf weight (1 below the handoff band,
// 0 above it, linear across it, R1-RND-045) and per node whether every member has weight 1.
struct FieldFrame {
  const Scene* scene = nullptr;
  std::vector<double> weight;                            // per particle
  // Per node, over its members with field weight > 0 this frame (R1-RND-054): the weight sum (0:
  // skip the node), their weighted centroid and colour, and their largest distance from it.
  std::array<std::vector<double>, kLevels> node_weight;
  std::array<std::vector<Vec3>, kLevels> node_centroid, node_color;
  std::array<std::vector<double>, kLevels> node_extent;
  // Per level-0 node, its members with field weight > 0, stored together in member order:
  // members[member_begin[id] .. member_begin[id + 1]).
  struct Member {
    Vec3 position, color;
    double weight = 0;
  };
  std::vector<std::uint32_t> member_begin;
  std::vector<Member> members;
  double tau_cam = 0;   // 9.5: tau0 (1 + |camera - centroid| / R_scene)^2
  double t_far = 0;     // farthest scene point from the camera (grown by the widest kernel)
  double focal_px = 1;
  FieldParams params;
};

double tinf_weight(double s, const Tiers& t);
FieldFrame make_field_frame(const Scene& s, const View& v, const CameraFrame& f, const FieldParams& p = {});

// Kernel width at ray distance t (R1-RND-051): sqrt(tau_cam t / t_far), at least half a pixel.
double field_sigma(const FieldFrame& ff, double t);

// The field at x with kernel width sigma: exactly (every particle) or through the hierarchy.
FieldValue field_exact(const FieldFrame& ff, const Vec3& x, double sigma);
FieldValue field_hierarchical(const FieldFrame& ff, const Vec3& x, double sigma);
// The documented bound on |rho_hier - rho_exact| (R1-RND-055) at this sigma.
double field_error_bound(const FieldFrame& ff, double sigma);

// One composited field sample along a ray.
struct FieldSample {
  double t = 0;      // ray parameter
  double alpha = 0;  // 1 - exp(-rho delta)
  Vec3 color, flow;
};

struct FieldRayStats {
  std::uint64_t walked = 0;       // nodes the candidate walk tested
  std::uint64_t candidates = 0;   // nodes the march considered (R1-RND-057)
  std::uint64_t samples = 0;      // samples evaluated (some node within reach of its interval)
  std::uint64_t evaluations = 0;  // kernel evaluations over all samples
};

// The stratified, jittered march of 7.2 along `ray` up to t_max (an opaque hit), samples
// written in ray order. `pixel` keys the counter-based jitter (r1::rng::uniform_double, R1-RND-056).
void march_field(const FieldFrame& ff, const Ray& ray, double t_max, std::uint64_t pixel, std::vector<FieldSample>& out,
                 FieldRayStats* stats = nullptr);

}  // namespace r1::render
