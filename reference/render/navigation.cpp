// Navigation rules of spec/viewer.md R1-VIEW-020..032 (see navigation.hpp).
#include "render/navigation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "r1/spec/epoch.hpp"
#include "render/view.hpp"

namespace r1::render {

namespace {

char lower(char c) { return (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c; }

std::string lowered(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = lower(c);
  return out;
}

bool is_hex(std::string_view s) {
  return std::all_of(s.begin(), s.end(), [](char c) {
    return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f') || (c >= 'A' && c <= 'F');
  });
}

std::string_view trimmed(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

}  // namespace

Result<std::uint32_t> find_particle(const std::vector<hemera::Digest>& ids, const std::vector<std::string>& titles,
                                    const std::vector<double>& phi, std::string_view query) {
  const std::string_view q = trimmed(query);
  if (q.empty()) return Status::input("warp: the query is empty");
  const std::size_t n = ids.size();
  // The first rule with a match picks; among its matches the highest phi, then the lower index.
  std::optional<std::uint32_t> best;
  const auto offer = [&](std::uint32_t p) {
    if (!best || phi[p] > phi[*best]) best = p;
  };
  if (q.size() <= 64 && is_hex(q)) {
    const std::string prefix = lowered(q);
    for (std::uint32_t p = 0; p < n; ++p)
      if (hemera::to_hex(ids[p]).compare(0, prefix.size(), prefix) == 0) offer(p);
    if (best) return *best;
  }
  for (std::uint32_t p = 0; p < n; ++p)
    if (titles[p] == q) offer(p);
  if (best) return *best;
  const std::string lq = lowered(q);
  for (std::uint32_t p = 0; p < n; ++p)
    if (lowered(titles[p]) == lq) offer(p);
  if (best) return *best;
  for (std::uint32_t p = 0; p < n; ++p)
    if (!titles[p].empty() && lowered(titles[p]).find(lq) != std::string::npos) offer(p);
  if (best) return *best;
  return Status::input("warp: no particle matches '" + std::string(q) + "' (a title, part of one, or a hex id prefix)");
}

double smoothstep(double x) {
  const double t = std::clamp(x, 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

Camera warp_end(const Camera& from, const Scene& s, std::uint32_t p) {
  const Vec3 x = s.position[p];
  const double tiny = 1e-9 * static_cast<double>(kSceneRadius);
  Vec3 d = from.position - x;
  if (!(length(d) > tiny)) d = x - s.centroid;
  const Vec3 n = length(d) > tiny ? normalize(d) : Vec3{0, 0, 1};
  Camera to = from;
  to.position = x + n * (kWarpStandOff * s.radius[p]);
  for (const Vec3& up : {from.orientation.rotate({0, 1, 0}), Vec3{0, 0, 1}, Vec3{0, 1, 0}}) {
    const Result<Quat> q = look_at(to.position, x, up);
    if (q.is_ok()) {
      to.orientation = q.value();
      break;
    }
  }
  return to;
}

Camera warp_at(const Camera& from, const Camera& to, double t) {
  if (t >= kWarpSeconds) return to;
  const double s = smoothstep(t / kWarpSeconds);
  Camera c = to;
  c.position = from.position + (to.position - from.position) * s;
  const Quat& a = from.orientation;
  Quat b = to.orientation;
  if (a.w * b.w + a.x * b.x + a.y * b.y + a.z * b.z < 0) b = {-b.w, -b.x, -b.y, -b.z};
  Quat q{a.w + (b.w - a.w) * s, a.x + (b.x - a.x) * s, a.y + (b.y - a.y) * s, a.z + (b.z - a.z) * s};
  const double len = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  c.orientation = {q.w / len, q.x / len, q.y / len, q.z / len};
  c.fov_deg = from.fov_deg + (to.fov_deg - from.fov_deg) * s;
  return c;
}

std::uint32_t nearest_particle(const Scene& s, const Vec3& x) {
  std::uint32_t best = 0;
  double best_d = std::numeric_limits<double>::infinity();
  for (std::uint32_t p = 0; p < s.n; ++p) {
    const Vec3 d = s.position[p] - x;
    const double dd = dot(d, d);
    if (dd < best_d) best_d = dd, best = p;
  }
  return best;
}

EdgeIndex index_edges(const Scene& s) {
  EdgeIndex ix;
  ix.offset.assign(s.n + 1, 0);
  for (const LayoutEdge& e : s.edges) ++ix.offset[e.p + 1], ++ix.offset[e.q + 1];
  for (std::uint32_t p = 0; p < s.n; ++p) ix.offset[p + 1] += ix.offset[p];
  ix.edge.resize(ix.offset[s.n]);
  std::vector<std::uint32_t> fill(ix.offset.begin(), ix.offset.end() - 1);
  for (std::uint32_t k = 0; k < s.edges.size(); ++k) {
    ix.edge[fill[s.edges[k].p]++] = k;
    ix.edge[fill[s.edges[k].q]++] = k;
  }
  return ix;
}

std::optional<std::uint32_t> heaviest_neighbour(const Scene& s, const EdgeIndex& index, std::uint32_t p) {
  std::optional<std::uint32_t> best;
  std::int64_t best_w = 0;
  for (std::uint32_t k = index.offset[p]; k < index.offset[p + 1]; ++k) {
    const LayoutEdge& e = s.edges[index.edge[k]];
    const std::uint32_t q = e.p == p ? e.q : e.p;
    if (!best || e.w_raw > best_w || (e.w_raw == best_w && q < *best)) best = q, best_w = e.w_raw;
  }
  return best;
}

double flight_speed(const Scene& s, const Vec3& x) {
  const std::uint32_t p = nearest_particle(s, x);
  const double d = length(s.position[p] - x);
  return std::min(std::max(d, 2.0 * s.radius[p]), static_cast<double>(kSceneRadius));
}

Camera follow_flow_step(const Scene& s, const EdgeIndex& index, const Camera& c, const Vec3& v_user, double dt) {
  Vec3 v = v_user;
  const std::uint32_t p = nearest_particle(s, c.position);
  if (const auto q = heaviest_neighbour(s, index, p)) {
    const Vec3 d = s.position[*q] - c.position;
    if (length(d) > 0) v += normalize(d) * flight_speed(s, c.position);
  }
  Camera out = c;
  out.position = c.position + v * dt;
  return out;
}

}  // namespace r1::render
