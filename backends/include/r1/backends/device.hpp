// The section 13.1 trait (spec/backends.md R1-BKD-012): GPU-like resources, compute and
// raster, presentation, the Clifford primitives of the T-infinity block and the determinism
// promise. A backend with such resources returns one from Backend::device(). Methods return
// values (R1-ERR-004); an operation a device cannot do is an input error that says so.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "r1/backends/backend.hpp"

namespace r1::backends {

using BufferId = std::uint32_t;
using ShaderId = std::uint32_t;
using PipelineId = std::uint32_t;
using TextureId = std::uint32_t;

enum class BufferUsage : std::uint8_t { kStorage, kUniform, kIndirect, kVertex, kTensor };
enum class ShaderStage : std::uint8_t { kCompute, kVertex, kFragment };

struct Binding {
  std::uint32_t slot = 0;
  BufferId buffer = 0;
};
struct PipelineShaders {
  ShaderId vertex = 0, fragment = 0;
};
struct PipelineLayout {
  std::vector<std::uint32_t> slots;
};

// A tensor buffer for the Clifford primitives (R1-BKD-013): u32 n, u32 d (little-endian), then
// n x d IEEE doubles row-major, little-endian. The gate buffer of clifford_block holds the block
// parameters as doubles in the order w ((2 |S| d) x d), bias (d), wg (2d x d), bg (d), gamma (d).
std::vector<std::uint8_t> tensor_bytes(std::uint32_t n, std::uint32_t d, std::span<const double> values);
Result<std::pair<std::array<std::uint32_t, 2>, std::vector<double>>> parse_tensor_bytes(std::span<const std::uint8_t> b);

class Device {
 public:
  virtual ~Device() = default;
  // GPU resources
  virtual Result<BufferId> buffer_create(std::size_t size, BufferUsage usage) = 0;
  virtual Status buffer_write(BufferId id, std::span<const std::uint8_t> data, std::size_t offset) = 0;
  virtual Result<std::vector<std::uint8_t>> buffer_read(BufferId id, std::size_t offset, std::size_t size) = 0;
  // compute
  virtual Result<ShaderId> shader_compile(std::string_view source, ShaderStage stage) = 0;
  virtual Status compute_dispatch(ShaderId shader, std::span<const Binding> bindings, std::array<std::uint32_t, 3> groups) = 0;
  // raster
  virtual Result<PipelineId> pipeline_create(const PipelineShaders& shaders, const PipelineLayout& layout) = 0;
  virtual Status draw_indirect(PipelineId pipeline, std::span<const Binding> bindings, BufferId indirect, std::uint32_t count) = 0;
  // presentation: an offscreen surface (R1-BKD-068). surface_configure sets its size (1280 x 720
  // until it is called); draw_indirect draws into the surface last acquired, cleared first
  // (colours 0, depth 1); surface_read returns colour attachment k of a texture, width x height x
  // 4 32-bit words row-major.
  virtual Status surface_configure(std::uint32_t width, std::uint32_t height) = 0;
  virtual Result<TextureId> surface_acquire() = 0;
  virtual Status surface_present(TextureId texture) = 0;
  virtual Result<std::vector<std::uint32_t>> surface_read(TextureId texture, std::uint32_t attachment) = 0;
  // Clifford primitives (tensor buffers as above; each returns a new buffer)
  virtual Result<BufferId> roll(BufferId tensor, std::int32_t shift, std::uint32_t axis) = 0;
  virtual Result<BufferId> shifted_inner(BufferId h, BufferId c, std::span<const std::int32_t> shifts) = 0;
  virtual Result<BufferId> shifted_wedge(BufferId h, BufferId c, std::span<const std::int32_t> shifts) = 0;
  virtual Result<BufferId> clifford_block(BufferId h, BufferId c, std::span<const std::int32_t> shifts, BufferId gate) = 0;
  // determinism contract
  virtual bool deterministic_mode() const = 0;
  virtual Domain numeric_domain() const = 0;
  // The device in words (name and driver), for listings and test reports.
  virtual std::string describe() const { return "host memory"; }
};

// The host device (R1-BKD-013): buffers in host memory and the Clifford primitives of the
// cpu-reference (r1/reference/clifford.hpp); no shader compiler, raster or surface (those calls
// are errors saying so). What the reference adapter's trait would be, and the oracle a GPU
// device's Clifford kernels are tested against.
std::unique_ptr<Device> make_host_device();

// The Vulkan device (R1-BKD-060..063): buffers and compute on the first usable Vulkan 1.3 device
// (R1_VULKAN_DEVICE=N picks another), the Clifford primitives as compute shaders. Input error
// saying why when r1 was built without Vulkan or no usable device exists.
Result<std::unique_ptr<Device>> make_vulkan_device();

}  // namespace r1::backends
