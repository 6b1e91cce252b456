// The legibility measures (spec/render.md R1-RND-120..123) on scenes whose answers are known:
// overlapping and separate discs, a nearer disc hiding a farther one, coincident positions, and
// the core disc of points on a known pattern; the overlap against brute force on random scenes.
#include "legibility.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "r1/fixedpoint/counter_rng.hpp"
#include "cull.hpp"
#include "test_epochs.hpp"
#include "view.hpp"

namespace {

using namespace r1::render;
using r1::Q32;

r1::Epoch epoch_at(const std::vector<Vec3>& pos, const std::vector<double>& radius) {
  std::vector<test::TestParticle> ps;
  for (std::size_t i = 0; i < pos.size(); ++i) ps.push_back({pos[i], radius[i]});
  return test::epoch_from("legibility-test", ps, "q");
}

// Looking down -z from z = 1000 with a 90-degree field of view on a 200 x 200 image: the plane
// z = 0 maps 10 scene units to 1 pixel, 100 pixels per 1000 units from the centre.
View top_view() {
  View v;
  v.width = v.height = 200;
  v.camera.position = {0, 0, 1000};
  v.camera.orientation = *look_at(v.camera.position, {0, 0, 0}, {0, 1, 0});
  v.camera.fov_deg = 90;
  return v;
}

TEST(Legibility, OverlapCountsTheFartherOfTwoMeetingDiscs) {
  // Radius 60 at depth 1000: 6 px radius, 12 px across (T2). Centres 100 units = 10 px apart
  // meet; 200 units = 20 px apart do not.
  {
    const r1::Epoch e = epoch_at({{0, 0, 0}, {100, 0, -5}}, {60, 60});  // the scene borrows its hierarchy
    const Scene s = make_scene(e);
    const Legibility l = legibility(s, top_view());
    EXPECT_EQ(l.shapes, 2u);
    EXPECT_EQ(l.overlapped, 1u);
    EXPECT_DOUBLE_EQ(l.overlap_share, 0.5);
  }
  {
    const r1::Epoch e = epoch_at({{0, 0, 0}, {200, 0, 0}}, {60, 60});
    const Scene s = make_scene(e);
    EXPECT_EQ(legibility(s, top_view()).overlapped, 0u);
  }
  // Sub-T2 particles are not shapes and never count.
  {
    const r1::Epoch e = epoch_at({{0, 0, 0}, {10, 0, 0}}, {5, 5});
    const Scene s = make_scene(e);
    const Legibility l = legibility(s, top_view());
    EXPECT_EQ(l.shapes, 0u);
    EXPECT_EQ(l.overlap_share, 0.0);
    EXPECT_EQ(l.visible, 2u);
  }
}

TEST(Legibility, CoincidentPositionsAndTheCoreDisc) {
  // Ten points on the x axis at 0, 100, ..., 900 units (0..90 px right of the centre) and an
  // eleventh on the one at 500: the median is x = 50 px (the 6th of 11 sorted), y = 0; the disc
  // holding ceil(9.9) = 10 of the 11 centres has radius 40 px (the farthest, at 0 px, is left out).
  std::vector<Vec3> pos;
  for (int i = 0; i < 10; ++i) pos.push_back({100.0 * i, 0, 0});
  pos.push_back({500, 0, 0});
  const r1::Epoch e = epoch_at(pos, std::vector<double>(pos.size(), 1.0));
  const Scene s = make_scene(e);
  const Legibility l = legibility(s, top_view());
  EXPECT_EQ(l.coincident, 2u);
  EXPECT_DOUBLE_EQ(l.coincident_share, 2.0 / 11.0);
  EXPECT_EQ(l.visible, 11u);
  EXPECT_NEAR(l.core_share, kPi * 40.0 * 40.0 / (200.0 * 200.0), 1e-9);
}

TEST(Legibility, OverlapEqualsBruteForce) {
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    std::vector<Vec3> pos;
    std::vector<double> radius;
    for (std::uint64_t i = 0; i < 300; ++i) {
      pos.push_back({r1::rng::uniform_double(seed, i, 0) * 1600 - 800, r1::rng::uniform_double(seed, i, 1) * 1600 - 800,
                     r1::rng::uniform_double(seed, i, 2) * 400 - 200});
      radius.push_back(10 + r1::rng::uniform_double(seed, i, 3) * 120);
    }
    const r1::Epoch e = epoch_at(pos, radius);
    const Scene s = make_scene(e);
    const View v = top_view();
    const CameraFrame f = camera_frame(v);
    std::vector<Visible> big;
    for (const Visible& p : cull(s, v, f))
      if (p.s > v.tiers.t2) big.push_back(p);
    std::uint64_t hidden = 0;
    for (const Visible& a : big) {
      const Projected pa = project(v, f, s.position[a.particle]);
      bool h = false;
      for (const Visible& b : big) {
        if (!(b.depth < a.depth || (b.depth == a.depth && b.particle < a.particle))) continue;
        const Projected pb = project(v, f, s.position[b.particle]);
        const double rr = (a.s + b.s) / 2;
        h = h || std::hypot(pa.px - pb.px, pa.py - pb.py) < rr;
      }
      hidden += h ? 1 : 0;
    }
    const Legibility l = legibility(s, v);
    EXPECT_EQ(l.shapes, big.size()) << seed;
    EXPECT_EQ(l.overlapped, hidden) << seed;
    EXPECT_GT(hidden, 0u) << seed;
  }
}

}  // namespace
