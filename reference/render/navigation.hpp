// Navigation (R-1.0 9.2-9.4; spec/viewer.md R1-VIEW-020..034): resolving a warp query to a
// particle, the warp flight as a function of time, and follow-flow's camera step. The viewer page
// runs the same rules in JavaScript; these are the oracle its browser tests compare against, and
// `r1 render --path` draws them as frames.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "r1/fixedpoint/hemera.hpp"
#include "r1/spec/status.hpp"
#include "r1/spec/view.hpp"
#include "render/scene.hpp"

namespace r1::render {

inline constexpr double kWarpSeconds = 0.5;     // 9.2
inline constexpr double kWarpStandOff = 3.0;    // the flight ends 3 r(p) from X'(p)

// R1-VIEW-020: the particle a warp query names. A query of 1..64 hex digits matches the particle
// ids it prefixes; otherwise (or when no id matches) titles: exact, then case-insensitive exact,
// then case-insensitive substring. Among the matches of the first rule that has any, the highest
// phi wins, ties by the lower index. No match, or an empty query: an input error naming it.
Result<std::uint32_t> find_particle(const std::vector<hemera::Digest>& ids, const std::vector<std::string>& titles,
                                    const std::vector<double>& phi, std::string_view query);

// x in [0, 1] (clamped) -> 3 x^2 - 2 x^3.
double smoothstep(double x);

// R1-VIEW-021: the pose a warp to particle p ends at: X'(p) + 3 r(p) n, looking at X'(p), with n
// the unit vector from X'(p) to the camera (from the focus centroid if the camera is within
// 1e-9 R_scene of it, +z if that too is degenerate), up the camera's current up (else +z, else +y).
Camera warp_end(const Camera& from, const Scene& s, std::uint32_t p);

// The camera t seconds into the flight from `from` to `to`: position lerped and orientation
// nlerped (the shorter way) by smoothstep(t / 0.5 s); `to` from t >= 0.5 s on.
Camera warp_at(const Camera& from, const Camera& to, double t);

// R1-VIEW-030: the particle whose centre is nearest to x (ties: the lower index).
std::uint32_t nearest_particle(const Scene& s, const Vec3& x);

// The layout edges incident to each particle, and the other end of p's heaviest one (largest
// A_sym; ties: the lower particle index); none when p has no edge.
struct EdgeIndex {
  std::vector<std::uint32_t> offset;    // n + 1
  std::vector<std::uint32_t> edge;      // incident edge ids, by particle, ascending edge id
};
EdgeIndex index_edges(const Scene& s);
std::optional<std::uint32_t> heaviest_neighbour(const Scene& s, const EdgeIndex& index, std::uint32_t p);

// R1-VIEW-031: the flying speed at x, scene units per second: the distance from x to the nearest
// particle's centre, at least 2 r of that particle and at most R_scene.
double flight_speed(const Scene& s, const Vec3& x);

// R1-VIEW-032: one follow-flow step of dt seconds: v = v_user + speed(x) unit(X'(q) - x), q the
// heaviest neighbour of the particle nearest x (no bias when it has none, or x is at X'(q)),
// x += v dt; the orientation is kept.
Camera follow_flow_step(const Scene& s, const EdgeIndex& index, const Camera& c, const Vec3& v_user, double dt);

}  // namespace r1::render
