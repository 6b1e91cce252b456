// The Vulkan context's state (internal to accel/vulkan): what context.cpp creates and the
// compute and raster files share.
#pragma once

#include <vulkan/vulkan.h>
#include <shaderc/shaderc.h>

#include <cstring>
#include <functional>
#include <span>
#include <string_view>
#include <array>
#include <string>
#include <map>
#include <vector>

#include "r1/accel/vulkan.hpp"

namespace r1::vk {

inline std::string code(VkResult r) { return "VkResult " + std::to_string(static_cast<int>(r)); }

inline Status fail(const std::string& what, VkResult r) { return Status::input("vulkan: " + what + " failed (" + code(r) + ")"); }

// A Vulkan structure with its type set and every other member zero.
template <class T>
T make(VkStructureType type) {
  T v{};
  v.sType = type;
  return v;
}

struct Context::State {
  VkInstance instance = VK_NULL_HANDLE;
  VkPhysicalDevice physical = VK_NULL_HANDLE;
  VkDevice device = VK_NULL_HANDLE;
  VkQueue queue = VK_NULL_HANDLE;
  std::uint32_t family = 0;
  VkPhysicalDeviceMemoryProperties memory{};
  VkPhysicalDeviceLimits limits{};
  VkCommandPool pool = VK_NULL_HANDLE;
  VkCommandBuffer cmd = VK_NULL_HANDLE;
  VkFence fence = VK_NULL_HANDLE;
  VkDescriptorSetLayout set_layout = VK_NULL_HANDLE;
  VkPipelineLayout layout = VK_NULL_HANDLE;
  VkDescriptorPool descriptors = VK_NULL_HANDLE;
  DeviceInfo info;
  struct Buffer {
    VkBuffer buffer = VK_NULL_HANDLE;
    VkDeviceMemory memory = VK_NULL_HANDLE;
    std::uint8_t* mapped = nullptr;
    std::size_t size = 0;
  };
  std::vector<Buffer> buffers;  // buffers[0]: the 16-byte placeholder every unused slot binds
  std::vector<VkPipeline> pipelines;  // compute and graphics
  std::vector<bool> graphics_pipeline;  // per pipeline: made by graphics_compile
  std::map<std::string, std::uint32_t, std::less<>> compute_by_source;  // compute_compile's pipelines by GLSL
  // An offscreen render target: kTargetColors colour images (RGBA32_UINT) and a depth image
  // (D32_SFLOAT), device memory, with a host-visible buffer each colour image is copied to.
  struct Target {
    std::uint32_t width = 0, height = 0;
    std::array<VkImage, kTargetColors + 1> image{};  // the colours, then depth
    std::array<VkImageView, kTargetColors + 1> view{};
    std::array<VkDeviceMemory, kTargetColors + 1> memory{};
    std::array<std::uint32_t, kTargetColors> readback{};  // buffer ids
  };
  std::vector<Target> targets;

  // The shader stages the set layout and push constants serve.
  VkShaderStageFlags stages() const {
    return info.graphics ? VK_SHADER_STAGE_COMPUTE_BIT | VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT
                         : VK_SHADER_STAGE_COMPUTE_BIT;
  }
  // The descriptor set with the slots bound (the placeholder where none is named).
  Result<VkDescriptorSet> bind(std::span<const Slot> slots);
  // GLSL 4.60 to SPIR-V with shaderc (no optimisation).
  Result<std::vector<std::uint32_t>> spirv(std::string_view glsl, shaderc_shader_kind kind, std::string_view name);
  // Records commands into the one command buffer, submits and waits.
  Status submit(const std::function<void(VkCommandBuffer)>& record);
  Result<std::uint32_t> memory_type(std::uint32_t bits, VkMemoryPropertyFlags want) const {
    for (std::uint32_t t = 0; t < memory.memoryTypeCount; ++t)
      if ((bits & (1u << t)) && (memory.memoryTypes[t].propertyFlags & want) == want) return t;
    return Status::input("vulkan: no memory of the kind needed");
  }

  ~State() {
    if (device != VK_NULL_HANDLE) {
      vkDeviceWaitIdle(device);
      for (const Target& t : targets)
        for (std::size_t i = 0; i < t.image.size(); ++i) {
          vkDestroyImageView(device, t.view[i], nullptr);
          vkDestroyImage(device, t.image[i], nullptr);
          vkFreeMemory(device, t.memory[i], nullptr);
        }
      for (VkPipeline p : pipelines) vkDestroyPipeline(device, p, nullptr);
      for (const Buffer& b : buffers) {
        if (b.buffer == VK_NULL_HANDLE) continue;  // released
        if (b.memory != VK_NULL_HANDLE) vkUnmapMemory(device, b.memory);
        vkDestroyBuffer(device, b.buffer, nullptr);
        vkFreeMemory(device, b.memory, nullptr);
      }
      vkDestroyDescriptorPool(device, descriptors, nullptr);
      vkDestroyPipelineLayout(device, layout, nullptr);
      vkDestroyDescriptorSetLayout(device, set_layout, nullptr);
      vkDestroyFence(device, fence, nullptr);
      vkDestroyCommandPool(device, pool, nullptr);
      vkDestroyDevice(device, nullptr);
    }
    if (instance != VK_NULL_HANDLE) vkDestroyInstance(instance, nullptr);
  }

  Result<std::uint32_t> make_buffer(std::size_t bytes) {
    Buffer b;
    b.size = bytes;
    auto bi = make<VkBufferCreateInfo>(VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO);
    bi.size = std::max<std::size_t>(bytes, 16);
    bi.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT |
               VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT;
    bi.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    if (VkResult r = vkCreateBuffer(device, &bi, nullptr, &b.buffer); r != VK_SUCCESS) return fail("vkCreateBuffer", r);
    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(device, b.buffer, &req);
    const VkMemoryPropertyFlags want = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
    std::uint32_t type = memory.memoryTypeCount;
    for (std::uint32_t t = 0; t < memory.memoryTypeCount && type == memory.memoryTypeCount; ++t)
      if ((req.memoryTypeBits & (1u << t)) && (memory.memoryTypes[t].propertyFlags & want) == want) type = t;
    if (type == memory.memoryTypeCount) {
      vkDestroyBuffer(device, b.buffer, nullptr);
      return Status::input("vulkan: no host-visible coherent memory for a storage buffer");
    }
    auto ai = make<VkMemoryAllocateInfo>(VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO);
    ai.allocationSize = req.size;
    ai.memoryTypeIndex = type;
    if (VkResult r = vkAllocateMemory(device, &ai, nullptr, &b.memory); r != VK_SUCCESS) {
      vkDestroyBuffer(device, b.buffer, nullptr);
      return fail("vkAllocateMemory of " + std::to_string(req.size) + " bytes", r);
    }
    vkBindBufferMemory(device, b.buffer, b.memory, 0);
    void* p = nullptr;
    if (VkResult r = vkMapMemory(device, b.memory, 0, VK_WHOLE_SIZE, 0, &p); r != VK_SUCCESS) {
      vkDestroyBuffer(device, b.buffer, nullptr);
      vkFreeMemory(device, b.memory, nullptr);
      return fail("vkMapMemory", r);
    }
    b.mapped = static_cast<std::uint8_t*>(p);
    std::memset(b.mapped, 0, bi.size);
    buffers.push_back(b);
    return static_cast<std::uint32_t>(buffers.size() - 1);
  }
};


}  // namespace r1::vk
