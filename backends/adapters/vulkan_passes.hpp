// The vulkan backend's frame passes that its tests call directly (internal to backends/adapters).
#pragma once

#include "r1/accel/vulkan.hpp"
#include "render/cull.hpp"
#include "render/neural_field.hpp"
#include "render/passes.hpp"

namespace r1::backends {

// The frame's cull on the device (R1-BKD-074): the scene flattened for vk::CullPass, its visible
// list taken as is, and the far nodes and the walk's counts from the device's node decisions by
// the reference's walk order (R1-RND-074).
Status cull_on_device(vk::CullPass& pass, const render::Scene& s, const render::View& v, const render::CameraFrame& f,
                      render::CullResult& out, render::CullStats& stats);

// The frame's edge tubes on the device (R1-BKD-075): the tubes flattened for vk::EdgePass, drawn
// over the layer; when the pass declines (a tile past lavapipe's loop limit), the reference's
// draw_edge_tubes.
Status edges_on_device(vk::EdgePass& pass, std::span<const render::EdgeTube> tubes, const render::View& v,
                       const render::CameraFrame& f, render::OpaqueLayer& layer);

// A trained neural field as the device's inference reads it (R1-BKD-076).
vk::NeuralData neural_data(const render::NeuralField& f);

}  // namespace r1::backends
