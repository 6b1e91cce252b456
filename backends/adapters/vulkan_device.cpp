// The Vulkan device (spec/backends.md R1-BKD-060..063): the 13.1 trait on accel/vulkan's
// compute context. Buffers and compute are the device's; the Clifford primitives run as compute
// shaders with det_exp's constants taken from the reference. Graphics pipelines, indirect draws
// and the surface are not built yet: each says so as an input error.
#include <utility>

#include "r1/accel/vulkan.hpp"
#include "r1/backends/device.hpp"
#include "r1/reference/clifford.hpp"
#include "vulkan_adapters.hpp"

namespace r1::backends {

namespace {

Status not_yet(const char* what) {
  return Status::input(std::string("vulkan device: ") + what + " is not available yet (compute only)");
}

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
  Result<ShaderId> shader_compile(std::string_view source, ShaderStage stage) override {
    if (stage != ShaderStage::kCompute) return not_yet("a vertex or fragment shader");
    return ctx_->compute_compile(source, "shader_compile");
  }
  Status compute_dispatch(ShaderId shader, std::span<const Binding> bindings, std::array<std::uint32_t, 3> groups) override {
    std::vector<vk::Slot> slots;
    for (const Binding& b : bindings) slots.push_back({b.slot, b.buffer});
    return ctx_->dispatch(shader, slots, groups);
  }
  Result<PipelineId> pipeline_create(const PipelineShaders&, const PipelineLayout&) override { return not_yet("pipeline_create"); }
  Status draw_indirect(PipelineId, std::span<const Binding>, BufferId, std::uint32_t) override { return not_yet("draw_indirect"); }
  Result<TextureId> surface_acquire() override { return not_yet("surface_acquire"); }
  Status surface_present(TextureId) override { return not_yet("surface_present"); }

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
  std::shared_ptr<vk::Context> ctx_;
  vk::CliffordKernels kernels_;
};

}  // namespace

Result<std::unique_ptr<Device>> make_vulkan_device() {
  R1_ASSIGN(std::shared_ptr<vk::Context> ctx, vk::Context::create());
  return make_vulkan_device_on(std::move(ctx));
}

Result<std::unique_ptr<Device>> make_vulkan_device_on(std::shared_ptr<vk::Context> ctx) {
  vk::ExpConstants c;
  c.log2e = clifford::detail::kLog2e;
  c.ln2_hi = clifford::detail::kLn2Hi;
  c.ln2_lo = clifford::detail::kLn2Lo;
  const auto taylor = clifford::detail::exp_taylor();
  c.taylor.assign(taylor.begin(), taylor.end());
  R1_ASSIGN(auto kernels, vk::CliffordKernels::build(*ctx, c));
  return std::unique_ptr<Device>(std::make_unique<VulkanDevice>(std::move(ctx), std::move(kernels)));
}

}  // namespace r1::backends
