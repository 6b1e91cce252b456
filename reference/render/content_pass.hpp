// The T0 content pass (spec/render.md R1-RND-130..137): a particle above s_T0 that has content
// opens: its shape is not drawn and its content is, an image on a flat panel, text on a
// cylindrical section, anything else (and content that is missing, unreadable or refused) on a
// card naming it, all facing the camera inside the particle's bounding sphere.
#pragma once

#include <cstdint>
#include <vector>

#include "content.hpp"
#include "passes.hpp"

namespace r1::render {

// A texture in linear light, RGB, row-major from the top left.
struct ContentTexture {
  int width = 0, height = 0;
  std::vector<float> rgb;
};

enum class ContentSurface : std::uint8_t { kPanel, kCylinder };

struct ContentPanel {
  std::uint32_t particle = 0;
  ContentSurface surface = ContentSurface::kPanel;
  ContentTexture texture;
  bool card = false;  // a card (other types, missing, unreadable, refused) rather than the content
};

// The content of a scene, prepared once per epoch: textures decoded, typeset and drawn.
struct ContentScene {
  std::vector<std::int32_t> panel_of;  // per particle: its panel, -1 for none
  std::vector<ContentPanel> panels;
  bool has(std::uint32_t p) const { return p < panel_of.size() && panel_of[p] >= 0; }
};

// R1-RND-131..134: the panels of `c` for a scene of `n` particles. Never fails: an image that does
// not decode becomes the "unreadable" card, a missing font a card without its words.
ContentScene make_content_scene(const ContentSet& c, std::uint32_t n);

// The texture geometry (R1-RND-132): the text surface is a section of a cylinder of radius
// kTextRadius r about an axis parallel to the panel's up, spanning +-kTextHalfAngle radians.
inline constexpr double kTextRadius = 0.7;
inline constexpr double kTextHalfAngle = 3.14159265358979323846 / 3;

// R1-RND-135: draws every visible T0 particle of `culled` that has content into the opaque layer
// (nearest hit wins, as the impostors); returns how many it drew.
std::uint64_t draw_content(const Scene& s, const View& v, const CameraFrame& f, const CullResult& culled, OpaqueLayer& layer);

}  // namespace r1::render
