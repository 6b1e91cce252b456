// What the Vulkan adapters share (internal to backends/adapters): one compute context serves the
// 13.1 device and the backend's frame passes.
#pragma once

#include <memory>

#include "r1/accel/vulkan.hpp"
#include "r1/backends/device.hpp"

namespace r1::backends {

// det_exp's constants from the reference's Clifford code (R1-RND-101), for the device's shaders.
vk::ExpConstants reference_exp_constants();

// The Vulkan device of the 13.1 trait on an existing context.
Result<std::unique_ptr<Device>> make_vulkan_device_on(std::shared_ptr<vk::Context> ctx);

}  // namespace r1::backends
