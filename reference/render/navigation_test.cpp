// Navigation (spec/viewer.md R1-VIEW-020..032) against its definitions: the query rules in their
// order, the warp's end pose (3 r from the particle, looking at it) and its smooth-step flight,
// and follow-flow's step toward the heaviest neighbour.
#include "navigation.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "r1/spec/epoch.hpp"
#include "view.hpp"

namespace {

using namespace r1::render;

Vec3 forward(const Camera& c) { return c.orientation.rotate({0, 0, -1}); }

// Four particles on the x axis and one above; edges 0-1 (w 1), 0-2 (w 3), 0-3 (w 3), 1-2 (w 2).
Scene small_scene() {
  Scene s;
  s.n = 5;
  s.position = {{0, 0, 0}, {100, 0, 0}, {200, 0, 0}, {300, 0, 0}, {0, 0, 400}};
  s.radius = {10, 5, 5, 5, 20};
  s.phi = {0.4, 0.1, 0.2, 0.2, 0.1};
  s.centroid = {100, 0, 40};
  const auto w = [](double x) { return static_cast<std::int64_t>(x * 4294967296.0); };
  s.edges = {{0, 1, w(1), 0}, {0, 2, w(3), 0}, {0, 3, w(3), 0}, {1, 2, w(2), 0}};
  return s;
}

TEST(Navigation, QueryRulesInOrder) {
  std::vector<r1::hemera::Digest> ids;
  for (int i = 0; i < 4; ++i) ids.push_back(r1::hemera::hash("nav" + std::to_string(i)));
  const std::vector<std::string> titles{"Alpha", "alphabet", "ALPHA", "Beta"};
  const std::vector<double> phi{0.1, 0.5, 0.3, 0.1};
  // Exact title beats case-insensitive and substring matches with more focus.
  EXPECT_EQ(find_particle(ids, titles, phi, "Alpha").value(), 0u);
  // Case-insensitive exact: "Alpha" and "ALPHA" match; the higher phi (2) wins.
  EXPECT_EQ(find_particle(ids, titles, phi, "alpha").value(), 2u);
  // Substring: "lph" is in three titles; alphabet has the most focus.
  EXPECT_EQ(find_particle(ids, titles, phi, "  lph ").value(), 1u);
  // A hex prefix names the particle it prefixes, in either case.
  const std::string hex3 = r1::hemera::to_hex(ids[3]);
  EXPECT_EQ(find_particle(ids, titles, phi, hex3.substr(0, 10)).value(), 3u);
  std::string upper = hex3.substr(0, 12);
  for (char& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  EXPECT_EQ(find_particle(ids, titles, phi, upper).value(), 3u);
  EXPECT_EQ(find_particle(ids, titles, phi, hex3).value(), 3u);
  // Ties on phi go to the lower index: "a" prefixes no id here only by chance, so use titles.
  const std::vector<double> flat{0.25, 0.25, 0.25, 0.25};
  EXPECT_EQ(find_particle(ids, {"x1", "x2", "x3", "y"}, flat, "x").value(), 0u);
  EXPECT_FALSE(find_particle(ids, titles, phi, "").is_ok());
  EXPECT_FALSE(find_particle(ids, titles, phi, "gamma").is_ok());
  EXPECT_NE(find_particle(ids, titles, phi, "gamma").status().message().find("gamma"), std::string::npos);
}

TEST(Navigation, WarpEndsThreeRadiiAwayLookingAtTheParticle) {
  const Scene s = small_scene();
  Camera from;
  from.position = {300, 500, 0};
  from.orientation = look_at(from.position, {0, 0, 0}, {0, 0, 1}).value();
  for (std::uint32_t p = 0; p < s.n; ++p) {
    const Camera to = warp_end(from, s, p);
    EXPECT_NEAR(length(to.position - s.position[p]), 3 * s.radius[p], 1e-9);
    // On the side the camera came from.
    const Vec3 n = normalize(from.position - s.position[p]);
    EXPECT_NEAR(dot(normalize(to.position - s.position[p]), n), 1.0, 1e-12);
    EXPECT_NEAR(dot(forward(to), normalize(s.position[p] - to.position)), 1.0, 1e-12);
  }
  // A camera sitting on the particle backs out along the centroid's direction.
  Camera on = from;
  on.position = s.position[3];
  const Camera to = warp_end(on, s, 3);
  EXPECT_NEAR(dot(normalize(to.position - s.position[3]), normalize(s.position[3] - s.centroid)), 1.0, 1e-12);
}

TEST(Navigation, WarpFlightIsSmoothStep) {
  const Scene s = small_scene();
  Camera from;
  from.position = {300, 500, 0};
  from.orientation = look_at(from.position, {0, 0, 0}, {0, 0, 1}).value();
  const Camera to = warp_end(from, s, 4);
  const Camera c0 = warp_at(from, to, 0);
  EXPECT_NEAR(length(c0.position - from.position), 0, 1e-12);
  EXPECT_NEAR(dot(forward(c0), forward(from)), 1.0, 1e-12);
  // Half time: half way (smoothstep(1/2) = 1/2); a quarter: 5/32 of the way.
  const Camera half = warp_at(from, to, 0.25);
  EXPECT_NEAR(length(half.position - (from.position + to.position) * 0.5), 0, 1e-9);
  const Camera quarter = warp_at(from, to, 0.125);
  EXPECT_NEAR(length(quarter.position - (from.position + (to.position - from.position) * (5.0 / 32))), 0, 1e-9);
  const Camera end = warp_at(from, to, 0.5);
  EXPECT_EQ(end.position, to.position);
  for (double t = 0; t <= 0.5; t += 0.05) {
    const Quat q = warp_at(from, to, t).orientation;
    EXPECT_NEAR(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z, 1.0, 1e-12);
  }
  // Monotone approach along the straight line.
  double last = length(to.position - from.position);
  for (double t = 0.05; t <= 0.5; t += 0.05) {
    const double d = length(to.position - warp_at(from, to, t).position);
    EXPECT_LT(d, last);
    last = d;
  }
}

TEST(Navigation, FollowFlowHeadsForTheHeaviestNeighbour) {
  const Scene s = small_scene();
  const EdgeIndex ix = index_edges(s);
  // Particle 0: edges of weight 1, 3, 3: the tie between 2 and 3 goes to 2.
  EXPECT_EQ(heaviest_neighbour(s, ix, 0).value(), 2u);
  EXPECT_EQ(heaviest_neighbour(s, ix, 1).value(), 2u);
  EXPECT_EQ(heaviest_neighbour(s, ix, 3).value(), 0u);
  EXPECT_FALSE(heaviest_neighbour(s, ix, 4).has_value());
  EXPECT_EQ(nearest_particle(s, {90, 5, 0}), 1u);
  // From near particle 0 the camera moves toward particle 2 at the flight speed.
  Camera c;
  c.position = {0, 50, 0};
  const double speed = flight_speed(s, c.position);
  EXPECT_DOUBLE_EQ(speed, 50.0);
  const Camera next = follow_flow_step(s, ix, c, {0, 0, 0}, 0.1);
  EXPECT_NEAR(length(s.position[2] - c.position) - length(s.position[2] - next.position), 5.0, 1e-3);
  EXPECT_NEAR(dot(normalize(next.position - c.position), normalize(s.position[2] - c.position)), 1.0, 1e-12);
  // The user's own velocity adds to the bias; near a particle without edges there is none.
  const Camera user = follow_flow_step(s, ix, c, {0, 0, 10}, 0.1);
  EXPECT_NEAR(user.position.z - next.position.z, 1.0, 1e-12);
  Camera lone;
  lone.position = {0, 0, 380};
  EXPECT_EQ(follow_flow_step(s, ix, lone, {0, 0, 0}, 0.1).position, lone.position);
  // The speed is at least two radii and at most R_scene.
  EXPECT_DOUBLE_EQ(flight_speed(s, {0, 0, 401}), 40.0);
  EXPECT_DOUBLE_EQ(flight_speed(s, {0, 1e6, 0}), 1000.0);
}

}  // namespace
