// The reference frame: opaque impostors and edges, splats, the field, labels (R1-RND-060..079).
#include "renderer.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>

#include "content_pass.hpp"
#include "r1/reference/ply_export.hpp"  // kSplatOpacity, kSplatSigmaPerRadius: one splat everywhere
#include "shapes.hpp"

namespace r1::render {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kSplatLowPass = 0.3;        // px^2 added to the projected covariance (Kerbl et al.)
constexpr double kMinAlpha = kSplatMinAlpha;  // splat contributions below this are dropped
constexpr int kTile = SplatBins::kTile;        // splat binning tile, pixels

// ---- edges and bundling (R1-RND-063..066) ----

struct Endpoint {
  int level = -1;          // -1: the particle itself; else a cluster level
  std::uint32_t id = 0;    // particle index or cluster id
  bool operator<(const Endpoint& o) const { return std::pair(level, id) < std::pair(o.level, o.id); }
  bool operator==(const Endpoint& o) const = default;
};

struct Tube {
  Endpoint a, b;
  double w = 0, a2 = 0, degree_a = 0;
};

Endpoint endpoint_of(const Scene& s, const View& v, const CameraFrame& f, std::uint32_t p, double s_p) {
  if (s_p > v.tiers.t2) return {-1, p};
  // The finest cluster of p whose projected size reaches t2 pixels; the top level otherwise.
  for (int l = 0; l < kLevels; ++l) {
    const std::uint32_t id = s.hierarchy->cluster_of[static_cast<std::size_t>(l)][p];
    const NodeData& d = s.nodes[static_cast<std::size_t>(l)][id];
    const double depth = dot(d.centroid - v.camera.position, f.forward);
    const double size = depth > kNear ? screen_diameter(d.extent + d.max_radius, depth, f) : kInf;
    if (size >= v.tiers.t2 || l == kLevels - 1) return {l, id};
  }
  return {kLevels - 1, s.hierarchy->cluster_of[kLevels - 1][p]};
}

Vec3 endpoint_position(const Scene& s, const Endpoint& e) {
  return e.level < 0 ? s.position[e.id] : s.nodes[static_cast<std::size_t>(e.level)][e.id].centroid;
}
double endpoint_radius(const Scene& s, const Endpoint& e) {
  return e.level < 0 ? s.radius[e.id] : s.nodes[static_cast<std::size_t>(e.level)][e.id].radius;
}
Vec3 endpoint_color(const Scene& s, const Endpoint& e) {
  return e.level < 0 ? s.color[e.id] : s.nodes[static_cast<std::size_t>(e.level)][e.id].color;
}

// The nodes an edge between endpoints a and b runs through (R1-RND-064, after Holten 2006): up
// a's ancestors to the child of their lowest common ancestor, across, and down b's ancestors.
// The common ancestor itself is on the route only when it is one of the endpoints.
Endpoint parent_of(const Scene& s, const Endpoint& e) {
  if (e.level < 0) return {0, s.hierarchy->cluster_of[0][e.id]};
  return {e.level + 1, s.hierarchy->levels[static_cast<std::size_t>(e.level)][e.id].parent};
}

int ancestors(const Scene& s, Endpoint e, std::array<Endpoint, kLevels + 1>& chain) {
  int n = 0;
  chain[static_cast<std::size_t>(n++)] = e;
  while (e.level < kLevels - 1) chain[static_cast<std::size_t>(n++)] = e = parent_of(s, e);
  return n;
}

int route(const Scene& s, const Endpoint& a, const Endpoint& b, std::array<Endpoint, 2 * kLevels + 2>& out) {
  std::array<Endpoint, kLevels + 1> ca, cb;
  const int na = ancestors(s, a, ca), nb = ancestors(s, b, cb);
  // The first node of a's chain that is also on b's: their lowest common ancestor (none when the
  // hierarchy has several top-level clusters and a and b lie under different ones).
  int i = 0, j = 0;
  for (i = 0; i < na; ++i) {
    j = 0;
    while (j < nb && !(cb[static_cast<std::size_t>(j)] == ca[static_cast<std::size_t>(i)])) ++j;
    if (j < nb) break;
  }
  int n = 0;
  if (i == na) {  // separate top-level clusters (a disconnected hierarchy): join the two chains
    for (int k = 0; k < na; ++k) out[static_cast<std::size_t>(n++)] = ca[static_cast<std::size_t>(k)];
    for (int k = nb - 1; k >= 0; --k) out[static_cast<std::size_t>(n++)] = cb[static_cast<std::size_t>(k)];
    return n;
  }
  for (int k = 0; k < i; ++k) out[static_cast<std::size_t>(n++)] = ca[static_cast<std::size_t>(k)];
  if (i == 0 || j == 0) out[static_cast<std::size_t>(n++)] = ca[static_cast<std::size_t>(i)];
  for (int k = j - 1; k >= 0; --k) out[static_cast<std::size_t>(n++)] = cb[static_cast<std::size_t>(k)];
  return n;
}

std::vector<Tube> bundle(const Scene& s, const View& v, const CameraFrame& f, const std::vector<double>& size, BundleStats& st) {
  // Only edges with an endpoint drawn at T2 or above are drawn; each endpoint below T2 is
  // replaced by its cluster, every edge follows its route through the hierarchy, and equal
  // segments of different routes merge into one tube (R1-RND-064).
  std::map<std::pair<Endpoint, Endpoint>, Tube> merged;
  std::array<Endpoint, 2 * kLevels + 2> nodes;
  for (const LayoutEdge& e : s.edges) {
    if (size[e.p] > 0 && size[e.q] > 0) ++st.in_view;
    const bool big_p = size[e.p] > v.tiers.t2, big_q = size[e.q] > v.tiers.t2;
    if (!big_p && !big_q) continue;
    ++st.considered;
    const int n = route(s, endpoint_of(s, v, f, e.p, size[e.p]), endpoint_of(s, v, f, e.q, size[e.q]), nodes);
    for (int k = 0; k + 1 < n; ++k) {
      Endpoint a = nodes[static_cast<std::size_t>(k)], b = nodes[static_cast<std::size_t>(k + 1)];
      if (endpoint_position(s, a) == endpoint_position(s, b)) continue;  // a one-member cluster
      double a2 = Q32::from_raw(e.a2_raw).to_double();
      double deg = s.degree[e.p];
      if (b < a) {
        std::swap(a, b);
        a2 = -a2;
        deg = s.degree[e.q];
      }
      Tube& t = merged[{a, b}];
      t.a = a, t.b = b;
      t.w += Q32::from_raw(e.w_raw).to_double();
      t.a2 += a2;
      t.degree_a += deg;
    }
  }
  std::vector<Tube> out;
  out.reserve(merged.size());
  for (auto& [key, t] : merged) {
    out.push_back(t);
    st.max_weight = std::max(st.max_weight, t.w);
  }
  st.drawn = out.size();
  return out;
}

// Screen diameters of the visible particles; 0 for every particle outside the frustum, so only
// visible particles can anchor an edge (R1-RND-064).
// Per particle its screen diameter when visible, else 0: the listed particles and the far nodes'
// members.
std::vector<double> screen_sizes(const Scene& s, const View& v, const CameraFrame& f, const CullResult& culled) {
  std::vector<double> size(s.n, 0.0);
  for (const Visible& vis : culled.visible) size[vis.particle] = vis.s;
  for (const FarNode& node : culled.far)
    for_each_member(s, node.level, node.id, [&](std::uint32_t p) { size[p] = classify(s, v, f, p).s; });
  return size;
}

// ---- splats (R1-RND-040..044) ----


std::vector<Vec3> u5_gradients(const Scene& s) {
  std::vector<Vec3> g(s.n);
  for (const LayoutEdge& e : s.edges) {
    const Vec3 d = s.position[e.q] - s.position[e.p];
    const double d2 = dot(d, d);
    if (!(d2 > 0)) continue;
    const double w = Q32::from_raw(e.w_raw).to_double() * (s.u5[e.q] - s.u5[e.p]) / d2;
    g[e.p] += d * w;
    g[e.q] += d * w;
  }
  return g;
}

bool make_splat(const Scene& s, const View& v, const CameraFrame& f, std::uint32_t p, double weight, const std::vector<Vec3>& grad,
                Splat& out) {
  const Vec3 rel = s.position[p] - v.camera.position;
  const double z = dot(rel, f.forward);
  if (z <= kNear) return false;
  const double xc = dot(rel, f.right), yc = dot(rel, f.up);
  const double sigma = kSplatSigmaPerRadius * s.radius[p];
  // Camera-space covariance sigma^2 (I + k g g^T) (k = 0: isotropic), then EWA: J Sigma J^T.
  double S[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  if (v.splat_stretch > 0 && !grad.empty() && length(grad[p]) > 0) {
    const Vec3 gs = normalize(grad[p]);
    const double gc[3] = {dot(gs, f.right), dot(gs, f.up), dot(gs, f.forward)};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) S[i][j] += v.splat_stretch * gc[i] * gc[j];
  }
  const double fz = f.focal_px / z;
  const double J[2][3] = {{fz, 0, -fz * xc / z}, {0, -fz, fz * yc / z}};
  double C[2][2] = {{0, 0}, {0, 0}};
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 2; ++b)
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) C[a][b] += J[a][i] * S[i][j] * J[b][j];
  C[0][0] = C[0][0] * sigma * sigma + kSplatLowPass;
  C[1][1] = C[1][1] * sigma * sigma + kSplatLowPass;
  C[0][1] *= sigma * sigma;
  const double det = C[0][0] * C[1][1] - C[0][1] * C[0][1];
  if (!(det > 0)) return false;
  out.particle = p;
  out.depth = z;
  out.px = v.width * 0.5 + xc * fz;
  out.py = v.height * 0.5 - yc * fz;
  out.ca = C[1][1] / det;
  out.cb = -C[0][1] / det;
  out.cc = C[0][0] / det;
  out.opacity = kSplatOpacity * weight;
  out.color = s.color[p];
  return true;
}

double splat_alpha(const Splat& sp, double x, double y) {
  const double dx = x - sp.px, dy = y - sp.py;
  const double q = sp.ca * dx * dx + 2 * sp.cb * dx * dy + sp.cc * dy * dy;
  return std::min(0.99, sp.opacity * std::exp(-0.5 * q));
}

// Half-extent in pixels that holds every alpha >= kMinAlpha: q <= 2 ln(opacity / kMinAlpha).
double splat_reach(const Splat& sp) {
  const double det_conic = sp.ca * sp.cc - sp.cb * sp.cb;
  const double qmax = 2.0 * std::log(std::max(sp.opacity / kMinAlpha, 1.0));
  // The covariance's largest eigenvalue bounds each axis: lambda_max = 1 / lambda_min(conic).
  const double tr = sp.ca + sp.cc;
  const double lmin = 0.5 * (tr - std::sqrt(std::max(tr * tr - 4 * det_conic, 0.0)));
  return std::sqrt(qmax / std::max(lmin, 1e-300));
}

}  // namespace

BundleStats bundle_counts(const Scene& scene, const View& view) {
  const CameraFrame f = camera_frame(view);
  BundleStats st;
  bundle(scene, view, f, screen_sizes(scene, view, f, cull_frame(scene, view, f)), st);
  return st;
}

namespace {

// Per image row, the hull of the columns whose centres lie within hw pixels of the projected
// segment pa-pb (a capsule), accumulated into lo/hi (indexed by row); widens [row_min, row_max]
// to the rows it touched.
void capsule_rows(const Projected& pa, const Projected& pb, double hw, std::vector<double>& lo, std::vector<double>& hi, int& row_min,
                  int& row_max) {
  const int rows = static_cast<int>(lo.size());
  const auto to_row = [rows](double d) { return static_cast<int>(std::clamp(d, -1.0, static_cast<double>(rows))); };
  const int y0 = std::max(0, to_row(std::ceil(std::min(pa.py, pb.py) - hw - 0.5)));
  const int y1 = std::min(rows - 1, to_row(std::floor(std::max(pa.py, pb.py) + hw - 0.5)));
  const double dx = pb.px - pa.px, dy = pb.py - pa.py, len2 = dx * dx + dy * dy;
  if (y0 <= y1) row_min = std::min(row_min, y0), row_max = std::max(row_max, y1);
  for (int y = y0; y <= y1; ++y) {
    const double yc = y + 0.5;
    double l = kInf, h = -kInf;
    // The two end discs.
    for (const Projected* e : {&pa, &pb}) {
      const double h2 = hw * hw - (yc - e->py) * (yc - e->py);
      if (h2 < 0) continue;
      l = std::min(l, e->px - std::sqrt(h2));
      h = std::max(h, e->px + std::sqrt(h2));
    }
    // The band between them: 0 <= (P - a).d <= |d|^2 and |(P - a) x d| <= hw |d|, P = (x, yc).
    if (len2 > 0) {
      double bl = -kInf, bh = kInf;
      const auto keep = [&](double alpha, double beta, double lo_v, double hi_v) {  // lo_v <= alpha x + beta <= hi_v
        if (alpha == 0) {
          if (beta < lo_v || beta > hi_v) bl = kInf, bh = -kInf;
          return;
        }
        double u = (lo_v - beta) / alpha, w = (hi_v - beta) / alpha;
        if (u > w) std::swap(u, w);
        bl = std::max(bl, u), bh = std::min(bh, w);
      };
      keep(dx, -pa.px * dx + (yc - pa.py) * dy, 0, len2);
      const double reach = hw * std::sqrt(len2);
      keep(dy, -pa.px * dy - (yc - pa.py) * dx, -reach, reach);
      if (bl <= bh) l = std::min(l, bl), h = std::max(h, bh);
    }
    const std::size_t k = static_cast<std::size_t>(y);
    lo[k] = std::min(lo[k], l), hi[k] = std::max(hi[k], h);
  }
}

}  // namespace

std::vector<RowSpan> tube_spans(const View& v, const CameraFrame& f, const Vec3& a, const Vec3& b, double rho) {
  std::vector<RowSpan> rows;
  // Clip the segment to the frustum widened by rho on every side (a point further out has no
  // tube point inside the view) and to depth 2 rho + near (nearer, the bound below degenerates;
  // that sliver of a tube is not drawn).
  const auto cam = [&](const Vec3& p) {
    const Vec3 r = p - v.camera.position;
    return Vec3{dot(r, f.right), dot(r, f.up), dot(r, f.forward)};
  };
  const Vec3 ca = cam(a), cb = cam(b);
  const double tx = f.tan_half_fov * v.width / v.height, ty = f.tan_half_fov;
  const double nx = std::sqrt(1 + tx * tx), ny = std::sqrt(1 + ty * ty);
  double t0 = 0, t1 = 1;
  const auto keep = [&](const auto& g) {  // keeps the part of the segment where g <= 0 (g linear)
    const double ga = g(ca), gb = g(cb);
    if (ga > 0 && gb > 0) t0 = 1, t1 = 0;
    else if (ga > 0) t0 = std::max(t0, ga / (ga - gb));
    else if (gb > 0) t1 = std::min(t1, ga / (ga - gb));
  };
  keep([&](const Vec3& c) { return 2 * rho + kNear - c.z; });
  keep([&](const Vec3& c) { return (c.x - c.z * tx) / nx - rho; });
  keep([&](const Vec3& c) { return (-c.x - c.z * tx) / nx - rho; });
  keep([&](const Vec3& c) { return (c.y - c.z * ty) / ny - rho; });
  keep([&](const Vec3& c) { return (-c.y - c.z * ty) / ny - rho; });
  if (!(t0 <= t1)) return rows;
  const Vec3 ea = a + (b - a) * t0, eb = a + (b - a) * t1;
  const double za = ca.z + (cb.z - ca.z) * t0, zb = ca.z + (cb.z - ca.z) * t1;
  // A point within rho of a segment point at depth z and pixel offset s from the image centre
  // projects within rho sqrt(f^2 + |s|^2) / (z - rho) pixels of that point's projection. Depth is
  // smallest and |s| largest at an end of a piece, so pieces over which depth at most doubles
  // keep the bound near the tube's own width.
  std::vector<double> lo(static_cast<std::size_t>(v.height), kInf), hi(static_cast<std::size_t>(v.height), -kInf);
  const double cx = 0.5 * v.width, cy = 0.5 * v.height;
  int row_min = v.height, row_max = -1;
  Vec3 start = ea;
  double z_start = za;
  while (true) {
    const bool last = std::max(z_start, zb) <= 2 * std::min(z_start, zb);
    const double z_end = last ? zb : (zb > z_start ? 2 * z_start : 0.5 * z_start);
    const Vec3 end = last ? eb : ea + (eb - ea) * ((z_end - za) / (zb - za));
    const Projected pa = project(v, f, start), pb = project(v, f, end);
    const double s_max = std::max(std::hypot(pa.px - cx, pa.py - cy), std::hypot(pb.px - cx, pb.py - cy));
    const double z_min = std::min(pa.depth, pb.depth);
    capsule_rows(pa, pb, rho * std::sqrt(f.focal_px * f.focal_px + s_max * s_max) / (z_min - rho) + 0.5, lo, hi, row_min, row_max);
    if (last) break;
    start = end, z_start = z_end;
  }
  const auto to_col = [&](double d) { return static_cast<int>(std::clamp(d, 0.0, static_cast<double>(v.width))); };
  for (int y = row_min; y <= row_max; ++y) {
    const std::size_t k = static_cast<std::size_t>(y);
    if (!(lo[k] <= hi[k])) continue;
    const int x0 = to_col(std::ceil(lo[k] - 0.5)), x1 = to_col(std::floor(hi[k] - 0.5) + 1);
    if (x0 < x1) rows.push_back({y, x0, x1});
  }
  return rows;
}

Vec3 headlight(const Vec3& albedo, const Vec3& normal, const Vec3& dir) {
  return albedo * (0.25 + 0.75 * std::max(0.0, -dot(normal, dir)));
}

std::vector<Impostor> impostor_list(const Scene& s, const View& v, const CameraFrame& f, const CullResult& culled) {
  std::vector<Impostor> out;
  for (const Visible& vis : culled.visible) {
    if (vis.tier > Tier::kT2) continue;
    // A T0 particle with content opens: the content pass draws it instead (R1-RND-130).
    if (vis.tier == Tier::kT0 && s.content && s.content->has(vis.particle)) continue;
    const std::uint32_t p = vis.particle;
    const double r = s.radius[p];
    const Vec3 c = s.position[p];
    const Rect rect = project_box(v, f, c - Vec3{r, r, r}, c + Vec3{r, r, r});
    if (!rect.empty()) out.push_back({p, s.shape[p], c, r, s.color[p], rect});
  }
  return out;
}

void draw_impostors(std::span<const Impostor> impostors, const View& v, const CameraFrame& f, OpaqueLayer& op) {
  const int W = op.width;
  for (const Impostor& im : impostors) {
    for (int y = im.rect.y0; y < im.rect.y1; ++y)
      for (int x = im.rect.x0; x < im.rect.x1; ++x) {
        const std::size_t k = static_cast<std::size_t>(y) * W + x;
        const Ray ray = pixel_ray(v, f, x + 0.5, y + 0.5);
        const auto hit = intersect_shape(im.shape, im.center, im.radius, ray, kNear, op.t[k]);
        if (!hit) continue;
        op.t[k] = hit->t;
        op.color[k] = headlight(im.color, hit->normal, ray.d);
        op.owner[k] = im.particle;
      }
  }
}

std::vector<EdgeTube> edge_tubes(const Scene& s, const View& v, const CameraFrame& f, const CullResult& culled, FrameStats& st) {
  const std::vector<double> size = screen_sizes(s, v, f, culled);
  BundleStats bs;
  const std::vector<Tube> tubes = bundle(s, v, f, size, bs);
  st.edges_in_view = bs.in_view;
  st.edges_considered = bs.considered;
  st.edges_drawn = bs.drawn;
  // An opened particle (T0 with content, R1-RND-130) is entered by its edges at its bounding
  // sphere, so they do not cross its content. A tube ends at it when the end is the particle or a
  // cluster whose one member it is (the cluster's centroid is then the particle's position).
  const auto opened_radius = [&](const Endpoint& e) {
    if (!s.content) return 0.0;
    std::int64_t p = e.level < 0 ? static_cast<std::int64_t>(e.id) : -1;
    if (e.level >= 0 && s.nodes[static_cast<std::size_t>(e.level)][e.id].count == 1)
      for_each_member(s, e.level, e.id, [&](std::uint32_t q) { p = q; });
    if (p < 0) return 0.0;
    const auto q = static_cast<std::uint32_t>(p);
    return s.content->has(q) && size[q] > v.tiers.t0 ? s.radius[q] : 0.0;
  };
  std::vector<EdgeTube> out;
  for (const Tube& tube : tubes) {
    Vec3 a = endpoint_position(s, tube.a), b = endpoint_position(s, tube.b);
    const double cut_a = opened_radius(tube.a), cut_b = opened_radius(tube.b);
    if (cut_a > 0 || cut_b > 0) {
      const double len = length(b - a);
      if (!(cut_a + cut_b < len)) continue;
      const Vec3 dir = (b - a) / len;
      b = b - dir * cut_b;
      a = a + dir * cut_a;
    }
    const double cap = 0.3 * std::min(endpoint_radius(s, tube.a), endpoint_radius(s, tube.b));
    const double rho = std::min(0.1 * s.median_radius * std::sqrt(tube.w), cap);
    if (!(rho > 0)) continue;
    EdgeTube et;
    et.a = a, et.b = b, et.rho = rho;
    // Flow: v = sign(A2) |P_ab| cycles per second along the strip (R-1.0 8.2).
    const double p_ab = tube.degree_a > 0 ? tube.w / tube.degree_a : 0.0;
    et.speed = (tube.a2 > 0 ? 1.0 : (tube.a2 < 0 ? -1.0 : 0.0)) * std::fabs(p_ab);
    et.stripes = std::max(1.0, std::round(length(b - a) / (8 * rho)));
    et.ca = endpoint_color(s, tube.a), et.cb = endpoint_color(s, tube.b);
    et.rows = tube_spans(v, f, a, b, rho);
    if (!et.rows.empty()) out.push_back(std::move(et));
  }
  return out;
}

void draw_edge_tubes(std::span<const EdgeTube> tubes, const View& v, const CameraFrame& f, OpaqueLayer& op) {
  const int W = op.width;
  for (const EdgeTube& tube : tubes)
    for (const RowSpan& row : tube.rows)
      for (int x = row.x0; x < row.x1; ++x) {
        const int y = row.y;
        const std::size_t k = static_cast<std::size_t>(y) * W + x;
        const Ray ray = pixel_ray(v, f, x + 0.5, y + 0.5);
        const auto hit = intersect_tube(tube.a, tube.b, tube.rho, ray, kNear, op.t[k]);
        if (!hit) continue;
        const double phase = tube.stripes * hit->u - tube.speed * v.time;
        const double strip = 0.55 + 0.45 * 0.5 * (1 + std::cos(2 * kPi * (phase - std::floor(phase))));
        op.t[k] = hit->hit.t;
        op.color[k] = headlight((tube.ca * (1 - hit->u) + tube.cb * hit->u) * (0.6 * strip), hit->hit.normal, ray.d);
        op.owner[k] = OpaqueLayer::kEdge;
      }
}

Result<SplatBins> bin_splats(const Scene& s, const View& v, const CameraFrame& f, const CullResult& culled,
                             const SplatSortPass& sort) {
  // Every visible T3 particle, and the handoff band's share of T-inf ones (R1-RND-045).
  const std::vector<Vec3> grad = v.splat_stretch > 0 ? u5_gradients(s) : std::vector<Vec3>{};
  SplatBins b;
  for (const Visible& vis : culled.visible) {
    if (vis.tier < Tier::kT3) continue;
    const double weight = 1.0 - tinf_weight(vis.s, v.tiers);
    Splat sp;
    if (weight > 0 && make_splat(s, v, f, vis.particle, weight, grad, sp)) b.splats.push_back(sp);
  }
  // Front to back by depth, ties by particle index (R1-RND-043), binned into tiles. The splats
  // come in ascending particle order, so a backend's stable sort by depth gives the same order.
  const bool positive = std::all_of(b.splats.begin(), b.splats.end(),
                                    [](const Splat& sp) { return sp.depth > 0 && std::isfinite(sp.depth); });
  if (sort && positive) {
    std::vector<double> depth(b.splats.size());
    for (std::size_t i = 0; i < depth.size(); ++i) depth[i] = b.splats[i].depth;
    std::vector<std::uint32_t> order;
    R1_TRY(sort(depth, order));
    std::vector<char> seen(depth.size(), 0);
    bool permutation = order.size() == depth.size();
    for (std::size_t i = 0; permutation && i < order.size(); ++i) {
      permutation = order[i] < depth.size() && seen[order[i]] == 0;
      if (permutation) seen[order[i]] = 1;
    }
    if (!permutation) return Status::internal("splat sort: the backend's order is not a permutation of the splats");
    std::vector<Splat> sorted;
    sorted.reserve(order.size());
    for (const std::uint32_t i : order) sorted.push_back(b.splats[i]);
    b.splats = std::move(sorted);
  } else {
    std::sort(b.splats.begin(), b.splats.end(),
              [](const Splat& a, const Splat& c) { return a.depth != c.depth ? a.depth < c.depth : a.particle < c.particle; });
  }
  b.tiles_x = (v.width + kTile - 1) / kTile, b.tiles_y = (v.height + kTile - 1) / kTile;
  b.tiles.resize(static_cast<std::size_t>(b.tiles_x) * b.tiles_y);
  for (std::uint32_t i = 0; i < b.splats.size(); ++i) {
    const Splat& sp = b.splats[i];
    const double reach = splat_reach(sp);
    const int x0 = std::max(0, static_cast<int>(std::floor((sp.px - reach) / kTile)));
    const int x1 = std::min(b.tiles_x - 1, static_cast<int>(std::floor((sp.px + reach) / kTile)));
    const int y0 = std::max(0, static_cast<int>(std::floor((sp.py - reach) / kTile)));
    const int y1 = std::min(b.tiles_y - 1, static_cast<int>(std::floor((sp.py + reach) / kTile)));
    for (int ty = y0; ty <= y1; ++ty)
      for (int tx = x0; tx <= x1; ++tx) b.tiles[static_cast<std::size_t>(ty) * b.tiles_x + tx].push_back(i);
  }
  return b;
}

PixelCompositor::PixelCompositor(const CompositeInput& in)
    : in_(in), ff_(make_field_frame(in.scene, in.view, in.frame, in.options.field)) {}

void PixelCompositor::pixel(int x, int y, float rgba[4], float flow[3], FieldRayStats* fs, FrameStats* timing) {
  using clock = std::chrono::steady_clock;
  const View& v = in_.view;
  const OpaqueLayer& op = in_.opaque;
  const SplatBins& bins = in_.splats;
  const std::size_t k = static_cast<std::size_t>(y) * static_cast<std::size_t>(v.width) + static_cast<std::size_t>(x);
  const Ray ray = pixel_ray(v, in_.frame, x + 0.5, y + 0.5);
  const double t_op = op.t[k];
  const auto c0 = timing ? clock::now() : clock::time_point{};
  if (v.field) march_field(ff_, ray, t_op, k, samples_, fs);
  else samples_.clear();
  const auto c1 = timing ? clock::now() : clock::time_point{};
  hits_.clear();
  const double cos_fwd = dot(ray.d, in_.frame.forward);
  for (std::uint32_t i : bins.tiles[static_cast<std::size_t>(y / kTile) * bins.tiles_x + x / kTile]) {
    const Splat& sp = bins.splats[i];
    const double t = sp.depth / cos_fwd;
    if (t >= t_op) continue;
    const double a = splat_alpha(sp, x + 0.5, y + 0.5);
    if (a >= kMinAlpha) hits_.push_back({t, a, i});
  }
  // Tile lists are in depth order; the ray parameter keeps it (t = depth / cos).
  Vec3 color, fl;
  double T = 1;
  std::size_t i = 0, j = 0;
  while ((i < samples_.size() || j < hits_.size()) && T > 1e-4) {
    const bool take_splat = j < hits_.size() && (i >= samples_.size() || hits_[j].t <= samples_[i].t);
    if (take_splat) {
      const SplatHit& h = hits_[j++];
      color += bins.splats[h.splat].color * (T * h.alpha);
      T *= 1 - h.alpha;
    } else {
      const FieldSample& fsmp = samples_[i++];
      color += fsmp.color * (T * fsmp.alpha);
      fl += fsmp.flow * (T * fsmp.alpha);
      T *= 1 - fsmp.alpha;
    }
  }
  if (t_op < kInf) {
    color += op.color[k] * T;
    T = 0;
  }
  rgba[0] = static_cast<float>(color.x);
  rgba[1] = static_cast<float>(color.y);
  rgba[2] = static_cast<float>(color.z);
  rgba[3] = static_cast<float>(1 - T);
  flow[0] = static_cast<float>(fl.x), flow[1] = static_cast<float>(fl.y), flow[2] = static_cast<float>(fl.z);
  if (timing) {
    const auto c2 = clock::now();
    timing->field_s += std::chrono::duration<double>(c1 - c0).count();
    timing->splat_s += std::chrono::duration<double>(c2 - c1).count();
  }
}

namespace {

// Composite per pixel, front to back in ray order: splats and field samples up to the opaque
// hit, then the hit (R1-RND-070).
void composite(const CompositeInput& in, Image& image, FrameStats& st, const ProgressFn& progress) {
  const int W = in.view.width, H = in.view.height;
  PixelCompositor pc(in);
  FieldRayStats fs;
  bool any_flow = false;
  std::vector<float> flow(static_cast<std::size_t>(W) * H * 3, 0.0f);
  for (int y = 0; y < H; ++y) {
    if (progress && (y % 16 == 0 || y + 1 == H)) progress("render", static_cast<std::uint64_t>(y + 1), static_cast<std::uint64_t>(H));
    for (int x = 0; x < W; ++x) {
      float* fl = flow.data() + (static_cast<std::size_t>(y) * W + x) * 3;
      pc.pixel(x, y, image.px(x, y), fl, &fs, &st);
      if (fl[0] != 0 || fl[1] != 0 || fl[2] != 0) any_flow = true;
    }
  }
  if (any_flow) image.flow = std::move(flow);
  image.depth = in.opaque.t;
  st.field_walked = fs.walked;
  st.field_samples = fs.samples;
  st.field_candidates = fs.candidates;
  st.field_evaluations = fs.evaluations;
  st.field_neural = fs.neural;
}

// Labels at T1 (and T0, drawn as T1): title or hex prefix beside the particle, far ones first,
// only where the particle itself is the nearest surface at its centre (R1-RND-067).
Status draw_labels(const Scene& s, const View& v, const CameraFrame& f, const CullResult& culled, const OpaqueLayer& op,
                   Image& image, FrameStats& st) {
  const int W = v.width, H = v.height;
  std::vector<const Visible*> labelled;
  for (const Visible& vis : culled.visible)
    if (vis.tier <= Tier::kT1) labelled.push_back(&vis);
  std::sort(labelled.begin(), labelled.end(), [](const Visible* a, const Visible* b) {
    return a->depth != b->depth ? a->depth > b->depth : a->particle < b->particle;
  });
  for (const Visible* vis : labelled) {
    const Projected pr = project(v, f, s.position[vis->particle]);
    if (pr.depth <= kNear) continue;
    const int cx = static_cast<int>(std::floor(pr.px)), cy = static_cast<int>(std::floor(pr.py));
    if (cx < 0 || cy < 0 || cx >= W || cy >= H) continue;
    if (op.owner[static_cast<std::size_t>(cy) * W + cx] != static_cast<std::int64_t>(vis->particle)) continue;
    const double half = std::min(vis->s, 4.0 * H) * 0.5;
    const int text_px = 14;
    // Beside the disc, never over it: the particle cannot hide its own label.
    R1_TRY(draw_text(image, static_cast<int>(pr.px + half) + 4, cy + text_px / 3, s.label[vis->particle], text_px,
                     {0.85f, 0.85f, 0.85f}));
    ++st.labels;
  }
  return Status::ok();
}

}  // namespace

Result<Image> render_frame(const Scene& s, const View& v, const RenderOptions& options, FrameStats* stats_out,
                           const ProgressFn& progress, const FramePasses& passes) {
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  FrameStats st;
  const CameraFrame f = camera_frame(v);
  Image image(v.width, v.height);

  // Cull and classify (R1-RND-020..023). Far nodes' members are visible T-infinity particles
  // drawn by the field alone (R1-RND-025).
  auto t0 = clock::now();
  CullStats cs;
  CullResult culled;
  if (passes.cull) {
    R1_TRY(passes.cull(s, v, f, culled, cs));
    R1_TRY(check_cull_result(s, culled));
  } else {
    culled = cull_frame(s, v, f, &cs);
  }
  st.visible = culled.visible.size() + culled.far_particles;
  st.nodes_tested = cs.nodes_tested;
  st.culled_nodes = cs.nodes_culled;
  for (const Visible& vis : culled.visible) ++st.tier_count[static_cast<std::size_t>(vis.tier)];
  st.tier_count[static_cast<std::size_t>(Tier::kTinf)] += culled.far_particles;
  st.cull_s = seconds_since(t0);

  // Opaque impostors (R1-RND-076: the backend's pass when it has one).
  t0 = clock::now();
  OpaqueLayer op(v.width, v.height);
  const std::vector<Impostor> impostors = impostor_list(s, v, f, culled);
  if (passes.impostors) R1_TRY(passes.impostors(impostors, v, f, op));
  else draw_impostors(impostors, v, f, op);
  // T0 content after the shapes, with the same nearest-hit rule (R1-RND-135).
  st.content = draw_content(s, v, f, culled, op);
  st.impostor_s = seconds_since(t0);

  t0 = clock::now();
  if (v.edges) {
    const std::vector<EdgeTube> tubes = edge_tubes(s, v, f, culled, st);
    if (passes.edges) R1_TRY(passes.edges(tubes, v, f, op));
    else draw_edge_tubes(tubes, v, f, op);
  }
  st.edge_s = seconds_since(t0);

  t0 = clock::now();
  R1_ASSIGN(const SplatBins bins, bin_splats(s, v, f, culled, passes.splat_sort));
  st.splats = bins.splats.size();
  st.splat_s = seconds_since(t0);

  // Field and composite (R1-RND-078: the backend's pass when it has one).
  if (passes.composite) {
    t0 = clock::now();
    R1_TRY(passes.composite({s, v, f, options, op, bins}, image, st));
    image.depth = op.t;
    st.field_s = seconds_since(t0);
  } else {
    composite({s, v, f, options, op, bins}, image, st, progress);
  }

  t0 = clock::now();
  if (v.labels) R1_TRY(draw_labels(s, v, f, culled, op, image, st));
  st.label_s = seconds_since(t0);
  st.total_s = seconds_since(start);
  if (stats_out) *stats_out = st;
  return image;
}

}  // namespace r1::render
