// The T-infinity ground-truth field and its ray march (R1-RND-050..058).
#include "field.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

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
  FieldValue value(double kappa, double sigma) const {
    FieldValue v;
    v.weight = w;
    v.density = kappa / sigma * w;
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
  for (std::uint32_t k = ff.member_begin[id]; k < ff.member_begin[id + 1]; ++k) {
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

FieldFrame make_field_frame(const Scene& s, const View& v, const CameraFrame& f, const FieldParams& p) {
  FieldFrame ff;
  ff.scene = &s;
  ff.params = p;
  ff.focal_px = f.focal_px;
  ff.weight.resize(s.n);
  const double n = s.n;
  for (std::uint32_t i = 0; i < s.n; ++i) {
    const double depth = dot(s.position[i] - v.camera.position, f.forward);
    const double sz = depth > s.radius[i] + kNear ? screen_diameter(s.radius[i], depth, f) : 1e300;
    ff.weight[i] = tinf_weight(sz, v.tiers) * n * s.phi[i];
  }
  // Node aggregates over the members in the field this frame (weights, centroid, colour, extent).
  for (std::size_t l = 0; l < kLevels; ++l) {
    const std::size_t count = s.hierarchy->levels[l].size();
    ff.node_weight[l].assign(count, 0.0);
    ff.node_centroid[l].assign(count, Vec3{});
    ff.node_color[l].assign(count, Vec3{});
    ff.node_extent[l].assign(count, 0.0);
  }
  for (std::uint32_t i = 0; i < s.n; ++i) {
    if (!(ff.weight[i] > 0)) continue;
    for (std::size_t l = 0; l < kLevels; ++l) {
      const std::uint32_t id = s.hierarchy->cluster_of[l][i];
      ff.node_weight[l][id] += ff.weight[i];
      ff.node_centroid[l][id] += s.position[i] * ff.weight[i];
      ff.node_color[l][id] += s.color[i] * ff.weight[i];
    }
  }
  for (std::size_t l = 0; l < kLevels; ++l)
    for (std::size_t id = 0; id < ff.node_weight[l].size(); ++id)
      if (ff.node_weight[l][id] > 0) {
        ff.node_centroid[l][id] = ff.node_centroid[l][id] / ff.node_weight[l][id];
        ff.node_color[l][id] = ff.node_color[l][id] / ff.node_weight[l][id];
      }
  for (std::uint32_t i = 0; i < s.n; ++i) {
    if (!(ff.weight[i] > 0)) continue;
    for (std::size_t l = 0; l < kLevels; ++l) {
      const std::uint32_t id = s.hierarchy->cluster_of[l][i];
      ff.node_extent[l][id] = std::max(ff.node_extent[l][id], length(s.position[i] - ff.node_centroid[l][id]));
    }
  }
  const auto& level0 = s.hierarchy->levels[0];
  ff.member_begin.assign(level0.size() + 1, 0);
  for (std::size_t id = 0; id < level0.size(); ++id) {
    for (std::uint32_t q : level0[id].children)
      if (ff.weight[q] > 0) ff.members.push_back({s.position[q], s.color[q], ff.weight[q]});
    ff.member_begin[id + 1] = static_cast<std::uint32_t>(ff.members.size());
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
  return ff;
}

double field_sigma(const FieldFrame& ff, double t) {
  const double tau = ff.tau_cam * std::max(t, 0.0) / ff.t_far;
  return std::max(std::sqrt(tau), 0.5 * std::max(t, 0.0) / ff.focal_px + 1e-9);
}

FieldValue field_exact(const FieldFrame& ff, const Vec3& x, double sigma) {
  const Scene& s = *ff.scene;
  Accumulator acc;
  const double inv = 1.0 / (2 * sigma * sigma);
  for (std::uint32_t p = 0; p < s.n; ++p)
    if (ff.weight[p] > 0) acc.add(ff.weight[p], s.position[p], s.color[p], x, inv);
  return acc.value(ff.params.kappa, sigma);
}

FieldValue field_hierarchical(const FieldFrame& ff, const Vec3& x, double sigma) {
  const Scene& s = *ff.scene;
  Accumulator acc;
  const double inv = 1.0 / (2 * sigma * sigma);
  const double reach = ff.params.cutoff * sigma;
  std::vector<std::pair<int, std::uint32_t>> stack;
  for (std::uint32_t id = 0; id < s.nodes[kLevels - 1].size(); ++id) stack.push_back({kLevels - 1, id});
  while (!stack.empty()) {
    const auto [l, id] = stack.back();
    stack.pop_back();
    const auto L = static_cast<std::size_t>(l);
    if (ff.node_weight[L][id] <= 0 || !within_reach(x, ff.node_centroid[L][id], ff.node_extent[L][id], reach)) continue;
    if (ff.node_extent[L][id] <= ff.params.theta * sigma) {
      acc.add(ff.node_weight[L][id], ff.node_centroid[L][id], ff.node_color[L][id], x, inv);
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

double field_error_bound(const FieldFrame& ff, double sigma) {
  double total = 0;
  for (double w : ff.weight) total += w;
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
  const double grow = p.cutoff * field_sigma(ff, t_end);
  // Candidates: nodes whose box grown by the widest kernel on this ray meets the ray (R1-RND-057).
  struct Candidate {
    int level;
    std::uint32_t id;
    bool aggregate;
    double t0, t1;
  };
  std::vector<Candidate> cands;
  std::vector<std::pair<int, std::uint32_t>> stack;
  for (std::uint32_t id = 0; id < s.nodes[kLevels - 1].size(); ++id) stack.push_back({kLevels - 1, id});
  double a = t_end, b = kNear;
  while (!stack.empty()) {
    const auto [l, id] = stack.back();
    stack.pop_back();
    if (stats) ++stats->walked;
    const auto L = static_cast<std::size_t>(l);
    if (ff.node_weight[L][id] <= 0) continue;  // nothing of it is in the field this frame
    double t0 = kNear, t1 = t_end;
    ray_ball(ray, ff.node_centroid[L][id], ff.node_extent[L][id] + grow, t0, t1);
    if (t0 > t1) continue;
    const bool aggregate = ff.node_extent[L][id] <= p.theta * field_sigma(ff, t0);
    if (aggregate || l == 0) {
      cands.push_back({l, id, aggregate, t0, t1});
      a = std::min(a, t0);
      b = std::max(b, t1);
      continue;
    }
    for (std::uint32_t c : s.hierarchy->levels[static_cast<std::size_t>(l)][id].children) stack.push_back({l - 1, c});
  }
  if (stats) stats->candidates += cands.size();
  if (cands.empty() || !(b > a)) return;
  // Sweep: candidates in order of entry (ties by level and id), an active list of those whose
  // interval may hold the current sample, kept in that order; the march usually saturates long
  // before the last candidate is reached.
  std::sort(cands.begin(), cands.end(), [](const Candidate& x, const Candidate& y) {
    return x.t0 != y.t0 ? x.t0 < y.t0 : (x.level != y.level ? x.level < y.level : x.id < y.id);
  });
  std::vector<const Candidate*> active;
  std::size_t next = 0;
  const double delta = (b - a) / p.samples;
  double transmittance = 1;
  for (int i = 0; i < p.samples && transmittance >= p.stop; ++i) {
    const double t = a + (i + rng::uniform_double(s.seed, pixel, static_cast<std::uint64_t>(i))) * delta;
    const double sigma = field_sigma(ff, t);
    const double inv = 1.0 / (2 * sigma * sigma);
    const double reach = p.cutoff * sigma;
    while (next < cands.size() && cands[next].t0 <= t) active.push_back(&cands[next++]);
    std::erase_if(active, [t](const Candidate* c) { return c->t1 < t; });
    if (active.empty()) {
      // No node reaches this sample: skip to the stratum of the next entry (exact: such samples
      // add nothing, and every sample's jitter depends only on its own index).
      if (next == cands.size()) break;
      const double stratum = std::floor((cands[next].t0 - a) / delta);
      if (stratum > i) i = static_cast<int>(std::min(stratum, static_cast<double>(p.samples))) - 1;
      continue;
    }
    const Vec3 x = ray.at(t);
    if (stats) ++stats->samples;
    Accumulator acc;
    for (const Candidate* cp : active) {
      const Candidate& c = *cp;
      const auto L = static_cast<std::size_t>(c.level);
      if (!within_reach(x, ff.node_centroid[L][c.id], ff.node_extent[L][c.id], reach)) continue;
      if (c.aggregate) {
        acc.add(ff.node_weight[L][c.id], ff.node_centroid[L][c.id], ff.node_color[L][c.id], x, inv);
        continue;
      }
      add_members(ff, c.id, x, inv, acc);
    }
    if (stats) stats->evaluations += acc.kernels;
    if (acc.w <= 0) continue;
    const FieldValue v = acc.value(p.kappa, sigma);
    const double alpha = 1.0 - std::exp(-v.density * delta);
    out.push_back({t, alpha, v.color, v.flow});
    transmittance *= 1.0 - alpha;
  }
}

}  // namespace r1::render
