// T-infinity without the neural field (R-1.0 7.2, 7.3, 9.5; spec/render.md R1-RND-050..058): the
// ground-truth field of section 7.3 evaluated through the hierarchy, and the ray march.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "cull.hpp"
#include "r1/spec/render_options.hpp"
#include "scene.hpp"
#include "view.hpp"

namespace r1::render {

struct FieldValue {
  double density = 0;  // rho, per scene unit
  Vec3 color;          // linear light
  Vec3 flow;           // mean-shift vector (R1-RND-053), scene units
  double weight = 0;   // sum of weight * kernel (for tests)
  std::uint64_t kernels = 0;  // kernels evaluated (nodes and particles; for tests)
};

// A node as the field sees it this frame (R1-RND-054): over its members with field weight > 0,
// their weight sum (0: skip the node), weighted centroid and colour, largest distance from it, and
// the colour's spread.
struct NodeField {
  double weight = 0;
  Vec3 centroid, color;
  double extent = 0;
  // The colour's spread over the same members and weights (R1-RND-055), held by the scene's node
  // or the frame's `mixed_spread`; null for a node of weight 0.
  const ColourSpread* spread = nullptr;
};

class NeuralInference;

// What the field of one frame depends on (R1-RND-059). Nodes are classified from the top by
// far_class: a kFar node's members all have weight exactly 1 x n phi, so its aggregates are the
// scene's (NodeData, computed once per epoch) and nothing below it is visited; a kBehind node
// weighs 0; only kMixed nodes get aggregates of their own, computed over their members. A pure
// far view therefore costs the top of the hierarchy, not |P|.
struct FieldFrame {
  static constexpr std::uint32_t kFarSlot = 0xFFFFFFFFu, kBehindSlot = 0xFFFFFFFEu;
  const Scene* scene = nullptr;
  CameraFrame frame;
  Vec3 camera;
  Tiers tiers;
  // Per level, per node: kFarSlot, kBehindSlot or an index into `mixed`. A level is filled only
  // when some node of it was classified (the top level, and the children of kMixed and kBehind
  // nodes); an empty level, or an entry left at kFarSlot, lies below a kFar node.
  std::array<std::vector<std::uint32_t>, kLevels> slot;
  std::vector<NodeField> mixed;             // their spreads are `mixed_spread`'s (node() points at them)
  std::vector<ColourSpread> mixed_spread;   // beside `mixed`
  // Per kMixed level-0 node, its members with field weight > 0 in member order:
  // members[member_range[k].first .. member_range[k].second) for mixed[k].
  struct Member {
    Vec3 position, color;
    double weight = 0;
  };
  std::vector<std::pair<std::uint32_t, std::uint32_t>> member_range;
  std::vector<Member> members;
  // Per 16 x 16 pixel tile of the view (row-major), the top-level nodes a ray through it may
  // meet (R1-RND-057): those whose ball, grown by the frame's widest kernel, projects onto the tile
  // with a pixel to spare. A ray walks only its tile's list, so a pixel far from the scene tests
  // nothing. Empty: every ray walks every top-level node (the same samples, more tests).
  static constexpr int kTile = 16;
  int width = 0, tiles_x = 0;
  std::vector<std::vector<std::uint32_t>> top_by_tile;
  double tau_cam = 0;   // 9.5: tau0 (1 + |camera - centroid| / R_scene)^2
  double t_far = 0;     // farthest scene point from the camera (grown by the widest kernel)
  FieldParams params;
  // Of the training targets' far-field frame (far_field_frame with FarLayout::kOctree): the
  // particles' octree the walk runs over instead of the hierarchy. Null in the frames of a view.
  struct FarTree;
  std::shared_ptr<const FarTree> far_tree;
  // The scene's neural field made ready for the frame's evaluations (R1-NRF-031), when it has one.
  std::shared_ptr<const NeuralInference> neural;

  // Particle p's field weight: its T-infinity weight (1 below the handoff band, 0 above it, linear
  // across it, R1-RND-045) times n phi(p).
  double weight(std::uint32_t p) const;
  // Node `id` of `level` this frame.
  NodeField node(int level, std::uint32_t id) const;
};

// The tree the training targets' walk runs over (R1-NRF-014): a spatial octree of the particles,
// flat. `nodes[0, roots)` are the top, every inner node's children are the run
// `nodes[first, first + count)` and a leaf's members the run `members[first, first + count)`.
// Its nodes are compact in space, so a walk takes more of the scene whole within the same bound
// than the walk over the hierarchy's clusters. Nodes carry their members' mean colour alone.
struct FieldFrame::FarTree {
  struct Node {
    Vec3 centroid;
    double extent = 0, weight = 0;  // weight n phi of the members
    std::uint32_t first = 0;
    std::uint32_t count : 31 = 0;
    std::uint32_t leaf : 1 = 0;
  };
  std::uint32_t roots = 0;
  std::vector<Node> nodes;
  std::vector<Vec3> color;  // beside `nodes`: read only by accepted nodes
  std::vector<Member> members;  // field weight > 0
};

double tinf_weight(double s, const Tiers& t);
// The frame's field parameters are `p` with the cut of R1-RND-054 for the scene's particle count
// (field_cutoff).
FieldFrame make_field_frame(const Scene& s, const View& v, const CameraFrame& f, const FieldParams& p = {});
// R1-RND-054's cut for n particles: `cutoff` (5), or more where the kernels it would drop add up
// to over 1/32 of a mean particle's weight: max(cutoff, sqrt(2 ln(32 n))).
double field_cutoff(double cutoff, std::uint32_t n);

// Kernel width at ray distance t (R1-RND-051): sqrt(tau_cam t / t_far), at least half a pixel.
double field_sigma(const FieldFrame& ff, double t);

// The field at x with kernel width sigma: exactly (every particle) or through the hierarchy.
FieldValue field_exact(const FieldFrame& ff, const Vec3& x, double sigma);
FieldValue field_hierarchical(const FieldFrame& ff, const Vec3& x, double sigma);
// The same field with R1-RND-060's acceptance graded by distance: a node farther from x may be
// wider than theta sigma, as far as the kernel's curvature there allows, within the same bound
// (field_error_bound). The neural field's training targets; frames keep field_hierarchical.
FieldValue field_graded(const FieldFrame& ff, const Vec3& x, double sigma);
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
  std::uint64_t neural = 0;       // samples the neural field drew (R1-NRF-031)
};

// The stratified, jittered march of 7.2 along `ray` up to t_max (an opaque hit), samples
// written in ray order. `pixel` = y * width + x of the view: it keys the counter-based jitter
// (r1::rng::uniform_double, R1-RND-056) and names the tile whose top-level nodes the walk starts
// from; `ray` is that pixel's ray (pixel_ray at its centre).
void march_field(const FieldFrame& ff, const Ray& ray, double t_max, std::uint64_t pixel, std::vector<FieldSample>& out,
                 FieldRayStats* stats = nullptr);

}  // namespace r1::render
