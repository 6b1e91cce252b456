// The Vulkan compute context (R1-BKD-060..063): instance, device, queue, buffers in host-visible
// coherent memory, shaderc compilation and synchronous dispatches.
#include <vulkan/vulkan.h>
#include <shaderc/shaderc.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <string>
#include <utility>

#include "context_state.hpp"

namespace r1::vk {

namespace {

int type_rank(VkPhysicalDeviceType t) {
  switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return 0;
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return 1;
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return 2;
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return 3;
    default: return 4;
  }
}

}  // namespace

Context::Context(std::unique_ptr<State> s) : s_(std::move(s)) {}
Context::~Context() = default;
const DeviceInfo& Context::info() const { return s_->info; }

Result<std::unique_ptr<Context>> Context::create() {
  auto s = std::make_unique<State>();
  auto app = make<VkApplicationInfo>(VK_STRUCTURE_TYPE_APPLICATION_INFO);
  app.pApplicationName = "r1";
  app.apiVersion = VK_API_VERSION_1_3;
  auto ici = make<VkInstanceCreateInfo>(VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO);
  ici.pApplicationInfo = &app;
  if (VkResult r = vkCreateInstance(&ici, nullptr, &s->instance); r != VK_SUCCESS)
    return Status::input("vulkan: no Vulkan instance (vkCreateInstance: " + code(r) + "; is a loader and a driver installed?)");
  std::uint32_t count = 0;
  vkEnumeratePhysicalDevices(s->instance, &count, nullptr);
  std::vector<VkPhysicalDevice> all(count);
  vkEnumeratePhysicalDevices(s->instance, &count, all.data());
  // The usable devices: Vulkan 1.3, 64-bit floats and integers in shaders, a compute queue.
  struct Candidate {
    VkPhysicalDevice d;
    std::uint32_t family;
    int rank;
    bool graphics;
  };
  std::vector<Candidate> usable;
  std::string why;
  for (VkPhysicalDevice d : all) {
    VkPhysicalDeviceProperties p;
    vkGetPhysicalDeviceProperties(d, &p);
    VkPhysicalDeviceFeatures f;
    vkGetPhysicalDeviceFeatures(d, &f);
    const std::string name = p.deviceName;
    if (p.apiVersion < VK_API_VERSION_1_3) {
      why += "; " + name + ": Vulkan below 1.3";
      continue;
    }
    if (!f.shaderFloat64 || !f.shaderInt64) {
      why += "; " + name + ": no 64-bit floats or integers in shaders";
      continue;
    }
    std::uint32_t nf = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(d, &nf, nullptr);
    std::vector<VkQueueFamilyProperties> fam(nf);
    vkGetPhysicalDeviceQueueFamilyProperties(d, &nf, fam.data());
    // A family with graphics and compute when there is one (the raster passes need both), else compute.
    std::uint32_t family = nf;
    for (std::uint32_t q = 0; q < nf && family == nf; ++q)
      if ((fam[q].queueFlags & (VK_QUEUE_COMPUTE_BIT | VK_QUEUE_GRAPHICS_BIT)) == (VK_QUEUE_COMPUTE_BIT | VK_QUEUE_GRAPHICS_BIT)) family = q;
    for (std::uint32_t q = 0; q < nf && family == nf; ++q)
      if (fam[q].queueFlags & VK_QUEUE_COMPUTE_BIT) family = q;
    const bool graphics = family < nf && (fam[family].queueFlags & VK_QUEUE_GRAPHICS_BIT) != 0;
    if (family == nf) {
      why += "; " + name + ": no compute queue";
      continue;
    }
    usable.push_back({d, family, type_rank(p.deviceType), graphics});
  }
  std::stable_sort(usable.begin(), usable.end(), [](const Candidate& a, const Candidate& b) { return a.rank < b.rank; });
  if (usable.empty())
    return Status::input("vulkan: no usable device among " + std::to_string(count) + (why.empty() ? std::string() : why));
  std::size_t pick = 0;
  if (const char* env = std::getenv("R1_VULKAN_DEVICE")) {
    char* end = nullptr;
    const unsigned long k = std::strtoul(env, &end, 10);
    if (end == env || *end != '\0' || k >= usable.size())
      return Status::input("vulkan: R1_VULKAN_DEVICE=" + std::string(env) + " names none of the " + std::to_string(usable.size()) +
                           " usable devices");
    pick = k;
  }
  s->physical = usable[pick].d;
  s->family = usable[pick].family;
  s->info.graphics = usable[pick].graphics;
  {
    auto driver = make<VkPhysicalDeviceDriverProperties>(VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES);
    auto p2 = make<VkPhysicalDeviceProperties2>(VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2);
    p2.pNext = &driver;
    vkGetPhysicalDeviceProperties2(s->physical, &p2);
    s->info.name = p2.properties.deviceName;
    s->info.driver = driver.driverName;
    s->info.api = p2.properties.apiVersion;
    s->info.cpu = p2.properties.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU;
    s->limits = p2.properties.limits;
    s->info.max_buffer = p2.properties.limits.maxStorageBufferRange;
  }
  vkGetPhysicalDeviceMemoryProperties(s->physical, &s->memory);

  const float priority = 1.0f;
  auto qi = make<VkDeviceQueueCreateInfo>(VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO);
  qi.queueFamilyIndex = s->family;
  qi.queueCount = 1;
  qi.pQueuePriorities = &priority;
  // 64-bit floats and integers; dynamic rendering (core in 1.3) for the raster passes.
  auto v13 = make<VkPhysicalDeviceVulkan13Features>(VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES);
  auto features = make<VkPhysicalDeviceFeatures2>(VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2);
  features.pNext = &v13;
  vkGetPhysicalDeviceFeatures2(s->physical, &features);
  s->info.graphics = s->info.graphics && v13.dynamicRendering == VK_TRUE;
  const VkBool32 dynamic_rendering = s->info.graphics ? VK_TRUE : VK_FALSE;
  v13 = make<VkPhysicalDeviceVulkan13Features>(VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES);
  v13.dynamicRendering = dynamic_rendering;
  features = make<VkPhysicalDeviceFeatures2>(VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2);
  features.pNext = &v13;
  features.features.shaderFloat64 = VK_TRUE;
  features.features.shaderInt64 = VK_TRUE;
  auto di = make<VkDeviceCreateInfo>(VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO);
  di.pNext = &features;
  di.queueCreateInfoCount = 1;
  di.pQueueCreateInfos = &qi;
  if (VkResult r = vkCreateDevice(s->physical, &di, nullptr, &s->device); r != VK_SUCCESS) return fail("vkCreateDevice", r);
  vkGetDeviceQueue(s->device, s->family, 0, &s->queue);

  auto pci = make<VkCommandPoolCreateInfo>(VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO);
  pci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pci.queueFamilyIndex = s->family;
  if (VkResult r = vkCreateCommandPool(s->device, &pci, nullptr, &s->pool); r != VK_SUCCESS) return fail("vkCreateCommandPool", r);
  auto cai = make<VkCommandBufferAllocateInfo>(VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO);
  cai.commandPool = s->pool;
  cai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  cai.commandBufferCount = 1;
  if (VkResult r = vkAllocateCommandBuffers(s->device, &cai, &s->cmd); r != VK_SUCCESS) return fail("vkAllocateCommandBuffers", r);
  auto fci = make<VkFenceCreateInfo>(VK_STRUCTURE_TYPE_FENCE_CREATE_INFO);
  if (VkResult r = vkCreateFence(s->device, &fci, nullptr, &s->fence); r != VK_SUCCESS) return fail("vkCreateFence", r);

  std::array<VkDescriptorSetLayoutBinding, kSlots> bindings{};
  for (std::uint32_t i = 0; i < kSlots; ++i) {
    bindings[i].binding = i;
    bindings[i].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    bindings[i].descriptorCount = 1;
    bindings[i].stageFlags = s->stages();
  }
  auto dl = make<VkDescriptorSetLayoutCreateInfo>(VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO);
  dl.bindingCount = kSlots;
  dl.pBindings = bindings.data();
  if (VkResult r = vkCreateDescriptorSetLayout(s->device, &dl, nullptr, &s->set_layout); r != VK_SUCCESS)
    return fail("vkCreateDescriptorSetLayout", r);
  VkPushConstantRange push{s->stages(), 0, kPushBytes};
  auto pl = make<VkPipelineLayoutCreateInfo>(VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO);
  pl.setLayoutCount = 1;
  pl.pSetLayouts = &s->set_layout;
  pl.pushConstantRangeCount = 1;
  pl.pPushConstantRanges = &push;
  if (VkResult r = vkCreatePipelineLayout(s->device, &pl, nullptr, &s->layout); r != VK_SUCCESS) return fail("vkCreatePipelineLayout", r);
  VkDescriptorPoolSize size{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, kSlots};
  auto dp = make<VkDescriptorPoolCreateInfo>(VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO);
  dp.maxSets = 1;
  dp.poolSizeCount = 1;
  dp.pPoolSizes = &size;
  if (VkResult r = vkCreateDescriptorPool(s->device, &dp, nullptr, &s->descriptors); r != VK_SUCCESS)
    return fail("vkCreateDescriptorPool", r);
  R1_ASSIGN(const std::uint32_t placeholder, s->make_buffer(16));
  (void)placeholder;
  return std::unique_ptr<Context>(new Context(std::move(s)));
}

Result<std::uint32_t> Context::buffer_create(std::size_t bytes, Residence where) {
  if (bytes > s_->limits.maxStorageBufferRange)
    return Status::input("vulkan: a buffer of " + std::to_string(bytes) + " bytes exceeds the device's storage range of " +
                         std::to_string(s_->limits.maxStorageBufferRange));
  return s_->make_buffer(bytes, where);
}

void Context::buffer_release(std::uint32_t id) {
  if (id < 1 || id >= s_->buffers.size() || s_->buffers[id].buffer == VK_NULL_HANDLE) return;
  auto& b = s_->buffers[id];
  vkDeviceWaitIdle(s_->device);
  if (b.mapped != nullptr) vkUnmapMemory(s_->device, b.memory);
  vkDestroyBuffer(s_->device, b.buffer, nullptr);
  vkFreeMemory(s_->device, b.memory, nullptr);
  b = State::Buffer{};
}

Status Context::buffer_ensure(std::uint32_t& id, std::size_t bytes, Residence where) {
  if (id != 0 && buffer_size(id) >= bytes && s_->buffers[id].asked == where) return Status::ok();
  buffer_release(id);
  id = 0;
  const std::size_t slack = std::max(bytes, std::min(bytes + bytes / 4, s_->info.max_buffer));
  R1_ASSIGN(id, buffer_create(std::max<std::size_t>(slack, 16), where));
  return Status::ok();
}

std::size_t Context::buffer_size(std::uint32_t id) const {
  return id >= 1 && id < s_->buffers.size() ? s_->buffers[id].size : 0;
}

Status Context::buffer_write(std::uint32_t id, std::span<const std::uint8_t> data, std::size_t offset) {
  if (id < 1 || id >= s_->buffers.size()) return Status::input("vulkan: no buffer " + std::to_string(id));
  const auto& b = s_->buffers[id];
  if (b.mapped == nullptr) return Status::internal("vulkan: buffer " + std::to_string(id) + " is device-only scratch");
  if (offset > b.size || data.size() > b.size - offset)
    return Status::input("vulkan: write of " + std::to_string(data.size()) + " bytes at " + std::to_string(offset) +
                         " overruns buffer " + std::to_string(id) + " of " + std::to_string(b.size));
  if (!data.empty()) std::memcpy(b.mapped + offset, data.data(), data.size());
  return Status::ok();
}

Result<std::vector<std::uint8_t>> Context::buffer_read(std::uint32_t id, std::size_t offset, std::size_t size) {
  if (id < 1 || id >= s_->buffers.size()) return Status::input("vulkan: no buffer " + std::to_string(id));
  const auto& b = s_->buffers[id];
  if (b.mapped == nullptr) return Status::internal("vulkan: buffer " + std::to_string(id) + " is device-only scratch");
  if (offset > b.size || size > b.size - offset)
    return Status::input("vulkan: read of " + std::to_string(size) + " bytes at " + std::to_string(offset) + " overruns buffer " +
                         std::to_string(id) + " of " + std::to_string(b.size));
  return std::vector<std::uint8_t>(b.mapped + offset, b.mapped + offset + size);
}

Result<VkDescriptorSet> Context::State::bind(std::span<const Slot> slots) {
  State& s = *this;
  // Every slot bound: the placeholder where the caller names no buffer.
  std::array<VkDescriptorBufferInfo, kSlots> infos{};
  for (auto& i : infos) i = {s.buffers[0].buffer, 0, VK_WHOLE_SIZE};
  for (const Slot& slot : slots) {
    if (slot.binding >= kSlots) return Status::input("vulkan: binding " + std::to_string(slot.binding) + " beyond the " + std::to_string(kSlots) + " slots");
    if (slot.buffer < 1 || slot.buffer >= s.buffers.size() || s.buffers[slot.buffer].buffer == VK_NULL_HANDLE) return Status::input("vulkan: no buffer " + std::to_string(slot.buffer));
    infos[slot.binding] = {s.buffers[slot.buffer].buffer, 0, VK_WHOLE_SIZE};
  }
  if (VkResult r = vkResetDescriptorPool(s.device, s.descriptors, 0); r != VK_SUCCESS) return fail("vkResetDescriptorPool", r);
  auto ai = make<VkDescriptorSetAllocateInfo>(VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO);
  ai.descriptorPool = s.descriptors;
  ai.descriptorSetCount = 1;
  ai.pSetLayouts = &s.set_layout;
  VkDescriptorSet set = VK_NULL_HANDLE;
  if (VkResult r = vkAllocateDescriptorSets(s.device, &ai, &set); r != VK_SUCCESS) return fail("vkAllocateDescriptorSets", r);
  std::array<VkWriteDescriptorSet, kSlots> writes{};
  for (std::uint32_t i = 0; i < kSlots; ++i) {
    writes[i].sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET;
    writes[i].dstSet = set;
    writes[i].dstBinding = i;
    writes[i].descriptorCount = 1;
    writes[i].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    writes[i].pBufferInfo = &infos[i];
  }
  vkUpdateDescriptorSets(s.device, kSlots, writes.data(), 0, nullptr);
  return set;
}

Result<std::vector<std::uint32_t>> Context::State::spirv(std::string_view glsl, shaderc_shader_kind kind, std::string_view name) {
  // Without a #version line glslang falls back to a profile whose built-ins it cannot parse and
  // prints them all: refuse such a source before it gets there.
  const std::size_t first = glsl.find_first_not_of(" \t\r\n");
  if (first == std::string_view::npos || glsl.substr(first, 8) != "#version")
    return Status::input("vulkan: shader " + std::string(name) + " does not compile: it must begin with a #version line (GLSL 4.60)");
  shaderc_compiler_t compiler = shaderc_compiler_initialize();
  shaderc_compile_options_t options = shaderc_compile_options_initialize();
  if (compiler == nullptr || options == nullptr) {
    shaderc_compile_options_release(options);
    shaderc_compiler_release(compiler);
    return Status::internal("vulkan: shaderc did not initialise");
  }
  shaderc_compile_options_set_target_env(options, shaderc_target_env_vulkan, shaderc_env_version_vulkan_1_3);
  shaderc_compile_options_set_optimization_level(options, shaderc_optimization_level_zero);
  const std::string label(name);
  shaderc_compilation_result_t result =
      shaderc_compile_into_spv(compiler, glsl.data(), glsl.size(), kind, label.c_str(), "main", options);
  shaderc_compile_options_release(options);
  shaderc_compiler_release(compiler);
  if (shaderc_result_get_compilation_status(result) != shaderc_compilation_status_success) {
    std::string message = shaderc_result_get_error_message(result);
    shaderc_result_release(result);
    while (!message.empty() && message.back() == '\n') message.pop_back();
    for (char& c : message)
      if (c == '\n') c = ' ';
    return Status::input("vulkan: shader " + label + " does not compile: " + message);
  }
  const std::size_t bytes = shaderc_result_get_length(result);
  std::vector<std::uint32_t> words(bytes / 4);
  std::memcpy(words.data(), shaderc_result_get_bytes(result), words.size() * 4);
  shaderc_result_release(result);
  return words;
}

Result<std::uint32_t> Context::compute_compile(std::string_view glsl, std::string_view name) {
  // The same source is the same pipeline: kernels made once per stage call (the focus products,
  // R1-BKD-064) compile once per context.
  if (const auto hit = s_->compute_by_source.find(glsl); hit != s_->compute_by_source.end()) return hit->second;
  R1_ASSIGN(const std::vector<std::uint32_t> words, s_->spirv(glsl, shaderc_compute_shader, name));
  const std::string label(name);
  auto mi = make<VkShaderModuleCreateInfo>(VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO);
  mi.codeSize = words.size() * 4;
  mi.pCode = words.data();
  VkShaderModule module = VK_NULL_HANDLE;
  if (VkResult r = vkCreateShaderModule(s_->device, &mi, nullptr, &module); r != VK_SUCCESS) return fail("vkCreateShaderModule", r);
  auto ci = make<VkComputePipelineCreateInfo>(VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO);
  ci.stage.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
  ci.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
  ci.stage.module = module;
  ci.stage.pName = "main";
  ci.layout = s_->layout;
  VkPipeline pipeline = VK_NULL_HANDLE;
  const VkResult r = vkCreateComputePipelines(s_->device, VK_NULL_HANDLE, 1, &ci, nullptr, &pipeline);
  vkDestroyShaderModule(s_->device, module, nullptr);
  if (r != VK_SUCCESS) return fail("vkCreateComputePipelines for " + label, r);
  s_->pipelines.push_back(pipeline);
  s_->graphics_pipeline.push_back(false);
  const auto id = static_cast<std::uint32_t>(s_->pipelines.size() - 1);
  s_->compute_by_source.emplace(std::string(glsl), id);
  return id;
}

Status Context::dispatch(std::uint32_t pipeline, std::span<const Slot> slots, std::array<std::uint32_t, 3> groups,
                         std::span<const std::uint8_t> push) {
  State& s = *s_;
  if (pipeline >= s.pipelines.size() || s.graphics_pipeline[pipeline])
    return Status::input("vulkan: no compute pipeline " + std::to_string(pipeline));
  if (push.size() > kPushBytes || push.size() % 4 != 0)
    return Status::input("vulkan: " + std::to_string(push.size()) + " push-constant bytes (a multiple of 4, at most 128)");
  for (std::size_t a = 0; a < 3; ++a)
    if (groups[a] > s.limits.maxComputeWorkGroupCount[a])
      return Status::input("vulkan: " + std::to_string(groups[a]) + " workgroups on axis " + std::to_string(a) + " exceed the device's " +
                           std::to_string(s.limits.maxComputeWorkGroupCount[a]));
  VkDescriptorSet set = VK_NULL_HANDLE;
  R1_ASSIGN(set, s.bind(slots));

  return s.submit([&](VkCommandBuffer cmd) {
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, s.pipelines[pipeline]);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, s.layout, 0, 1, &set, 0, nullptr);
    if (!push.empty()) vkCmdPushConstants(cmd, s.layout, s.stages(), 0, static_cast<std::uint32_t>(push.size()), push.data());
    vkCmdDispatch(cmd, groups[0], groups[1], groups[2]);
    // The shader's writes, visible to the host's reads of the mapped memory.
    auto barrier = make<VkMemoryBarrier>(VK_STRUCTURE_TYPE_MEMORY_BARRIER);
    barrier.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
    barrier.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &barrier, 0, nullptr, 0, nullptr);
  });
}

Status Context::State::submit(const std::function<void(VkCommandBuffer)>& record) {
  auto bi = make<VkCommandBufferBeginInfo>(VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO);
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  if (VkResult r = vkBeginCommandBuffer(cmd, &bi); r != VK_SUCCESS) return fail("vkBeginCommandBuffer", r);
  record(cmd);
  if (VkResult r = vkEndCommandBuffer(cmd); r != VK_SUCCESS) return fail("vkEndCommandBuffer", r);
  auto si = make<VkSubmitInfo>(VK_STRUCTURE_TYPE_SUBMIT_INFO);
  si.commandBufferCount = 1;
  si.pCommandBuffers = &cmd;
  if (VkResult r = vkQueueSubmit(queue, 1, &si, fence); r != VK_SUCCESS) return fail("vkQueueSubmit", r);
  const VkResult w = vkWaitForFences(device, 1, &fence, VK_TRUE, UINT64_MAX);
  vkResetFences(device, 1, &fence);
  vkResetCommandBuffer(cmd, 0);
  if (w != VK_SUCCESS) return fail("vkWaitForFences", w);
  return Status::ok();
}

}  // namespace r1::vk
