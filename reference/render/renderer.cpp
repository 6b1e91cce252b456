// The reference frame: opaque impostors and edges, splats, the field, labels (R1-RND-060..079).
#include "renderer.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>

#include "r1/reference/ply_export.hpp"  // kSplatOpacity, kSplatSigmaPerRadius: one splat everywhere
#include "shapes.hpp"

namespace r1::render {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kSplatLowPass = 0.3;        // px^2 added to the projected covariance (Kerbl et al.)
constexpr double kMinAlpha = 1.0 / 255.0;    // splat contributions below this are dropped
constexpr int kTile = 16;                    // splat binning tile, pixels

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// The pixel rectangle [x0, x1) x [y0, y1) that holds the projection of a box; the whole image
// when part of the box lies at or behind the near plane.
struct Rect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  bool empty() const { return x0 >= x1 || y0 >= y1; }
};
Rect project_box(const View& v, const CameraFrame& f, const Vec3& lo, const Vec3& hi) {
  double minx = kInf, miny = kInf, maxx = -kInf, maxy = -kInf;
  for (int c = 0; c < 8; ++c) {
    const Vec3 corner{c & 1 ? hi.x : lo.x, c & 2 ? hi.y : lo.y, c & 4 ? hi.z : lo.z};
    const Projected p = project(v, f, corner);
    if (p.depth <= kNear) return {0, 0, v.width, v.height};
    minx = std::min(minx, p.px), maxx = std::max(maxx, p.px);
    miny = std::min(miny, p.py), maxy = std::max(maxy, p.py);
  }
  const auto clampi = [](double d, int top) { return static_cast<int>(std::clamp(d, 0.0, static_cast<double>(top))); };
  return {clampi(std::floor(minx), v.width), clampi(std::floor(miny), v.height), clampi(std::ceil(maxx) + 1, v.width),
          clampi(std::ceil(maxy) + 1, v.height)};
}

// The opaque layer: nearest hit per pixel.
struct Opaque {
  std::vector<double> t;
  std::vector<Vec3> color;
  std::vector<std::int64_t> owner;  // particle index, -2 for an edge, -1 for none
  Opaque(int w, int h)
      : t(static_cast<std::size_t>(w) * h, kInf), color(static_cast<std::size_t>(w) * h), owner(static_cast<std::size_t>(w) * h, -1) {}
};

Vec3 shade(const Vec3& albedo, const Vec3& normal, const Vec3& dir) {
  // A headlight: ambient 0.25 plus 0.75 Lambert toward the camera (R1-RND-061).
  return albedo * (0.25 + 0.75 * std::max(0.0, -dot(normal, dir)));
}

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

std::vector<Tube> bundle(const Scene& s, const View& v, const CameraFrame& f, const std::vector<double>& size, BundleStats& st) {
  // Only edges with an endpoint drawn at T2 or above are drawn (R1-RND-064); each endpoint below
  // T2 is replaced by its cluster and equal endpoint pairs merge into one tube.
  std::map<std::pair<Endpoint, Endpoint>, Tube> merged;
  for (const LayoutEdge& e : s.edges) {
    const bool big_p = size[e.p] > v.tiers.t2, big_q = size[e.q] > v.tiers.t2;
    if (!big_p && !big_q) continue;
    ++st.considered;
    Endpoint a = endpoint_of(s, v, f, e.p, size[e.p]), b = endpoint_of(s, v, f, e.q, size[e.q]);
    double a2 = Q32::from_raw(e.a2_raw).to_double();
    double deg = s.degree[e.p];
    if (b < a) {
      std::swap(a, b);
      a2 = -a2;
      deg = s.degree[e.q];
    }
    if (a == b) continue;
    Tube& t = merged[{a, b}];
    t.a = a, t.b = b;
    t.w += Q32::from_raw(e.w_raw).to_double();
    t.a2 += a2;
    t.degree_a += deg;
  }
  std::vector<Tube> out;
  out.reserve(merged.size());
  for (auto& [key, t] : merged) out.push_back(t);
  st.drawn = out.size();
  return out;
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

// Screen diameters of the visible particles; 0 for every particle outside the frustum, so only
// visible particles can anchor an edge (R1-RND-064).
std::vector<double> screen_sizes(const Scene& s, const std::vector<Visible>& visible) {
  std::vector<double> size(s.n, 0.0);
  for (const Visible& vis : visible) size[vis.particle] = vis.s;
  return size;
}

// ---- splats (R1-RND-040..044) ----

struct Splat {
  std::uint32_t particle = 0;
  double depth = 0, px = 0, py = 0;
  double ca = 0, cb = 0, cc = 0;  // conic: inverse 2D covariance [[ca, cb], [cb, cc]]
  double opacity = 0;
  Vec3 color;
};

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
  bundle(scene, view, f, screen_sizes(scene, cull(scene, view, f)), st);
  return st;
}

Result<Image> render_frame(const Scene& s, const View& v, const RenderOptions& options, FrameStats* stats_out,
                           const ProgressFn& progress) {
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  FrameStats st;
  const CameraFrame f = camera_frame(v);
  const int W = v.width, H = v.height;
  Image image(W, H);

  // Cull and classify (R1-RND-020..023).
  auto t0 = clock::now();
  CullStats cs;
  const std::vector<Visible> visible = cull(s, v, f, &cs);
  st.visible = visible.size();
  st.nodes_tested = cs.nodes_tested;
  st.culled_nodes = cs.nodes_culled;
  for (const Visible& vis : visible) ++st.tier_count[static_cast<std::size_t>(vis.tier)];
  st.cull_s = seconds_since(t0);

  // Opaque impostors: T0 draws as T1 until the content tier exists (R1-RND-024).
  t0 = clock::now();
  Opaque op(W, H);
  for (const Visible& vis : visible) {
    if (vis.tier > Tier::kT2) continue;
    const std::uint32_t p = vis.particle;
    const double r = s.radius[p];
    const Vec3 c = s.position[p];
    const Rect rect = project_box(v, f, c - Vec3{r, r, r}, c + Vec3{r, r, r});
    for (int y = rect.y0; y < rect.y1; ++y)
      for (int x = rect.x0; x < rect.x1; ++x) {
        const std::size_t k = static_cast<std::size_t>(y) * W + x;
        const Ray ray = pixel_ray(v, f, x + 0.5, y + 0.5);
        const auto hit = intersect_shape(s.shape[p], c, r, ray, kNear, op.t[k]);
        if (!hit) continue;
        op.t[k] = hit->t;
        op.color[k] = shade(s.color[p], hit->normal, ray.d);
        op.owner[k] = p;
      }
  }
  st.impostor_s = seconds_since(t0);

  // Edge tubes with the flow strip (R1-RND-063..066).
  t0 = clock::now();
  const std::vector<double> size = screen_sizes(s, visible);
  if (v.edges) {
    BundleStats bs;
    const std::vector<Tube> tubes = bundle(s, v, f, size, bs);
    st.edges_considered = bs.considered;
    st.edges_drawn = bs.drawn;
    for (const Tube& tube : tubes) {
      const Vec3 a = endpoint_position(s, tube.a), b = endpoint_position(s, tube.b);
      const double cap = 0.3 * std::min(endpoint_radius(s, tube.a), endpoint_radius(s, tube.b));
      const double rho = std::min(0.1 * s.median_radius * std::sqrt(tube.w), cap);
      if (!(rho > 0)) continue;
      // The pixel rectangle comes from the part of the segment at least 2 rho in front of the
      // camera (a tube reaching behind it would otherwise cover the whole image); the hits below
      // still use the whole tube, so only a sliver within 2 rho of the eye can be missed.
      Vec3 ea = a, eb = b;
      const double near_d = 2 * rho + kNear;
      const double da = dot(a - v.camera.position, f.forward), db = dot(b - v.camera.position, f.forward);
      if (da < near_d && db < near_d) continue;
      if (da < near_d) ea = a + (b - a) * ((near_d - da) / (db - da));
      if (db < near_d) eb = b + (a - b) * ((near_d - db) / (da - db));
      const Vec3 lo{std::min(ea.x, eb.x) - rho, std::min(ea.y, eb.y) - rho, std::min(ea.z, eb.z) - rho};
      const Vec3 hi{std::max(ea.x, eb.x) + rho, std::max(ea.y, eb.y) + rho, std::max(ea.z, eb.z) + rho};
      const Rect rect = project_box(v, f, lo, hi);
      // Flow: v = sign(A2) |P_ab| cycles per second along the strip (R-1.0 8.2).
      const double p_ab = tube.degree_a > 0 ? tube.w / tube.degree_a : 0.0;
      const double speed = (tube.a2 > 0 ? 1.0 : (tube.a2 < 0 ? -1.0 : 0.0)) * std::fabs(p_ab);
      const double stripes = std::max(1.0, std::round(length(b - a) / (8 * rho)));
      const Vec3 ca = endpoint_color(s, tube.a), cb = endpoint_color(s, tube.b);
      for (int y = rect.y0; y < rect.y1; ++y)
        for (int x = rect.x0; x < rect.x1; ++x) {
          const std::size_t k = static_cast<std::size_t>(y) * W + x;
          const Ray ray = pixel_ray(v, f, x + 0.5, y + 0.5);
          const auto hit = intersect_tube(a, b, rho, ray, kNear, op.t[k]);
          if (!hit) continue;
          const double phase = stripes * hit->u - speed * v.time;
          const double strip = 0.55 + 0.45 * 0.5 * (1 + std::cos(2 * kPi * (phase - std::floor(phase))));
          op.t[k] = hit->hit.t;
          op.color[k] = shade((ca * (1 - hit->u) + cb * hit->u) * (0.6 * strip), hit->hit.normal, ray.d);
          op.owner[k] = -2;
        }
    }
  }
  st.edge_s = seconds_since(t0);

  // Splats: every visible T3 particle, and the handoff band's share of T-inf ones (R1-RND-045).
  t0 = clock::now();
  const std::vector<Vec3> grad = v.splat_stretch > 0 ? u5_gradients(s) : std::vector<Vec3>{};
  std::vector<Splat> splats;
  for (const Visible& vis : visible) {
    if (vis.tier < Tier::kT3) continue;
    const double weight = 1.0 - tinf_weight(vis.s, v.tiers);
    Splat sp;
    if (weight > 0 && make_splat(s, v, f, vis.particle, weight, grad, sp)) splats.push_back(sp);
  }
  st.splats = splats.size();
  // Front to back by depth, ties by particle index (R1-RND-043), binned into tiles.
  std::sort(splats.begin(), splats.end(),
            [](const Splat& a, const Splat& b) { return a.depth != b.depth ? a.depth < b.depth : a.particle < b.particle; });
  const int tiles_x = (W + kTile - 1) / kTile, tiles_y = (H + kTile - 1) / kTile;
  std::vector<std::vector<std::uint32_t>> tiles(static_cast<std::size_t>(tiles_x) * tiles_y);
  for (std::uint32_t i = 0; i < splats.size(); ++i) {
    const double reach = splat_reach(splats[i]);
    const int x0 = std::max(0, static_cast<int>(std::floor((splats[i].px - reach) / kTile)));
    const int x1 = std::min(tiles_x - 1, static_cast<int>(std::floor((splats[i].px + reach) / kTile)));
    const int y0 = std::max(0, static_cast<int>(std::floor((splats[i].py - reach) / kTile)));
    const int y1 = std::min(tiles_y - 1, static_cast<int>(std::floor((splats[i].py + reach) / kTile)));
    for (int ty = y0; ty <= y1; ++ty)
      for (int tx = x0; tx <= x1; ++tx) tiles[static_cast<std::size_t>(ty) * tiles_x + tx].push_back(i);
  }
  st.splat_s = seconds_since(t0);

  // Composite per pixel, front to back in ray order: splats and field samples up to the opaque
  // hit, then the hit (R1-RND-070).
  const FieldFrame ff = make_field_frame(s, v, f, options.field);
  std::vector<FieldSample> samples;
  struct SplatHit {
    double t, alpha;
    std::uint32_t splat;
  };
  std::vector<SplatHit> hits;
  FieldRayStats fs;
  bool any_flow = false;
  std::vector<float> flow(static_cast<std::size_t>(W) * H * 3, 0.0f);
  for (int y = 0; y < H; ++y) {
    if (progress && (y % 16 == 0 || y + 1 == H)) progress("render", static_cast<std::uint64_t>(y + 1), static_cast<std::uint64_t>(H));
    for (int x = 0; x < W; ++x) {
      const std::size_t k = static_cast<std::size_t>(y) * W + x;
      const Ray ray = pixel_ray(v, f, x + 0.5, y + 0.5);
      const double t_op = op.t[k];
      auto c0 = clock::now();
      if (v.field) march_field(ff, ray, t_op, k, samples, &fs);
      else samples.clear();
      auto c1 = clock::now();
      hits.clear();
      const double cos_fwd = dot(ray.d, f.forward);
      for (std::uint32_t i : tiles[static_cast<std::size_t>(y / kTile) * tiles_x + x / kTile]) {
        const double t = splats[i].depth / cos_fwd;
        if (t >= t_op) continue;
        const double a = splat_alpha(splats[i], x + 0.5, y + 0.5);
        if (a >= kMinAlpha) hits.push_back({t, a, i});
      }
      // Tile lists are in depth order; the ray parameter keeps it (t = depth / cos).
      Vec3 color, fl;
      double T = 1;
      std::size_t i = 0, j = 0;
      while ((i < samples.size() || j < hits.size()) && T > 1e-4) {
        const bool take_splat = j < hits.size() && (i >= samples.size() || hits[j].t <= samples[i].t);
        if (take_splat) {
          const SplatHit& h = hits[j++];
          color += splats[h.splat].color * (T * h.alpha);
          T *= 1 - h.alpha;
        } else {
          const FieldSample& fsmp = samples[i++];
          color += fsmp.color * (T * fsmp.alpha);
          fl += fsmp.flow * (T * fsmp.alpha);
          T *= 1 - fsmp.alpha;
        }
      }
      if (t_op < kInf) {
        color += op.color[k] * T;
        T = 0;
      }
      float* px = image.px(x, y);
      px[0] = static_cast<float>(color.x);
      px[1] = static_cast<float>(color.y);
      px[2] = static_cast<float>(color.z);
      px[3] = static_cast<float>(1 - T);
      if (fl.x != 0 || fl.y != 0 || fl.z != 0) any_flow = true;
      flow[k * 3] = static_cast<float>(fl.x), flow[k * 3 + 1] = static_cast<float>(fl.y), flow[k * 3 + 2] = static_cast<float>(fl.z);
      auto c2 = clock::now();
      st.field_s += std::chrono::duration<double>(c1 - c0).count();
      st.splat_s += std::chrono::duration<double>(c2 - c1).count();
    }
  }
  if (any_flow) image.flow = std::move(flow);
  image.depth = op.t;
  st.field_candidates = fs.candidates;
  st.field_evaluations = fs.evaluations;

  // Labels at T1 (and T0, drawn as T1): title or hex prefix beside the particle, far ones first,
  // only where the particle itself is the nearest surface at its centre (R1-RND-067).
  t0 = clock::now();
  if (v.labels) {
    std::vector<const Visible*> labelled;
    for (const Visible& vis : visible)
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
      R1_TRY(draw_text(image, static_cast<int>(pr.px + half * 0.75) + 4, cy + text_px / 3, s.label[vis->particle], text_px,
                       {0.85f, 0.85f, 0.85f}));
      ++st.labels;
    }
  }
  st.label_s = seconds_since(t0);
  st.total_s = seconds_since(start);
  if (stats_out) *stats_out = st;
  return image;
}

}  // namespace r1::render
