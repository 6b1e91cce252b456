// The T-infinity ground-truth field and its ray march (R1-RND-050..058).
#include "field.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "neural_field.hpp"
#include "r1/fixedpoint/counter_rng.hpp"

namespace r1::render {

namespace {

// The ray parameters where the ray is within r of c (d is unit length), intersected with [t0, t1]
// (empty: t0 > t1).
void ray_ball(const Ray& ray, const Vec3& c, double r, double& t0, double& t1) {
  const Vec3 oc = ray.o - c;
  const double b = dot(ray.d, oc), disc = b * b - (dot(oc, oc) - r * r);
  if (disc < 0) {
    t0 = 1, t1 = 0;
    return;
  }
  const double q = std::sqrt(disc);
  t0 = std::max(t0, -b - q);
  t1 = std::min(t1, -b + q);
}

// Whether a node can matter at x: some member with field weight lies within cutoff sigma of x
// (the members lie within `extent` of the centroid).
bool within_reach(const Vec3& x, const Vec3& centroid, double extent, double reach) {
  const Vec3 d = x - centroid;
  return dot(d, d) <= (extent + reach) * (extent + reach);
}

// R1-RND-054's cut grows with the particle count so that the kernels it drops weigh at most
// 1 / kCutoffMass of a mean particle's weight in all (n e^(-c^2/2) <= 1 / kCutoffMass, the weights
// n phi summing to n): c = max(cutoff, sqrt(2 ln(kCutoffMass n))), the given 5 up to 8,385 particles.
constexpr double kCutoffMass = 32.0;

// Sums weight * exp(-|center - x|^2 / (2 sigma^2)); a kernel whose exponent exceeds max_q is
// skipped (a particle farther than cutoff sigma: max_q = cutoff^2 / 2, within R1-RND-055's bound).
struct Accumulator {
  double w = 0;
  Vec3 c, f;
  std::uint64_t kernels = 0;
  void add(double weight, const Vec3& center, const Vec3& color, const Vec3& x, double inv2s2,
           double max_q = std::numeric_limits<double>::infinity()) {
    const Vec3 d = center - x;
    const double q = dot(d, d) * inv2s2;
    if (q > max_q) return;
    ++kernels;
    const double k = weight * std::exp(-q);
    w += k;
    c += color * k;
    f += d * k;
  }
  // A node taken whole (R1-RND-055): its kernel at the centroid, with the colour its spread gives
  // at x (inv2s2 = 1 / (2 sigma^2), so (x - centroid) 2 inv2s2 = (x - centroid) / sigma^2).
  void add_node(double weight, const Vec3& centroid, const Vec3& color, const ColourSpread& spread, const Vec3& x,
                double inv2s2) {
    add(weight, centroid, spread.at(color, (x - centroid) * (2 * inv2s2)), x, inv2s2);
  }
  FieldValue value(double kappa, double sigma) const {
    FieldValue v;
    v.weight = w;
    v.density = kappa / sigma * w;
    v.kernels = kernels;
    if (w > 0) {
      v.color = c / w;
      v.flow = f / w;
    }
    return v;
  }
};

// Every field member of level-0 node `id` within cutoff sigma of x, one kernel each.
void add_members(const FieldFrame& ff, std::uint32_t id, const Vec3& x, double inv2s2, Accumulator& acc) {
  const double max_q = 0.5 * ff.params.cutoff * ff.params.cutoff;
  const std::uint32_t slot = ff.slot[0].empty() ? FieldFrame::kFarSlot : ff.slot[0][id];
  if (slot == FieldFrame::kBehindSlot) return;
  if (slot == FieldFrame::kFarSlot) {
    const Scene& s = *ff.scene;
    const double n = s.n;
    for (std::uint32_t q : s.hierarchy->levels[0][id].children) {
      const double w = n * s.phi[q];
      if (w > 0) acc.add(w, s.position[q], s.color[q], x, inv2s2, max_q);
    }
    return;
  }
  const auto [begin, end] = ff.member_range[slot];
  for (std::uint32_t k = begin; k < end; ++k) {
    const FieldFrame::Member& m = ff.members[k];
    acc.add(m.weight, m.position, m.color, x, inv2s2, max_q);
  }
}

}  // namespace

double tinf_weight(double s, const Tiers& t) {
  if (s <= t.t3 - t.band) return 1;
  if (s >= t.t3 + t.band || t.band <= 0) return 0;
  return (t.t3 + t.band - s) / (2 * t.band);
}

double FieldFrame::weight(std::uint32_t p) const {
  const Scene& s = *scene;
  const double depth = dot(s.position[p] - camera, frame.forward);
  const double sz = depth > s.radius[p] + kNear ? screen_diameter(s.radius[p], depth, frame) : 1e300;
  return tinf_weight(sz, tiers) * static_cast<double>(s.n) * s.phi[p];
}

NodeField FieldFrame::node(int level, std::uint32_t id) const {
  const auto L = static_cast<std::size_t>(level);
  const std::uint32_t k = slot[L].empty() ? kFarSlot : slot[L][id];
  if (k == kBehindSlot) return {};
  if (k != kFarSlot) {
    NodeField nf = mixed[k];
    nf.spread = &mixed_spread[k];
    return nf;
  }
  const NodeData& d = scene->nodes[L][id];
  return {static_cast<double>(scene->n) * d.phi, d.centroid, d.color, d.extent, &d.spread};
}

double field_cutoff(double cutoff, std::uint32_t n) {
  return std::max(cutoff, std::sqrt(2.0 * std::log(kCutoffMass * static_cast<double>(n))));
}

FieldFrame make_field_frame(const Scene& s, const View& v, const CameraFrame& f, const FieldParams& given) {
  FieldFrame ff;
  ff.scene = &s;
  ff.params = given;
  ff.params.cutoff = field_cutoff(given.cutoff, s.n);
  const FieldParams& p = ff.params;
  ff.frame = f;
  ff.camera = v.camera.position;
  ff.tiers = v.tiers;
  if (s.neural != nullptr) ff.neural = std::make_shared<const NeuralInference>(*s.neural);
  // Classify from the top; only kMixed nodes are opened and get aggregates of their own, over
  // their members with field weight > 0 (weights, centroid, colour, extent; R1-RND-054).
  // Every node under a kBehind one is marked kBehind too (a walk never opens them, but node()
  // answers for every node); nothing under a kFar node is visited.
  struct Entry {
    int level;
    std::uint32_t id;
    bool behind;  // under a kBehind node
  };
  std::vector<Entry> stack;
  auto open = [&](int l, std::uint32_t id, bool behind) {
    const auto below = static_cast<std::size_t>(l - 1);
    if (ff.slot[below].empty()) ff.slot[below].assign(s.nodes[below].size(), FieldFrame::kFarSlot);
    for (std::uint32_t child : s.hierarchy->levels[static_cast<std::size_t>(l)][id].children)
      stack.push_back({l - 1, child, behind});
  };
  const std::size_t top = s.nodes[kLevels - 1].size();
  ff.slot[kLevels - 1].assign(top, FieldFrame::kFarSlot);
  for (std::uint32_t id = 0; id < top; ++id) stack.push_back({kLevels - 1, id, false});
  while (!stack.empty()) {
    const auto [l, id, under_behind] = stack.back();
    stack.pop_back();
    const auto L = static_cast<std::size_t>(l);
    const FarClass c = under_behind ? FarClass::kBehind : far_class(s.nodes[L][id], v, f);
    if (c != FarClass::kMixed) {
      ff.slot[L][id] = c == FarClass::kFar ? FieldFrame::kFarSlot : FieldFrame::kBehindSlot;
      if (c == FarClass::kBehind && l > 0) open(l, id, true);
      continue;
    }
    NodeField nf;
    ColourSpread spread;
    for_each_member(s, l, id, [&](std::uint32_t q) {
      const double w = ff.weight(q);
      if (!(w > 0)) return;
      nf.weight += w;
      nf.centroid += s.position[q] * w;
      nf.color += s.color[q] * w;
    });
    if (nf.weight > 0) {
      nf.centroid = nf.centroid / nf.weight;
      nf.color = nf.color / nf.weight;
      for_each_member(s, l, id, [&](std::uint32_t q) {
        const double w = ff.weight(q);
        if (!(w > 0)) return;
        nf.extent = std::max(nf.extent, length(s.position[q] - nf.centroid));
        spread.add(w / nf.weight, s.color[q], nf.color, s.position[q] - nf.centroid);
      });
    }
    ff.slot[L][id] = static_cast<std::uint32_t>(ff.mixed.size());
    ff.mixed.push_back(nf);
    ff.mixed_spread.push_back(spread);
    if (l == 0) {
      const auto begin = static_cast<std::uint32_t>(ff.members.size());
      for (std::uint32_t q : s.hierarchy->levels[0][id].children) {
        const double w = ff.weight(q);
        if (w > 0) ff.members.push_back({s.position[q], s.color[q], w});
      }
      ff.member_range.resize(ff.mixed.size());
      ff.member_range.back() = {begin, static_cast<std::uint32_t>(ff.members.size())};
      continue;
    }
    open(l, id, false);
  }
  const double dist = length(v.camera.position - s.centroid);
  const double g = 1.0 + dist / static_cast<double>(kSceneRadius);
  ff.tau_cam = s.tau0 * g * g;
  double far = 0;
  for (const NodeData& d : s.nodes[kLevels - 1])
    for (int c = 0; c < 8; ++c) {
      const Vec3 corner{c & 1 ? d.hi.x : d.lo.x, c & 2 ? d.hi.y : d.lo.y, c & 4 ? d.hi.z : d.lo.z};
      far = std::max(far, length(corner - v.camera.position));
    }
  ff.t_far = std::max(far, 1.0);
  // Grow by the widest kernel at that distance so the tails of the farthest particles are inside.
  ff.t_far += p.cutoff * field_sigma(ff, ff.t_far);
  // Tile lists of top-level nodes. sigma grows along the ray, so cutoff sigma(t_far) bounds every
  // ray's grow; a ray meeting the grown ball passes through its projection (R1-RND-057).
  const double grow = p.cutoff * field_sigma(ff, ff.t_far);
  ff.width = v.width;
  ff.tiles_x = (v.width + FieldFrame::kTile - 1) / FieldFrame::kTile;
  const int tiles_y = (v.height + FieldFrame::kTile - 1) / FieldFrame::kTile;
  ff.top_by_tile.assign(static_cast<std::size_t>(ff.tiles_x) * static_cast<std::size_t>(tiles_y), {});
  for (std::uint32_t id = 0; id < top; ++id) {
    const NodeField nd = ff.node(kLevels - 1, id);
    if (nd.weight <= 0) continue;
    const double r = nd.extent + grow;
    const Rect box = project_box(v, f, nd.centroid - Vec3{r, r, r}, nd.centroid + Vec3{r, r, r});
    if (box.empty()) continue;
    const int x0 = std::max(box.x0 - 1, 0) / FieldFrame::kTile, x1 = std::min(box.x1, v.width - 1) / FieldFrame::kTile;
    const int y0 = std::max(box.y0 - 1, 0) / FieldFrame::kTile, y1 = std::min(box.y1, v.height - 1) / FieldFrame::kTile;
    for (int ty = y0; ty <= y1; ++ty)
      for (int tx = x0; tx <= x1; ++tx) ff.top_by_tile[static_cast<std::size_t>(ty * ff.tiles_x + tx)].push_back(id);
  }
  return ff;
}

double field_sigma(const FieldFrame& ff, double t) {
  const double tau = ff.tau_cam * std::max(t, 0.0) / ff.t_far;
  return std::max(std::sqrt(tau), 0.5 * std::max(t, 0.0) / ff.frame.focal_px + 1e-9);
}

FieldValue field_exact(const FieldFrame& ff, const Vec3& x, double sigma) {
  const Scene& s = *ff.scene;
  Accumulator acc;
  const double inv = 1.0 / (2 * sigma * sigma);
  for (std::uint32_t p = 0; p < s.n; ++p) {
    const double w = ff.weight(p);
    if (w > 0) acc.add(w, s.position[p], s.color[p], x, inv);
  }
  return acc.value(ff.params.kappa, sigma);
}

namespace {

// The walk of R1-RND-054 with its acceptance as a parameter: `accept(centroid, extent)` says
// whether a node within reach of x is one Gaussian.
template <class Accept>
FieldValue walk_field(const FieldFrame& ff, const Vec3& x, double sigma, Accept accept) {
  Accumulator acc;
  const double inv = 1.0 / (2 * sigma * sigma);
  const double reach = ff.params.cutoff * sigma;
  if (ff.far_tree) {
    // The same walk over the particles' octree (FieldFrame::FarTree, the training targets').
    const FieldFrame::FarTree& t = *ff.far_tree;
    const double max_q = 0.5 * ff.params.cutoff * ff.params.cutoff;
    thread_local std::vector<std::uint32_t> stack;
    stack.clear();
    for (std::uint32_t id = 0; id < t.roots; ++id) stack.push_back(id);
    while (!stack.empty()) {
      const std::uint32_t id = stack.back();
      stack.pop_back();
      const FieldFrame::FarTree::Node& nd = t.nodes[id];
      if (nd.weight <= 0 || !within_reach(x, nd.centroid, nd.extent, reach)) continue;
      if (accept(nd.centroid, nd.extent)) {
        acc.add(nd.weight, nd.centroid, t.color[id], x, inv);
        continue;
      }
      const std::uint32_t end = nd.first + nd.count;
      if (nd.leaf) {
        for (std::uint32_t k = nd.first; k < end; ++k) {
          const FieldFrame::Member& m = t.members[k];
          acc.add(m.weight, m.position, m.color, x, inv, max_q);
        }
        continue;
      }
      for (std::uint32_t c = nd.first; c < end; ++c) stack.push_back(c);
    }
    return acc.value(ff.params.kappa, sigma);
  }
  const Scene& s = *ff.scene;
  std::vector<std::pair<int, std::uint32_t>> stack;
  for (std::uint32_t id = 0; id < s.nodes[kLevels - 1].size(); ++id) stack.push_back({kLevels - 1, id});
  while (!stack.empty()) {
    const auto [l, id] = stack.back();
    stack.pop_back();
    const auto L = static_cast<std::size_t>(l);
    const NodeField nd = ff.node(l, id);
    if (nd.weight <= 0 || !within_reach(x, nd.centroid, nd.extent, reach)) continue;
    if (accept(nd.centroid, nd.extent)) {
      acc.add_node(nd.weight, nd.centroid, nd.color, *nd.spread, x, inv);
      continue;
    }
    if (l == 0) {
      add_members(ff, id, x, inv, acc);
      continue;
    }
    for (std::uint32_t c : s.hierarchy->levels[L][id].children) stack.push_back({l - 1, c});
  }
  return acc.value(ff.params.kappa, sigma);
}

// R1-RND-060's table: M(u0) = the least upper bound over u >= u0 of max(g(u), h(u) / h_max), with
// g(u) = e^(-u^2/2) max(1, |u^2 - 1|) (sigma^2 times the Gaussian's Hessian norm at distance u
// sigma) and h(u) = u (2 e^(-u^2/2) + g(u)) (the same for the flow's numerator), at u0 = i / 32.
// Sampled every 1/1024 and taken as a suffix maximum plus 0.002 (g and h / h_max move by under
// 0.001 within a sample step), so M at floor(32 u0) / 32 is at least the supremum from u0 on.
// Near x it is the plain rule (M(0) > 1, and a node within theta sigma is taken whole anyway).
constexpr int kGradedSteps = 32, kGradedFine = 1024;
constexpr double kGradedEnd = 8.0, kGradedMargin = 0.002;
const std::vector<double>& graded_table() {
  static const std::vector<double> table = [] {
    const int fine = static_cast<int>(kGradedEnd * kGradedFine);
    auto g = [](double u) { return std::exp(-0.5 * u * u) * std::max(1.0, std::fabs(u * u - 1)); };
    auto h = [&](double u) { return u * (2 * std::exp(-0.5 * u * u) + g(u)); };
    double h_max = 0;
    for (int i = 0; i <= fine; ++i) h_max = std::max(h_max, h(static_cast<double>(i) / kGradedFine));
    std::vector<double> sup(static_cast<std::size_t>(fine) + 2, 0.0);
    for (int i = fine; i >= 0; --i) {
      const double u = static_cast<double>(i) / kGradedFine;
      sup[static_cast<std::size_t>(i)] = std::max({sup[static_cast<std::size_t>(i) + 1], g(u), h(u) / h_max});
    }
    std::vector<double> out(static_cast<std::size_t>(kGradedEnd * kGradedSteps) + 1);
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = sup[i * (kGradedFine / kGradedSteps)] + kGradedMargin;
    return out;
  }();
  return table;
}

}  // namespace

FieldValue field_hierarchical(const FieldFrame& ff, const Vec3& x, double sigma) {
  const double limit = ff.params.theta * sigma;
  return walk_field(ff, x, sigma, [limit](const Vec3&, double extent) { return extent <= limit; });
}

FieldValue field_graded(const FieldFrame& ff, const Vec3& x, double sigma) {
  const std::vector<double>& table = graded_table();
  const double limit2 = (ff.params.theta * sigma) * (ff.params.theta * sigma);
  return walk_field(ff, x, sigma, [&](const Vec3& centroid, double extent) {
    const double e2 = extent * extent;
    if (e2 <= limit2) return true;  // the plain rule (M <= 1 at every distance)
    const double gap = std::max(0.0, length(x - centroid) - extent) / sigma;
    const auto i = static_cast<std::size_t>(std::min(gap, kGradedEnd) * kGradedSteps);
    return e2 * table[i] <= limit2;
  });
}

double field_error_bound(const FieldFrame& ff, double sigma) {
  double total = 0;
  for (std::uint32_t p = 0; p < ff.scene->n; ++p) total += ff.weight(p);
  const double per_weight = 0.5 * ff.params.theta * ff.params.theta + std::exp(-0.5 * ff.params.cutoff * ff.params.cutoff);
  return ff.params.kappa / sigma * total * per_weight;
}

void march_field(const FieldFrame& ff, const Ray& ray, double t_max, std::uint64_t pixel, std::vector<FieldSample>& out,
                 FieldRayStats* stats) {
  out.clear();
  const Scene& s = *ff.scene;
  const FieldParams& p = ff.params;
  const double t_end = std::min(t_max, ff.t_far);
  if (!(t_end > kNear)) return;
  // The neural field stands for the far field with every particle at weight n phi, so it draws
  // only frames that are pure T-infinity (no node mixed with nearer tiers, R1-NRF-031).
  const bool neural = s.neural != nullptr && ff.mixed.empty();
  const double grow = p.cutoff * field_sigma(ff, t_end);
  if (neural && p.literal) {
    // The literal march (R1-NRF-033): the strata span the ray's chord through the ball about the
    // field's cube that holds every kernel reaching into it, [t_c - r, t_c + r] with t_c the
    // ray's closest approach to the cube's centre, also for a ray that misses the ball (whose
    // samples no particle reaches), so every pixel costs the same.
    const NeuralField& nf = *s.neural;
    const double half = nf.size / 2;
    const Vec3 centre = nf.lo + Vec3{half, half, half};
    const double r = half * std::sqrt(3.0) + grow;
    const double tc = dot(centre - ray.o, ray.d);
    const double a = std::max(kNear, tc - r), b = std::min(t_end, std::max(tc + r, a + 2 * r));
    const double delta = (b - a) / p.samples;
    for (int i = 0; i < p.samples; ++i) {
      const double t = a + (i + rng::uniform_double(s.seed, pixel, static_cast<std::uint64_t>(i))) * delta;
      const double sigma = field_sigma(ff, t);
      const Vec3 x = ray.at(t);
      const FieldValue v = ff.neural ? ff.neural->evaluate(x, sigma) : nf.evaluate(x, sigma);
      if (stats) ++stats->samples, ++stats->neural;
      // Where no particle can reach, the analytic field is 0 (its kernels end at cutoff sigma,
      // R1-RND-054) and so is this one; evaluated first all the same, so every sample costs one
      // evaluation.
      const bool reach = nf.may_reach(x, p.cutoff * sigma);  // tested for every sample: the same work
      if (!(v.weight > 0) || !reach) continue;
      out.push_back({t, 1.0 - std::exp(-v.density * delta), v.color, v.flow});
    }
    return;
  }
  // Candidates: nodes whose box grown by the widest kernel on this ray meets the ray (R1-RND-057).
  struct Candidate {
    int level;
    std::uint32_t id;
    bool aggregate;
    double t0, t1;  // the ray in the node's ball grown by the widest kernel on the ray
    double u0, u1;  // within that, where a sample can reach the node (empty: u0 > u1)
    NodeField node;
  };
  std::vector<Candidate> cands;
  std::vector<std::pair<int, std::uint32_t>> stack;
  const std::uint64_t tile = ff.width > 0 ? (pixel / static_cast<std::uint64_t>(ff.width)) / FieldFrame::kTile *
                                                     static_cast<std::uint64_t>(ff.tiles_x) +
                                                 (pixel % static_cast<std::uint64_t>(ff.width)) / FieldFrame::kTile
                                           : 0;
  if (tile >= ff.top_by_tile.size()) {
    for (std::uint32_t id = 0; id < s.nodes[kLevels - 1].size(); ++id) stack.push_back({kLevels - 1, id});
  } else {
    for (std::uint32_t id : ff.top_by_tile[tile]) stack.push_back({kLevels - 1, id});
  }
  double a = t_end, b = kNear;
  while (!stack.empty()) {
    const auto [l, id] = stack.back();
    stack.pop_back();
    if (stats) ++stats->walked;
    const NodeField nd = ff.node(l, id);
    if (nd.weight <= 0) continue;  // nothing of it is in the field this frame
    double t0 = kNear, t1 = t_end;
    ray_ball(ray, nd.centroid, nd.extent + grow, t0, t1);
    if (t0 > t1) continue;
    const bool aggregate = nd.extent <= p.theta * field_sigma(ff, t0);
    if (aggregate || l == 0) {
      // A sample at t <= t1 reaches at most cutoff sigma(t1) (sigma grows with t), so the node
      // is out of reach outside its ball grown by that much: near nodes leave the active list
      // where the widest kernel alone kept them (padded against the ball's rounding). [t0, t1]
      // still sets the strata and the order, so every sample and sum is the same.
      double u0 = t0, u1 = t1;
      const double g1 = p.cutoff * field_sigma(ff, t1);
      if (g1 < grow) {
        const double r = nd.extent + g1;
        ray_ball(ray, nd.centroid, r + 1e-6 * (r + length(nd.centroid - ray.o)), u0, u1);
      }
      cands.push_back({l, id, aggregate, t0, t1, u0, u1, nd});
      a = std::min(a, t0);
      b = std::max(b, t1);
      continue;
    }
    for (std::uint32_t c : s.hierarchy->levels[static_cast<std::size_t>(l)][id].children) stack.push_back({l - 1, c});
  }
  if (stats) stats->candidates += cands.size();
  if (cands.empty() || !(b > a)) return;
  // Sweep: an active list of the candidates whose [u0, u1] may hold the current sample, kept in
  // order of entry t0 (ties by level and id); they enter by u0. Candidates no sample can reach
  // only set the strata. The march usually saturates long before the last candidate is reached.
  const auto before = [](const Candidate* x, const Candidate* y) {
    return x->t0 != y->t0 ? x->t0 < y->t0 : (x->level != y->level ? x->level < y->level : x->id < y->id);
  };
  std::vector<const Candidate*> entering;
  entering.reserve(cands.size());
  for (const Candidate& c : cands)
    if (c.u0 <= c.u1) entering.push_back(&c);
  std::sort(entering.begin(), entering.end(),
            [&before](const Candidate* x, const Candidate* y) { return x->u0 != y->u0 ? x->u0 < y->u0 : before(x, y); });
  std::vector<const Candidate*> active;
  std::size_t next = 0;
  const double delta = (b - a) / p.samples;
  double transmittance = 1;
  for (int i = 0; i < p.samples && transmittance >= p.stop; ++i) {
    const double t = a + (i + rng::uniform_double(s.seed, pixel, static_cast<std::uint64_t>(i))) * delta;
    const double sigma = field_sigma(ff, t);
    const double inv = 1.0 / (2 * sigma * sigma);
    const double reach = p.cutoff * sigma;
    for (; next < entering.size() && entering[next]->u0 <= t; ++next)
      active.insert(std::upper_bound(active.begin(), active.end(), entering[next], before), entering[next]);
    std::erase_if(active, [t](const Candidate* c) { return c->u1 < t; });
    if (active.empty()) {
      // No node reaches this sample: skip to the stratum of the next entry (exact: such samples
      // add nothing, and every sample's jitter depends only on its own index).
      if (next == entering.size()) break;
      const double stratum = std::floor((entering[next]->u0 - a) / delta);
      if (stratum > i) i = static_cast<int>(std::min(stratum, static_cast<double>(p.samples))) - 1;
      continue;
    }
    const Vec3 x = ray.at(t);
    if (stats) ++stats->samples;
    FieldValue v;
    if (neural) {
      // The neural field (R1-NRF-031): evaluated where some candidate is within reach, the same
      // samples the analytic field would sum kernels at.
      const bool near = std::any_of(active.begin(), active.end(), [&](const Candidate* c) {
        return within_reach(x, c->node.centroid, c->node.extent, reach);
      });
      if (!near) continue;
      v = ff.neural ? ff.neural->evaluate(x, sigma) : s.neural->evaluate(x, sigma);
      if (stats) ++stats->neural;
    } else {
      Accumulator acc;
      for (const Candidate* cp : active) {
        const Candidate& c = *cp;
        if (!within_reach(x, c.node.centroid, c.node.extent, reach)) continue;
        if (c.aggregate) {
          acc.add_node(c.node.weight, c.node.centroid, c.node.color, *c.node.spread, x, inv);
          continue;
        }
        add_members(ff, c.id, x, inv, acc);
      }
      if (stats) stats->evaluations += acc.kernels;
      v = acc.value(p.kappa, sigma);
    }
    if (!(v.weight > 0)) continue;  // nothing of the field reaches this sample
    const double alpha = 1.0 - std::exp(-v.density * delta);
    out.push_back({t, alpha, v.color, v.flow});
    transmittance *= 1.0 - alpha;
  }
}

}  // namespace r1::render
