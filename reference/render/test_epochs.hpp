// Epochs made directly from particle positions for the frame tests (render, neural field,
// legibility): equal focus (raws summing to exactly 2^32, the remainder on particle 0), zero
// spectra and a real hierarchy. Ids are Hemera(id_prefix + index); the snapshot digest is
// Hemera(tag). A Scene made from one borrows its hierarchy: keep the epoch alive.
#pragma once

#include <gtest/gtest.h>

#include <array>
#include <string>
#include <vector>

#include "r1/reference/hierarchy.hpp"
#include "r1/spec/epoch.hpp"
#include "r1/spec/vec3.hpp"

namespace r1::render::test {

struct TestParticle {
  Vec3 position;
  double radius = 1;
  Shape shape = Shape::kSphere;
  std::array<std::uint8_t, 3> color{100, 120, 200};
};

inline Epoch epoch_from(const std::string& tag, const std::vector<TestParticle>& particles, const std::string& id_prefix = "p") {
  Epoch e;
  const std::size_t n = particles.size();
  e.snapshot_digest = hemera::hash(tag);
  const std::int64_t share = Q32::kOneRaw / static_cast<std::int64_t>(n);
  for (std::size_t i = 0; i < n; ++i) {
    const TestParticle& p = particles[i];
    e.ids.push_back(hemera::hash(id_prefix + std::to_string(i)));
    e.titles.push_back("");
    e.focus.phi.push_back(Q32::from_raw(i == 0 ? Q32::kOneRaw - share * static_cast<std::int64_t>(n - 1) : share));
    e.frame.position.push_back({Q32::from_double(p.position.x), Q32::from_double(p.position.y), Q32::from_double(p.position.z)});
    e.encoding.radius.push_back(Q32::from_double(p.radius));
    e.encoding.shape.push_back(p.shape);
    e.encoding.color.push_back(p.color);
  }
  for (auto& u : e.spectrum.u) u.assign(n, Q32{});
  auto h = build_hierarchy(e.frame.position, e.focus.phi, e.encoding.color, e.ids);
  EXPECT_TRUE(h.is_ok()) << h.status().message();
  if (h.is_ok()) e.hierarchy = *h;
  return e;
}

}  // namespace r1::render::test
