// The host device (R1-BKD-012..013): the 13.1 trait over host memory, with the reference's
// Clifford primitives. Compute shaders, raster and presentation are not available on it. The
// tensor buffers are the format library's (r1/format/tensor.hpp).
#include <algorithm>

#include "r1/backends/device.hpp"
#include "r1/format/bytes.hpp"
#include "r1/format/tensor.hpp"
#include "r1/reference/clifford.hpp"

namespace r1::backends {

namespace {

Status unsupported(const char* what) {
  return Status::input(std::string("host device: ") + what + " is not available (no GPU-like resources)");
}

class HostDevice final : public Device {
 public:
  Result<BufferId> buffer_create(std::size_t size, BufferUsage) override {
    buffers_.emplace_back(size, std::uint8_t{0});
    return static_cast<BufferId>(buffers_.size() - 1);
  }
  Status buffer_write(BufferId id, std::span<const std::uint8_t> data, std::size_t offset) override {
    R1_ASSIGN(std::vector<std::uint8_t>* b, buffer(id));
    if (offset > b->size() || data.size() > b->size() - offset)
      return Status::input("host device: write of " + std::to_string(data.size()) + " bytes at " + std::to_string(offset) +
                           " overruns buffer " + std::to_string(id));
    std::copy(data.begin(), data.end(), b->begin() + static_cast<std::ptrdiff_t>(offset));
    return Status::ok();
  }
  Result<std::vector<std::uint8_t>> buffer_read(BufferId id, std::size_t offset, std::size_t size) override {
    R1_ASSIGN(std::vector<std::uint8_t>* b, buffer(id));
    if (offset > b->size() || size > b->size() - offset)
      return Status::input("host device: read of " + std::to_string(size) + " bytes at " + std::to_string(offset) +
                           " overruns buffer " + std::to_string(id));
    return std::vector<std::uint8_t>(b->begin() + static_cast<std::ptrdiff_t>(offset),
                                     b->begin() + static_cast<std::ptrdiff_t>(offset + size));
  }
  Result<ShaderId> shader_compile(std::string_view, ShaderStage) override { return unsupported("shader_compile"); }
  Status compute_dispatch(ShaderId, std::span<const Binding>, std::array<std::uint32_t, 3>) override {
    return unsupported("compute_dispatch");
  }
  Result<PipelineId> pipeline_create(const PipelineShaders&, const PipelineLayout&) override {
    return unsupported("pipeline_create");
  }
  Status draw_indirect(PipelineId, std::span<const Binding>, BufferId, std::uint32_t) override {
    return unsupported("draw_indirect");
  }
  Status surface_configure(std::uint32_t, std::uint32_t) override { return unsupported("surface_configure"); }
  Result<TextureId> surface_acquire() override { return unsupported("surface_acquire"); }
  Status surface_present(TextureId) override { return unsupported("surface_present"); }
  Result<std::vector<std::uint32_t>> surface_read(TextureId, std::uint32_t) override { return unsupported("surface_read"); }

  Result<BufferId> roll(BufferId t, std::int32_t shift, std::uint32_t axis) override {
    R1_ASSIGN(const clifford::Rows x, tensor(t));
    R1_ASSIGN(const clifford::Rows y, clifford::roll(x, shift, axis));
    return store(y);
  }
  Result<BufferId> shifted_inner(BufferId h, BufferId c, std::span<const std::int32_t> shifts) override {
    R1_ASSIGN(const clifford::Rows a, tensor(h));
    R1_ASSIGN(const clifford::Rows b, tensor(c));
    R1_ASSIGN(const clifford::Rows y, clifford::shifted_inner(a, b, shifts));
    return store(y);
  }
  Result<BufferId> shifted_wedge(BufferId h, BufferId c, std::span<const std::int32_t> shifts) override {
    R1_ASSIGN(const clifford::Rows a, tensor(h));
    R1_ASSIGN(const clifford::Rows b, tensor(c));
    R1_ASSIGN(const clifford::Rows y, clifford::shifted_wedge(a, b, shifts));
    return store(y);
  }
  Result<BufferId> clifford_block(BufferId h, BufferId c, std::span<const std::int32_t> shifts, BufferId gate) override {
    R1_ASSIGN(const clifford::Rows a, tensor(h));
    R1_ASSIGN(const clifford::Rows b, tensor(c));
    R1_ASSIGN(std::vector<std::uint8_t>* g, buffer(gate));
    const std::size_t d = a.d, s = shifts.size();
    const std::size_t sizes[5] = {2 * s * d * d, d, 2 * d * d, d, d};
    std::size_t total = 0;
    for (std::size_t z : sizes) total += z;
    if (g->size() != total * 8)
      return Status::input("host device: gate buffer " + std::to_string(gate) + " holds " + std::to_string(g->size()) +
                           " bytes, expected " + std::to_string(total * 8) + " for d = " + std::to_string(d) +
                           " and " + std::to_string(s) + " shifts");
    std::vector<double> all(total);
    for (std::size_t i = 0; i < total; ++i) all[i] = format::load_f64(g->data() + i * 8);
    clifford::BlockParams p;
    std::size_t at = 0;
    auto take = [&](std::size_t k) {
      std::vector<double> v(all.begin() + static_cast<std::ptrdiff_t>(at), all.begin() + static_cast<std::ptrdiff_t>(at + k));
      at += k;
      return v;
    };
    p.w = {static_cast<std::uint32_t>(2 * s * d), static_cast<std::uint32_t>(d), take(sizes[0])};
    p.bias = take(sizes[1]);
    p.wg = {static_cast<std::uint32_t>(2 * d), static_cast<std::uint32_t>(d), take(sizes[2])};
    p.bg = take(sizes[3]);
    p.gamma = take(sizes[4]);
    R1_ASSIGN(const clifford::Rows y, clifford::clifford_block(a, b, shifts, p));
    return store(y);
  }
  bool deterministic_mode() const override { return true; }
  Domain numeric_domain() const override { return Domain::kFp64; }

 private:
  Result<std::vector<std::uint8_t>*> buffer(BufferId id) {
    if (id >= buffers_.size()) return Status::input("host device: no buffer " + std::to_string(id));
    return &buffers_[id];
  }
  Result<clifford::Rows> tensor(BufferId id) {
    R1_ASSIGN(std::vector<std::uint8_t>* b, buffer(id));
    R1_ASSIGN(auto t, parse_tensor_bytes(*b));
    return clifford::Rows{t.first[0], t.first[1], std::move(t.second)};
  }
  Result<BufferId> store(const clifford::Rows& r) {
    const auto bytes = tensor_bytes(r.n, r.d, r.v);
    R1_ASSIGN(const BufferId id, buffer_create(bytes.size(), BufferUsage::kTensor));
    R1_TRY(buffer_write(id, bytes, 0));
    return id;
  }
  std::vector<std::vector<std::uint8_t>> buffers_;
};

}  // namespace

std::vector<std::uint8_t> tensor_bytes(std::uint32_t n, std::uint32_t d, std::span<const double> values) {
  return format::tensor_bytes(n, d, values);
}

Result<std::pair<std::array<std::uint32_t, 2>, std::vector<double>>> parse_tensor_bytes(std::span<const std::uint8_t> b) {
  return format::parse_tensor_bytes(b);
}

std::unique_ptr<Device> make_host_device() { return std::make_unique<HostDevice>(); }

#ifndef R1_BACKEND_VULKAN
Result<std::unique_ptr<Device>> make_vulkan_device() {
  return Status::input("vulkan device: r1 was built without Vulkan (R1_BACKEND_VULKAN off: no Vulkan loader or shaderc when it was configured)");
}
#endif

}  // namespace r1::backends
