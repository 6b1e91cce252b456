// The Vulkan device (spec/backends.md R1-BKD-060..063): the 13.1 trait on accel/vulkan's
// compute context. Buffers and compute are the device's; the Clifford primitives run as compute
// shaders with det_exp's constants taken from the reference; graphics pipelines, indirect draws
// and an offscreen surface on the context's raster path (R1-BKD-068).
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "r1/accel/vulkan.hpp"
#include "r1/backends/device.hpp"
#include "r1/reference/clifford.hpp"
#include "vulkan_adapters.hpp"

namespace r1::backends {

namespace {


class VulkanDevice final : public Device {
 public:
  VulkanDevice(std::shared_ptr<vk::Context> ctx, vk::CliffordKernels kernels)
      : ctx_(std::move(ctx)), kernels_(std::move(kernels)) {}

  Result<BufferId> buffer_create(std::size_t size, BufferUsage) override { return ctx_->buffer_create(size); }
  Status buffer_write(BufferId id, std::span<const std::uint8_t> data, std::size_t offset) override {
    return ctx_->buffer_write(id, data, offset);
  }
  Result<std::vector<std::uint8_t>> buffer_read(BufferId id, std::size_t offset, std::size_t size) override {
    return ctx_->buffer_read(id, offset, size);
  }
  // Shader ids index shaders_: a compute shader is its pipeline, a vertex or fragment shader its
  // checked source until pipeline_create joins two.
  Result<ShaderId> shader_compile(std::string_view source, ShaderStage stage) override {
    Shader sh{stage, 0, std::string(source)};
    if (stage == ShaderStage::kCompute) {
      R1_ASSIGN(sh.pipeline, ctx_->compute_compile(source, "shader_compile"));
      sh.source.clear();
    } else {
      R1_TRY(ctx_->graphics_check(source, stage == ShaderStage::kVertex, "shader_compile"));
    }
    shaders_.push_back(std::move(sh));
    return static_cast<ShaderId>(shaders_.size() - 1);
  }
  Status compute_dispatch(ShaderId shader, std::span<const Binding> bindings, std::array<std::uint32_t, 3> groups) override {
    if (shader >= shaders_.size() || shaders_[shader].stage != ShaderStage::kCompute)
      return Status::input("vulkan device: no compute shader " + std::to_string(shader));
    return ctx_->dispatch(shaders_[shader].pipeline, slots_of(bindings), groups);
  }
  Result<PipelineId> pipeline_create(const PipelineShaders& shaders, const PipelineLayout& layout) override {
    if (shaders.vertex >= shaders_.size() || shaders_[shaders.vertex].stage != ShaderStage::kVertex)
      return Status::input("vulkan device: no vertex shader " + std::to_string(shaders.vertex));
    if (shaders.fragment >= shaders_.size() || shaders_[shaders.fragment].stage != ShaderStage::kFragment)
      return Status::input("vulkan device: no fragment shader " + std::to_string(shaders.fragment));
    for (const std::uint32_t slot : layout.slots)
      if (slot >= vk::Context::kSlots)
        return Status::input("vulkan device: slot " + std::to_string(slot) + " beyond the " + std::to_string(vk::Context::kSlots) + " slots");
    return ctx_->graphics_compile(shaders_[shaders.vertex].source, shaders_[shaders.fragment].source, "pipeline_create");
  }
  Status draw_indirect(PipelineId pipeline, std::span<const Binding> bindings, BufferId indirect, std::uint32_t count) override {
    if (!acquired_) return Status::input("vulkan device: draw_indirect before surface_acquire");
    return ctx_->draw_indirect(pipeline, *acquired_, slots_of(bindings), indirect, count, vk::Context::Clear{});
  }
  Status surface_configure(std::uint32_t width, std::uint32_t height) override {
    R1_ASSIGN(const std::uint32_t target, ctx_->target_create(width, height));
    if (surface_) ctx_->target_release(*surface_);
    surface_ = target;
    acquired_.reset();
    return Status::ok();
  }
  Result<TextureId> surface_acquire() override {
    if (!surface_) R1_TRY(surface_configure(1280, 720));
    acquired_ = surface_;
    return *surface_;
  }
  Status surface_present(TextureId texture) override {
    if (!acquired_ || texture != *acquired_) return Status::input("vulkan device: texture " + std::to_string(texture) + " was not acquired");
    acquired_.reset();  // offscreen: presenting hands the frame to surface_read
    return Status::ok();
  }
  Result<std::vector<std::uint32_t>> surface_read(TextureId texture, std::uint32_t attachment) override {
    if (!surface_ || texture != *surface_) return Status::input("vulkan device: no surface texture " + std::to_string(texture));
    return ctx_->target_read(texture, attachment);
  }

  Result<BufferId> roll(BufferId t, std::int32_t shift, std::uint32_t axis) override { return kernels_.roll(t, shift, axis); }
  Result<BufferId> shifted_inner(BufferId h, BufferId c, std::span<const std::int32_t> shifts) override {
    return kernels_.shifted_inner(h, c, shifts);
  }
  Result<BufferId> shifted_wedge(BufferId h, BufferId c, std::span<const std::int32_t> shifts) override {
    return kernels_.shifted_wedge(h, c, shifts);
  }
  Result<BufferId> clifford_block(BufferId h, BufferId c, std::span<const std::int32_t> shifts, BufferId gate) override {
    return kernels_.block(h, c, shifts, gate);
  }
  // The Clifford primitives match the reference bit for bit where the driver's fp64 division is
  // correctly rounded and subnormals are kept (lavapipe; the trait test holds every device to it).
  bool deterministic_mode() const override { return true; }
  Domain numeric_domain() const override { return Domain::kFp64; }
  std::string describe() const override {
    return ctx_->info().name + " (" + ctx_->info().driver + (ctx_->info().cpu ? ", on the CPU" : "") + ")";
  }

 private:
  struct Shader {
    ShaderStage stage;
    std::uint32_t pipeline;  // compute: the context's pipeline
    std::string source;      // vertex and fragment: the GLSL
  };
  static std::vector<vk::Slot> slots_of(std::span<const Binding> bindings) {
    std::vector<vk::Slot> slots;
    for (const Binding& b : bindings) slots.push_back({b.slot, b.buffer});
    return slots;
  }
  std::shared_ptr<vk::Context> ctx_;
  vk::CliffordKernels kernels_;
  std::vector<Shader> shaders_;
  std::optional<std::uint32_t> surface_, acquired_;
};

}  // namespace

Result<std::unique_ptr<Device>> make_vulkan_device() {
  R1_ASSIGN(std::shared_ptr<vk::Context> ctx, vk::Context::create());
  return make_vulkan_device_on(std::move(ctx));
}

vk::ExpConstants reference_exp_constants() {
  vk::ExpConstants c;
  c.log2e = clifford::detail::kLog2e;
  c.ln2_hi = clifford::detail::kLn2Hi;
  c.ln2_lo = clifford::detail::kLn2Lo;
  const auto taylor = clifford::detail::exp_taylor();
  c.taylor.assign(taylor.begin(), taylor.end());
  return c;
}

Result<std::unique_ptr<Device>> make_vulkan_device_on(std::shared_ptr<vk::Context> ctx) {
  R1_ASSIGN(auto kernels, vk::CliffordKernels::build(*ctx, reference_exp_constants()));
  return std::unique_ptr<Device>(std::make_unique<VulkanDevice>(std::move(ctx), std::move(kernels)));
}

}  // namespace r1::backends
