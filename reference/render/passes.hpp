// The frame's passes (spec/render.md R1-RND-075..078): the reference frame of renderer.hpp as
// cull -> impostors -> edges -> splats -> field and composite -> labels, with the values that flow
// between them public, so that a backend can run the passes it accelerates and conformance can
// compare a pass's output with the reference's one by one. Two are seams: the opaque impostor
// pass (T1/T2: impostor list -> opaque layer) and the field and composite pass (opaque layer,
// splats and field -> image).
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <span>
#include <vector>

#include "cull.hpp"
#include "field.hpp"
#include "image.hpp"
#include "scene.hpp"
#include "view.hpp"
#include "r1/spec/render_options.hpp"
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

// One T1/T2 analytic impostor (a T0 particle without content draws as T1, R1-RND-024): the
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
// particle at T2 or above whose rectangle is not empty, except T0 particles with content
// (R1-RND-130: the content pass draws them).
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

// Row y's pixels [x0, x1): a tube's capsule may cover them (tube_spans, renderer.hpp).
struct RowSpan {
  int y = 0, x0 = 0, x1 = 0;
};

// One edge tube as the frame draws it (R1-RND-063..066, 081): the axis a -> b (cut back at
// opened particles), radius rho, the flow strip's stripes and speed (cycles per second), the end
// colours, and the rows of pixels its capsule can cover, ascending (tube_spans).
struct EdgeTube {
  Vec3 a, b;
  double rho = 0, stripes = 1, speed = 0;
  Vec3 ca, cb;
  std::vector<RowSpan> rows;
};

// The frame's edge tubes in drawing order (R1-RND-064's bundling, visible endpoints only), with
// the bundling counts written into `stats` (edges in view, considered, drawn). Tubes with no row
// to draw are left out.
std::vector<EdgeTube> edge_tubes(const Scene& s, const View& v, const CameraFrame& f, const CullResult& culled, FrameStats& stats);

// The reference's edge pass (R1-RND-063..066): for each tube in order and each pixel of its
// rows, the ray through the pixel centre hits the tube's open wall nearer than the layer's t,
// which then takes the hit's t, the strip-shaded colour and owner kEdge. So the nearest hit wins,
// and an exact tie keeps what was there (an impostor, or an earlier tube).
void draw_edge_tubes(std::span<const EdgeTube> tubes, const View& v, const CameraFrame& f, OpaqueLayer& layer);

// A backend's edge pass: the same contract as draw_edge_tubes on the layer the impostors left
// (R1-RND-081).
using EdgePass = std::function<Status(std::span<const EdgeTube>, const View&, const CameraFrame&, OpaqueLayer&)>;

// One T3 splat (R1-RND-040..045): the particle, its view depth and pixel centre, the conic (the
// inverse of its projected 2D covariance [[ca, cb], [cb, cc]]), its opacity and colour. Its alpha
// at pixel centre (x, y) is min(0.99, opacity exp(-q / 2)), q the conic's quadratic form of
// (x - px, y - py); contributions below kSplatMinAlpha are dropped.
struct Splat {
  std::uint32_t particle = 0;
  double depth = 0, px = 0, py = 0;
  double ca = 0, cb = 0, cc = 0;
  double opacity = 0;
  Vec3 color;
};
inline constexpr double kSplatMinAlpha = 1.0 / 255.0;

// The splats of a frame front to back (depth, ties by particle), binned into 16-pixel tiles:
// tiles[ty * tiles_x + tx] lists the splats that may reach the tile, in depth order.
struct SplatBins {
  static constexpr int kTile = 16;
  std::vector<Splat> splats;
  int tiles_x = 0, tiles_y = 0;
  std::vector<std::vector<std::uint32_t>> tiles;
};
// A backend's splat sort (R1-RND-079): `order` becomes the permutation that puts `depth` in
// ascending order, equal depths in index order (a stable sort). Every depth is positive and finite.
using SplatSortPass = std::function<Status(std::span<const double> depth, std::vector<std::uint32_t>& order)>;
// With `sort`, the splats (made in ascending particle order) are put in its order, which is the
// reference's when the pass keeps its contract; an order that is no permutation is an internal
// error. Splat depths that are not all positive and finite are sorted on the host.
Result<SplatBins> bin_splats(const Scene& s, const View& v, const CameraFrame& f, const CullResult& culled,
                             const SplatSortPass& sort = {});

// What the field and composite pass reads (R1-RND-078): the opaque layer after impostors and
// edges, the binned splats, and the frame's scene, view and options (the field is built from
// them with make_field_frame).
struct CompositeInput {
  const Scene& scene;
  const View& view;
  const CameraFrame& frame;
  const RenderOptions& options;
  const OpaqueLayer& opaque;
  const SplatBins& splats;
};

// A backend's field and composite pass: per pixel, the splats and T-infinity samples in front of
// the opaque hit composited front to back, then the hit (R1-RND-070), written into the image's
// RGBA and, when the field produced flow, its flow channels; it counts the pixels it left to the
// host in FrameStats::host_pixels. The frame sets the depth.
using CompositePass = std::function<Status(const CompositeInput&, Image&, FrameStats&)>;

// The reference's field and composite, one pixel at a time: what the frame runs for every pixel,
// and what a backend's pass may run for the pixels it cannot do itself. `rgba` is the pixel's
// premultiplied colour and alpha, `flow` its flow (0 where the field adds none).
class PixelCompositor {
 public:
  explicit PixelCompositor(const CompositeInput& in);
  const FieldFrame& field() const { return ff_; }
  // Pixel (x, y); with `fs` the field walk is counted, with `timing` its time split into field_s
  // and splat_s.
  void pixel(int x, int y, float rgba[4], float flow[3], FieldRayStats* fs = nullptr, FrameStats* timing = nullptr);

 private:
  struct SplatHit {
    double t, alpha;
    std::uint32_t splat;
  };
  CompositeInput in_;  // references to the frame's values, which outlive the compositor
  FieldFrame ff_;
  std::vector<FieldSample> samples_;
  std::vector<SplatHit> hits_;
};

// A backend's cull (R1-RND-074): into a fresh result and stats, what cull_frame gives (the visible
// particles ascending with the reference's depth, size and tier bits, the far nodes in walk order,
// their particles, and the walk's counts). The frame checks the result's shape
// (check_cull_result) and refuses one that cannot be the reference's.
using CullPass = std::function<Status(const Scene&, const View&, const CameraFrame&, CullResult&, CullStats&)>;

// The passes a backend runs in place of the reference's; an empty member is the reference's.
struct FramePasses {
  CullPass cull;
  ImpostorPass impostors;
  EdgePass edges;
  CompositePass composite;
  SplatSortPass splat_sort;
};

}  // namespace r1::render
