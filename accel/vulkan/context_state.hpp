// The Vulkan context's state (internal to accel/vulkan): what context.cpp creates and the
// compute and raster files share.
#pragma once

#include <vulkan/vulkan.h>
#include <shaderc/shaderc.h>

#include <algorithm>
#include <cstdlib>
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
    Residence asked = Residence::kHost;
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
        if (b.mapped != nullptr) vkUnmapMemory(device, b.memory);
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

  // The memory types for a buffer of `bits` in the order `where` prefers (R1-BKD-061); those
  // after the first are fall-backs when an allocation fails.
  std::vector<std::uint32_t> memory_types(std::uint32_t bits, Residence where) const {
    constexpr VkMemoryPropertyFlags kLocal = VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, kVisible = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT,
                                    kCoherent = VK_MEMORY_PROPERTY_HOST_COHERENT_BIT, kCached = VK_MEMORY_PROPERTY_HOST_CACHED_BIT;
    std::vector<VkMemoryPropertyFlags> order;
    if (where == Residence::kScratch) order.push_back(kLocal);
    if (where == Residence::kUpload) order.push_back(kLocal | kVisible | kCoherent);
    order.push_back(kVisible | kCoherent | kCached);
    order.push_back(kVisible | kCoherent);
    std::vector<std::uint32_t> types;
    for (const VkMemoryPropertyFlags want : order)
      for (std::uint32_t t = 0; t < memory.memoryTypeCount; ++t)
        if ((bits & (1u << t)) && (memory.memoryTypes[t].propertyFlags & want) == want &&
            std::find(types.begin(), types.end(), t) == types.end()) {
          types.push_back(t);
          break;
        }
    return types;
  }

  Result<std::uint32_t> make_buffer(std::size_t bytes, Residence where = Residence::kHost) {
    Buffer b;
    b.size = bytes;
    b.asked = where;
    if (const char* env = std::getenv("R1_VULKAN_MEMORY"); env != nullptr && std::string_view(env) == "host") where = Residence::kHost;
    auto bi = make<VkBufferCreateInfo>(VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO);
    bi.size = std::max<std::size_t>(bytes, 16);
    bi.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT |
               VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT;
    bi.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    if (VkResult r = vkCreateBuffer(device, &bi, nullptr, &b.buffer); r != VK_SUCCESS) return fail("vkCreateBuffer", r);
    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(device, b.buffer, &req);
    const std::vector<std::uint32_t> types = memory_types(req.memoryTypeBits, where);
    if (types.empty() || !(memory.memoryTypes[types.back()].propertyFlags & VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT)) {
      vkDestroyBuffer(device, b.buffer, nullptr);
      return Status::input("vulkan: no host-visible coherent memory for a storage buffer");
    }
    // The first type that takes the allocation: device-local memory may be full or, mapped, small.
    auto ai = make<VkMemoryAllocateInfo>(VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO);
    ai.allocationSize = req.size;
    VkResult r = VK_ERROR_OUT_OF_DEVICE_MEMORY;
    std::uint32_t type = 0;
    for (const std::uint32_t t : types) {
      ai.memoryTypeIndex = type = t;
      if ((r = vkAllocateMemory(device, &ai, nullptr, &b.memory)) == VK_SUCCESS) break;
    }
    if (r != VK_SUCCESS) {
      vkDestroyBuffer(device, b.buffer, nullptr);
      return fail("vkAllocateMemory of " + std::to_string(req.size) + " bytes", r);
    }
    vkBindBufferMemory(device, b.buffer, b.memory, 0);
    if (!(memory.memoryTypes[type].propertyFlags & VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT)) {
      buffers.push_back(b);  // device-only scratch: never mapped, its contents the passes' own
      return static_cast<std::uint32_t>(buffers.size() - 1);
    }
    void* p = nullptr;
    if ((r = vkMapMemory(device, b.memory, 0, VK_WHOLE_SIZE, 0, &p)) != VK_SUCCESS) {
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
