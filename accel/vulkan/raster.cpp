// The Vulkan context's raster path (spec/backends.md R1-BKD-068): offscreen render targets,
// graphics pipelines with dynamic rendering (Vulkan 1.3), indirect draws and read-back.
#include <string>

#include "context_state.hpp"

namespace r1::vk {

namespace {

constexpr VkFormat kColorFormat = VK_FORMAT_R32G32B32A32_UINT;
constexpr VkFormat kDepthFormat = VK_FORMAT_D32_SFLOAT;

Status no_raster(const char* what) {
  return Status::input(std::string("vulkan: ") + what + ": this device has no graphics queue with dynamic rendering");
}

}  // namespace

Result<std::uint32_t> Context::target_create(std::uint32_t width, std::uint32_t height) {
  State& s = *s_;
  if (!s.info.graphics) return no_raster("target_create");
  if (width == 0 || height == 0 || width > s.limits.maxImageDimension2D || height > s.limits.maxImageDimension2D ||
      width > s.limits.maxFramebufferWidth || height > s.limits.maxFramebufferHeight)
    return Status::input("vulkan: a render target of " + std::to_string(width) + " x " + std::to_string(height) +
                         " pixels (the device allows 1.." + std::to_string(s.limits.maxFramebufferWidth) + " x 1.." +
                         std::to_string(s.limits.maxFramebufferHeight) + ")");
  for (const VkFormat f : {kColorFormat, kDepthFormat}) {
    VkFormatProperties fp;
    vkGetPhysicalDeviceFormatProperties(s.physical, f, &fp);
    const VkFormatFeatureFlags need =
        f == kDepthFormat ? VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT : VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BIT;
    if ((fp.optimalTilingFeatures & need) == 0)
      return Status::input("vulkan: the device cannot render to format " + std::to_string(static_cast<int>(f)));
  }
  State::Target t;
  t.width = width, t.height = height;
  // Whatever is made before a failure is destroyed with the context: the target is recorded first.
  s.targets.push_back(t);
  State::Target& tt = s.targets.back();
  for (std::size_t i = 0; i < tt.image.size(); ++i) {
    const bool depth = i == kTargetColors;
    auto ii = make<VkImageCreateInfo>(VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO);
    ii.imageType = VK_IMAGE_TYPE_2D;
    ii.format = depth ? kDepthFormat : kColorFormat;
    ii.extent = {width, height, 1};
    ii.mipLevels = 1;
    ii.arrayLayers = 1;
    ii.samples = VK_SAMPLE_COUNT_1_BIT;
    ii.tiling = VK_IMAGE_TILING_OPTIMAL;
    ii.usage = depth ? VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT : VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
    ii.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    ii.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    if (VkResult r = vkCreateImage(s.device, &ii, nullptr, &tt.image[i]); r != VK_SUCCESS) return fail("vkCreateImage", r);
    VkMemoryRequirements req;
    vkGetImageMemoryRequirements(s.device, tt.image[i], &req);
    auto type = s.memory_type(req.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
    if (!type.is_ok()) type = s.memory_type(req.memoryTypeBits, 0);
    R1_TRY(type.status());
    auto ai = make<VkMemoryAllocateInfo>(VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO);
    ai.allocationSize = req.size;
    ai.memoryTypeIndex = *type;
    if (VkResult r = vkAllocateMemory(s.device, &ai, nullptr, &tt.memory[i]); r != VK_SUCCESS)
      return fail("vkAllocateMemory of " + std::to_string(req.size) + " bytes for a render target", r);
    vkBindImageMemory(s.device, tt.image[i], tt.memory[i], 0);
    auto vi = make<VkImageViewCreateInfo>(VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO);
    vi.image = tt.image[i];
    vi.viewType = VK_IMAGE_VIEW_TYPE_2D;
    vi.format = ii.format;
    vi.subresourceRange = {static_cast<VkImageAspectFlags>(depth ? VK_IMAGE_ASPECT_DEPTH_BIT : VK_IMAGE_ASPECT_COLOR_BIT), 0, 1, 0, 1};
    if (VkResult r = vkCreateImageView(s.device, &vi, nullptr, &tt.view[i]); r != VK_SUCCESS) return fail("vkCreateImageView", r);
  }
  const std::uint32_t index = static_cast<std::uint32_t>(s.targets.size() - 1);
  for (std::uint32_t i = 0; i < kTargetColors; ++i) {
    R1_ASSIGN(const std::uint32_t b, s.make_buffer(std::size_t{width} * height * 16));
    s.targets[index].readback[i] = b;
  }
  return index;
}

Status Context::graphics_check(std::string_view glsl, bool vertex, std::string_view name) {
  if (!s_->info.graphics) return no_raster(vertex ? "a vertex shader" : "a fragment shader");
  return s_->spirv(glsl, vertex ? shaderc_vertex_shader : shaderc_fragment_shader, name).status();
}

Result<std::uint32_t> Context::graphics_compile(std::string_view vertex, std::string_view fragment, std::string_view name) {
  State& s = *s_;
  if (!s.info.graphics) return no_raster("graphics_compile");
  const std::string label(name);
  R1_ASSIGN(const std::vector<std::uint32_t> vs, s.spirv(vertex, shaderc_vertex_shader, label + ".vert"));
  R1_ASSIGN(const std::vector<std::uint32_t> fs, s.spirv(fragment, shaderc_fragment_shader, label + ".frag"));
  std::array<VkShaderModule, 2> modules{};
  std::array<VkPipelineShaderStageCreateInfo, 2> stages{};
  const std::array<const std::vector<std::uint32_t>*, 2> code{&vs, &fs};
  for (std::size_t i = 0; i < 2; ++i) {
    auto mi = make<VkShaderModuleCreateInfo>(VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO);
    mi.codeSize = code[i]->size() * 4;
    mi.pCode = code[i]->data();
    if (VkResult r = vkCreateShaderModule(s.device, &mi, nullptr, &modules[i]); r != VK_SUCCESS) {
      if (i == 1) vkDestroyShaderModule(s.device, modules[0], nullptr);
      return fail("vkCreateShaderModule", r);
    }
    stages[i] = make<VkPipelineShaderStageCreateInfo>(VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO);
    stages[i].stage = i == 0 ? VK_SHADER_STAGE_VERTEX_BIT : VK_SHADER_STAGE_FRAGMENT_BIT;
    stages[i].module = modules[i];
    stages[i].pName = "main";
  }
  const std::array<VkFormat, kTargetColors> formats{kColorFormat, kColorFormat, kColorFormat};
  auto rendering = make<VkPipelineRenderingCreateInfo>(VK_STRUCTURE_TYPE_PIPELINE_RENDERING_CREATE_INFO);
  rendering.colorAttachmentCount = kTargetColors;
  rendering.pColorAttachmentFormats = formats.data();
  rendering.depthAttachmentFormat = kDepthFormat;
  auto vertex_input = make<VkPipelineVertexInputStateCreateInfo>(VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO);
  auto assembly = make<VkPipelineInputAssemblyStateCreateInfo>(VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO);
  assembly.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
  auto viewport = make<VkPipelineViewportStateCreateInfo>(VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO);
  viewport.viewportCount = 1;
  viewport.scissorCount = 1;
  auto raster = make<VkPipelineRasterizationStateCreateInfo>(VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO);
  raster.polygonMode = VK_POLYGON_MODE_FILL;
  raster.cullMode = VK_CULL_MODE_NONE;
  raster.frontFace = VK_FRONT_FACE_COUNTER_CLOCKWISE;
  raster.lineWidth = 1.0f;
  auto multisample = make<VkPipelineMultisampleStateCreateInfo>(VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO);
  multisample.rasterizationSamples = VK_SAMPLE_COUNT_1_BIT;
  auto depth = make<VkPipelineDepthStencilStateCreateInfo>(VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO);
  depth.depthTestEnable = VK_TRUE;
  depth.depthWriteEnable = VK_TRUE;
  depth.depthCompareOp = VK_COMPARE_OP_LESS;
  std::array<VkPipelineColorBlendAttachmentState, kTargetColors> blend{};
  for (auto& b : blend)
    b.colorWriteMask = VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT | VK_COLOR_COMPONENT_B_BIT | VK_COLOR_COMPONENT_A_BIT;
  auto blending = make<VkPipelineColorBlendStateCreateInfo>(VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO);
  blending.attachmentCount = kTargetColors;
  blending.pAttachments = blend.data();
  const std::array<VkDynamicState, 2> dynamic_states{VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR};
  auto dynamic = make<VkPipelineDynamicStateCreateInfo>(VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO);
  dynamic.dynamicStateCount = static_cast<std::uint32_t>(dynamic_states.size());
  dynamic.pDynamicStates = dynamic_states.data();
  auto gi = make<VkGraphicsPipelineCreateInfo>(VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO);
  gi.pNext = &rendering;
  gi.stageCount = 2;
  gi.pStages = stages.data();
  gi.pVertexInputState = &vertex_input;
  gi.pInputAssemblyState = &assembly;
  gi.pViewportState = &viewport;
  gi.pRasterizationState = &raster;
  gi.pMultisampleState = &multisample;
  gi.pDepthStencilState = &depth;
  gi.pColorBlendState = &blending;
  gi.pDynamicState = &dynamic;
  gi.layout = s.layout;
  VkPipeline pipeline = VK_NULL_HANDLE;
  const VkResult r = vkCreateGraphicsPipelines(s.device, VK_NULL_HANDLE, 1, &gi, nullptr, &pipeline);
  for (VkShaderModule m : modules) vkDestroyShaderModule(s.device, m, nullptr);
  if (r != VK_SUCCESS) return fail("vkCreateGraphicsPipelines for " + label, r);
  s.pipelines.push_back(pipeline);
  s.graphics_pipeline.push_back(true);
  return static_cast<std::uint32_t>(s.pipelines.size() - 1);
}

Status Context::draw_indirect(std::uint32_t pipeline, std::uint32_t target, std::span<const Slot> slots, std::uint32_t indirect,
                              std::uint32_t draws, const Clear& clear, std::span<const std::uint8_t> push) {
  State& s = *s_;
  if (!s.info.graphics) return no_raster("draw_indirect");
  if (pipeline >= s.pipelines.size() || !s.graphics_pipeline[pipeline])
    return Status::input("vulkan: no graphics pipeline " + std::to_string(pipeline));
  if (target >= s.targets.size() || s.targets[target].width == 0) return Status::input("vulkan: no render target " + std::to_string(target));
  if (indirect < 1 || indirect >= s.buffers.size() || s.buffers[indirect].buffer == VK_NULL_HANDLE)
    return Status::input("vulkan: no indirect buffer " + std::to_string(indirect));
  if (std::size_t{draws} * 16 > s.buffers[indirect].size)
    return Status::input("vulkan: " + std::to_string(draws) + " indirect draws overrun buffer " + std::to_string(indirect) + " of " +
                         std::to_string(s.buffers[indirect].size) + " bytes");
  if (push.size() > kPushBytes || push.size() % 4 != 0)
    return Status::input("vulkan: " + std::to_string(push.size()) + " push-constant bytes (a multiple of 4, at most 128)");
  VkDescriptorSet set = VK_NULL_HANDLE;
  R1_ASSIGN(set, s.bind(slots));
  const State::Target& t = s.targets[target];
  return s.submit([&](VkCommandBuffer cmd) {
    std::array<VkImageMemoryBarrier, kTargetColors + 1> to_attachment{};
    for (std::size_t i = 0; i < to_attachment.size(); ++i) {
      const bool d = i == kTargetColors;
      auto& b = to_attachment[i];
      b = make<VkImageMemoryBarrier>(VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER);
      b.dstAccessMask = d ? VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT : VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
      b.oldLayout = VK_IMAGE_LAYOUT_UNDEFINED;
      b.newLayout = d ? VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL : VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
      b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
      b.image = t.image[i];
      b.subresourceRange = {static_cast<VkImageAspectFlags>(d ? VK_IMAGE_ASPECT_DEPTH_BIT : VK_IMAGE_ASPECT_COLOR_BIT), 0, 1, 0, 1};
    }
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT,
                         VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT |
                             VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT,
                         0, 0, nullptr, 0, nullptr, static_cast<std::uint32_t>(to_attachment.size()), to_attachment.data());
    std::array<VkRenderingAttachmentInfo, kTargetColors> colors{};
    for (std::uint32_t i = 0; i < kTargetColors; ++i) {
      colors[i] = make<VkRenderingAttachmentInfo>(VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO);
      colors[i].imageView = t.view[i];
      colors[i].imageLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
      colors[i].loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
      colors[i].storeOp = VK_ATTACHMENT_STORE_OP_STORE;
      for (std::size_t c = 0; c < 4; ++c) colors[i].clearValue.color.uint32[c] = clear[i][c];
    }
    auto depth = make<VkRenderingAttachmentInfo>(VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO);
    depth.imageView = t.view[kTargetColors];
    depth.imageLayout = VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL;
    depth.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
    depth.storeOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
    depth.clearValue.depthStencil = {1.0f, 0};
    auto ri = make<VkRenderingInfo>(VK_STRUCTURE_TYPE_RENDERING_INFO);
    ri.renderArea = {{0, 0}, {t.width, t.height}};
    ri.layerCount = 1;
    ri.colorAttachmentCount = kTargetColors;
    ri.pColorAttachments = colors.data();
    ri.pDepthAttachment = &depth;
    vkCmdBeginRendering(cmd, &ri);
    const VkViewport vp{0.0f, 0.0f, static_cast<float>(t.width), static_cast<float>(t.height), 0.0f, 1.0f};
    const VkRect2D scissor{{0, 0}, {t.width, t.height}};
    vkCmdSetViewport(cmd, 0, 1, &vp);
    vkCmdSetScissor(cmd, 0, 1, &scissor);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, s.pipelines[pipeline]);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, s.layout, 0, 1, &set, 0, nullptr);
    if (!push.empty()) vkCmdPushConstants(cmd, s.layout, s.stages(), 0, static_cast<std::uint32_t>(push.size()), push.data());
    if (draws > 0) vkCmdDrawIndirect(cmd, s.buffers[indirect].buffer, 0, draws, 16);
    vkCmdEndRendering(cmd);
    std::array<VkImageMemoryBarrier, kTargetColors> to_copy{};
    for (std::uint32_t i = 0; i < kTargetColors; ++i) {
      auto& b = to_copy[i];
      b = make<VkImageMemoryBarrier>(VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER);
      b.srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
      b.dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
      b.oldLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
      b.newLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
      b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
      b.image = t.image[i];
      b.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    }
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0, nullptr, 0, nullptr,
                         kTargetColors, to_copy.data());
    for (std::uint32_t i = 0; i < kTargetColors; ++i) {
      VkBufferImageCopy region{};
      region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
      region.imageExtent = {t.width, t.height, 1};
      vkCmdCopyImageToBuffer(cmd, t.image[i], VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, s.buffers[t.readback[i]].buffer, 1, &region);
    }
    auto barrier = make<VkMemoryBarrier>(VK_STRUCTURE_TYPE_MEMORY_BARRIER);
    barrier.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    barrier.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &barrier, 0, nullptr, 0, nullptr);
  });
}

Result<std::vector<std::uint32_t>> Context::target_read(std::uint32_t target, std::uint32_t index) {
  State& s = *s_;
  if (target >= s.targets.size() || s.targets[target].width == 0 || index >= kTargetColors)
    return Status::input("vulkan: no colour attachment " + std::to_string(index) + " of render target " + std::to_string(target));
  const State::Target& t = s.targets[target];
  const auto& b = s.buffers[t.readback[index]];
  std::vector<std::uint32_t> out(std::size_t{t.width} * t.height * 4);
  std::memcpy(out.data(), b.mapped, out.size() * 4);
  return out;
}

void Context::target_release(std::uint32_t target) {
  State& s = *s_;
  if (target >= s.targets.size() || s.targets[target].width == 0) return;
  vkDeviceWaitIdle(s.device);
  State::Target& t = s.targets[target];
  for (std::size_t i = 0; i < t.image.size(); ++i) {
    vkDestroyImageView(s.device, t.view[i], nullptr);
    vkDestroyImage(s.device, t.image[i], nullptr);
    vkFreeMemory(s.device, t.memory[i], nullptr);
  }
  for (const std::uint32_t b : t.readback) buffer_release(b);
  t = State::Target{};
}

}  // namespace r1::vk
