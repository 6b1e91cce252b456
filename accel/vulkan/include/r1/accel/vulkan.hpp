// A Vulkan 1.3 compute context (spec/backends.md R1-BKD-060..063): one physical device, one
// compute queue, storage buffers in host-visible coherent memory, GLSL compiled to SPIR-V at run
// time with shaderc, and synchronous dispatches. What the vulkan device of the 13.1 trait
// (backends/adapters/vulkan_device.cpp) is built on. Includes spec/ only.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "r1/spec/epoch.hpp"
#include "r1/spec/status.hpp"
#include "r1/spec/vec3.hpp"

namespace r1::vk {

struct DeviceInfo {
  std::string name;         // VkPhysicalDeviceProperties::deviceName, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)"
  std::string driver;       // VkPhysicalDeviceDriverProperties::driverName, e.g. "llvmpipe"
  std::uint32_t api = 0;    // VkPhysicalDeviceProperties::apiVersion
  bool cpu = false;         // VK_PHYSICAL_DEVICE_TYPE_CPU (lavapipe)
  std::size_t max_buffer = 0;  // the largest storage buffer a shader may bind (maxStorageBufferRange)
  bool graphics = false;       // a graphics queue and dynamic rendering: the raster calls work
};

// Where a buffer's memory lives (R1-BKD-061). kHost: host-visible coherent memory, cached where
// the device offers it (the host writes and reads it; the default). kUpload: what the host writes
// and the device reads again and again (a frame's hierarchy, parameters): device-local memory the
// host can map where there is some, else kHost. kScratch: what only the device writes and reads
// (a pass's intermediate samples): device-local, not mapped unless that memory is host-visible
// anyway (lavapipe); buffer_write and buffer_read refuse an unmapped buffer. $R1_VULKAN_MEMORY=host
// makes every buffer kHost. On a CPU device every kind is the same memory.
enum class Residence { kHost, kUpload, kScratch };

struct Slot {
  std::uint32_t binding = 0;  // layout(set = 0, binding = N) in the shader, N < kSlots
  std::uint32_t buffer = 0;
};

class Context {
 public:
  // Storage-buffer bindings every compute pipeline's layout has (set 0, bindings 0..kSlots-1), and
  // the push-constant bytes it may read.
  static constexpr std::uint32_t kSlots = 12;
  static constexpr std::uint32_t kPushBytes = 128;

  // The first device with a compute queue, 64-bit floats and integers in shaders and Vulkan 1.3
  // (discrete GPUs before integrated, virtual and CPU ones; R1_VULKAN_DEVICE=N picks the N-th).
  // Input error saying why when there is none (no loader, no driver, no such device).
  static Result<std::unique_ptr<Context>> create();
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  const DeviceInfo& info() const;

  Result<std::uint32_t> buffer_create(std::size_t bytes, Residence where = Residence::kHost);
  std::size_t buffer_size(std::uint32_t id) const;  // 0 for no such buffer
  // Frees the buffer's memory; its id then names no buffer (a no-op for an id that names none).
  void buffer_release(std::uint32_t id);
  // Makes `id` name a buffer of at least `bytes` (a quarter more when it grows, within the
  // storage range) with the residence asked for: kept when it is big enough and was asked for with
  // the same residence, else released and replaced. 0 names none yet.
  Status buffer_ensure(std::uint32_t& id, std::size_t bytes, Residence where = Residence::kHost);
  Status buffer_write(std::uint32_t id, std::span<const std::uint8_t> data, std::size_t offset);
  Result<std::vector<std::uint8_t>> buffer_read(std::uint32_t id, std::size_t offset, std::size_t size);

  // Whether GLSL 4.60 source compiles as a vertex (`vertex`) or fragment shader: the error says why.
  Status graphics_check(std::string_view glsl, bool vertex, std::string_view name);
  // GLSL 4.60 compute source to a pipeline; `name` names it in compiler messages.
  Result<std::uint32_t> compute_compile(std::string_view glsl, std::string_view name);
  // One dispatch of `groups` workgroups, waited for; `push` at most kPushBytes.
  Status dispatch(std::uint32_t pipeline, std::span<const Slot> slots, std::array<std::uint32_t, 3> groups,
                  std::span<const std::uint8_t> push = {});

  // ---- raster (spec/backends.md R1-BKD-068), where info().graphics ----
  // A render target: kTargetColors colour attachments of four 32-bit unsigned integers a pixel,
  // and a 32-bit float depth attachment, in device memory.
  static constexpr std::uint32_t kTargetColors = 3;
  using Clear = std::array<std::array<std::uint32_t, 4>, kTargetColors>;
  Result<std::uint32_t> target_create(std::uint32_t width, std::uint32_t height);
  // A graphics pipeline from vertex and fragment GLSL 4.60: no vertex input (the vertex shader
  // reads storage buffers by gl_VertexIndex and gl_InstanceIndex), triangle lists, no face
  // culling, depth test `less` with writes, kTargetColors uvec4 outputs; the slots and push
  // constants of the compute pipelines.
  Result<std::uint32_t> graphics_compile(std::string_view vertex, std::string_view fragment, std::string_view name);
  // Clears the target's colours to `clear` and depth to 1, then draws `draws` indirect records
  // (VkDrawIndirectCommand, 16 bytes each) from buffer `indirect`, and waits. Primitives are
  // rasterised in order, so of two fragments at equal depth the earlier is kept.
  Status draw_indirect(std::uint32_t pipeline, std::uint32_t target, std::span<const Slot> slots, std::uint32_t indirect,
                       std::uint32_t draws, const Clear& clear, std::span<const std::uint8_t> push = {});
  // Colour attachment `index` of the target: width x height x 4 words, row-major.
  Result<std::vector<std::uint32_t>> target_read(std::uint32_t target, std::uint32_t index);
  // Frees the target's images and read-back buffers; its id then names no target.
  void target_release(std::uint32_t target);

 private:
  struct State;
  explicit Context(std::unique_ptr<State> s);
  std::unique_ptr<State> s_;
};

// det_exp's constants (the reference's: spec/render.md R1-RND-101): log2 e, ln 2 split high and
// low, and the Taylor coefficients 1/n!, n = 0..13.
struct ExpConstants {
  double log2e = 0, ln2_hi = 0, ln2_lo = 0;
  std::vector<double> taylor;
};

// The Clifford primitives of the 13.1 trait as compute shaders (R1-BKD-062) on tensor
// buffers of the trait's format (u32 n, u32 d, then n x d doubles, R1-BKD-013): the reference's
// evaluation order in fp64 with every expression `precise` (no contraction into fma). Each returns
// a new buffer; shapes are checked with the reference's messages.
class CliffordKernels {
 public:
  static Result<CliffordKernels> build(Context& ctx, const ExpConstants& constants);
  Result<std::uint32_t> roll(std::uint32_t tensor, std::int32_t shift, std::uint32_t axis);
  Result<std::uint32_t> shifted_inner(std::uint32_t h, std::uint32_t c, std::span<const std::int32_t> shifts);
  Result<std::uint32_t> shifted_wedge(std::uint32_t h, std::uint32_t c, std::span<const std::int32_t> shifts);
  // The block of R1-RND-105: `gate` holds w, bias, wg, bg and gamma as doubles, in that order.
  Result<std::uint32_t> block(std::uint32_t h, std::uint32_t c, std::span<const std::int32_t> shifts, std::uint32_t gate);

 private:
  struct Shape;
  Result<Shape> shape_of(std::uint32_t tensor, const char* what);
  Result<std::uint32_t> tensor(std::uint32_t n, std::uint32_t d);
  Result<std::uint32_t> shifted(std::uint32_t h, std::uint32_t c, std::span<const std::int32_t> shifts, bool inner,
                                std::uint32_t width_factor);
  Context* ctx_ = nullptr;
  std::uint32_t constants_ = 0, roll_ = 0, shifted_ = 0, linear_ = 0, residual_ = 0;
};

// llvmpipe (lavapipe) stops an invocation's loop nest after 65,535 iterations, and its results
// are then silently wrong (R1-BKD-073). Kernels that loop over a matrix row take rows of at most
// kLongestRow entries; a matrix with a longer row is left to the host, on every device, so the
// bits never depend on the device.
inline constexpr std::uint64_t kLongestRow = 65000;
inline bool rows_fit_the_loop_limit(std::span<const std::uint64_t> row_ptr) {
  for (std::size_t i = 0; i + 1 < row_ptr.size(); ++i)
    if (row_ptr[i + 1] - row_ptr[i] > kLongestRow) return false;
  return true;
}

// The exact Q32 sparse product (R1-BKD-064): y_i = RNE(sum_k val_k x_(col_k) / 2^32), the row sum
// exact in 128 bits (two 64-bit limbs in the shader) and rounded once, ties to even, as the host's
// i128 arithmetic and fx::detail::rne_shift give it: the walk and operator products of the focus
// and spectral stages. With `empty_rows_identity` an empty row returns x_i (an isolated
// particle's walk, R1-FOC-041). The matrix is uploaded once; each apply uploads x. Sums must stay
// within 128 bits, as on the host; a row that rounds outside int64 is an internal error naming it.
class ExactSpmv {
 public:
  static Result<ExactSpmv> build(Context& ctx, std::span<const std::uint64_t> row_ptr, std::span<const std::uint32_t> col,
                                 std::span<const std::int64_t> val, bool empty_rows_identity);
  Result<std::vector<std::int64_t>> apply(std::span<const std::int64_t> x);
  std::uint32_t rows() const { return rows_; }
  std::uint32_t columns() const { return columns_; }

  // Owns its buffers: released with it (the context must outlive it).
  ExactSpmv() = default;
  ExactSpmv(ExactSpmv&& o) noexcept { *this = std::move(o); }
  ExactSpmv& operator=(ExactSpmv&& o) noexcept;
  ExactSpmv(const ExactSpmv&) = delete;
  ExactSpmv& operator=(const ExactSpmv&) = delete;
  ~ExactSpmv();

 private:
  Context* ctx_ = nullptr;
  std::uint32_t rows_ = 0, columns_ = 0;
  bool identity_ = false;
  std::uint32_t pipeline_ = 0, row_ptr_ = 0, col_ = 0, val_ = 0, x_ = 0, y_ = 0, flag_ = 0;
};

// The splats' depth sort (R1-BKD-072, R1-RND-079): a stable least-significant-digit radix sort of
// 64-bit keys, eight bits a pass, on the device. order(depth) returns the permutation that puts
// positive finite depths in ascending order, equal depths in index order (their bit patterns
// order as the values do). Passes over a byte every key shares are skipped (a stable pass over a
// constant digit moves nothing). More than kMaxKeys depths: an input error.
class DepthSort {
 public:
  // Keys one call sorts at most (2^23): no shader loop then passes lavapipe's 65535 iterations.
  static constexpr std::size_t kMaxKeys = std::size_t{1} << 23;
  static Result<DepthSort> build(Context& ctx);
  Result<std::vector<std::uint32_t>> order(std::span<const double> depth);

  DepthSort() = default;
  DepthSort(DepthSort&& o) noexcept { *this = std::move(o); }
  DepthSort& operator=(DepthSort&& o) noexcept;
  DepthSort(const DepthSort&) = delete;
  DepthSort& operator=(const DepthSort&) = delete;
  ~DepthSort();

 private:
  Context* ctx_ = nullptr;
  std::uint32_t histogram_ = 0, scan_digits_ = 0, scan_bases_ = 0, scatter_ = 0;
  std::array<std::uint32_t, 6> buffers_{};  // keys and indices (two of each), the counts, the digit totals
};

// The frame's cull on the device (R1-BKD-074; the reference's cull_frame, R1-RND-025, whose walk
// it reproduces). The scene, flattened by the host:
struct CullScene {
  // Names the scene (render::Scene::serial): a run with the serial of the scene the pass holds
  // keeps it on the device and reads nothing below; 0 uploads every time.
  std::uint64_t serial = 0;
  // Per level (0 finest .. kLevels - 1), 8 doubles a node: the box's lo and hi, the largest member
  // radius, 0; and each node's parent (an id at the next level; not read at the top level).
  std::array<std::span<const double>, kLevels> node;
  std::array<std::span<const std::uint32_t>, kLevels> parent;
  std::span<const double> position;   // 3 doubles a particle
  std::span<const double> radius;
  std::span<const std::uint32_t> leaf;  // the level-0 node holding each particle (0xffffffff: none)
  // What the impostor draw fed by the cull reads (ImpostorPass::draw_culled): colour (3 doubles a
  // particle) and shape; may be empty when no such draw follows.
  std::span<const double> color;
  std::span<const Shape> shape;
};
// The frame's view as the cull reads it: the frustum's five inward planes (a point x is inside
// plane k when dot(normal[k], x) + offset[k] >= 0), the camera, the near plane and the tiers.
struct CullView {
  std::array<render::Vec3, 5> normal;
  std::array<double, 5> offset{};
  render::Vec3 position, forward;
  double focal_px = 0, near = 0;
  double t0 = 0, t1 = 0, t2 = 0, t3 = 0, band = 0;
};
// VkDrawIndirectCommand.
struct DrawArgs {
  std::uint32_t vertex_count = 0, instance_count = 0, first_vertex = 0, first_instance = 0;
};
struct CullOutput {
  static constexpr std::uint8_t kUntested = 0, kOpen = 1, kCulled = 2, kFar = 3;
  std::array<std::vector<std::uint8_t>, kLevels> state;  // per node: what the walk did with it
  // The visible particles of the open level-0 nodes, ascending, with view depth, screen diameter
  // and tier (0 = T0 .. 4 = T-infinity).
  std::vector<std::uint32_t> particle;
  std::vector<double> depth, size;
  std::vector<std::uint8_t> tier;
  // One indirect draw per tier: a quad (6 vertices) an instance, instance_count the tier's visible
  // particles, first_instance where its list starts in the tier lists (read back when asked).
  std::array<DrawArgs, 5> args;
  std::vector<std::uint32_t> tier_lists;
};
// Per frame: a dispatch per level decides each node from its parent's decision (tested when the
// parent is open or it is a top node; culled, far or open by the reference's box tests with their
// slack); one invocation a particle tests and classifies the particles of open level-0 nodes; then
// per 256 particles counts, a scan over the blocks and a scatter in particle order write the
// visible list and the per-tier lists, and one invocation the five indirect-draw records. fp64,
// every expression `precise`, in the reference's order of operations.
class CullPass {
 public:
  // Particles one call takes at most: the scan then loops over at most 16,384 blocks (lavapipe's
  // loop limit, R1-BKD-073); their geometry (64 bytes each) must also fit the storage range.
  static constexpr std::size_t kMaxParticles = std::size_t{1} << 22;
  static Result<CullPass> build(Context& ctx);
  // Whether a scene of this many particles and nodes (all levels) is within kMaxParticles and the
  // device's storage range; run refuses one that is not.
  bool fits(std::size_t particles, std::size_t nodes) const;
  // Input error: more than kMaxParticles, inconsistent sizes, or a buffer past the device's range.
  Result<CullOutput> run(const CullScene& scene, const CullView& view, bool read_tier_lists = false);
  // The buffers the last run left on the device: the indirect-draw records, the tier lists, and
  // the scene's particles as the impostor draw reads them (8 doubles each: centre, radius,
  // colour, 0; 8 ints each: 0, 0, 0, 0, particle, shape, 0, 0), with the records read back.
  std::uint32_t args_buffer() const { return buffers_[kArgs]; }
  std::uint32_t tier_list_buffer() const { return buffers_[kLists]; }
  std::uint32_t geometry_buffer() const { return buffers_[kGeometry]; }
  std::uint32_t meta_buffer() const { return buffers_[kMeta]; }
  const std::array<DrawArgs, 5>& last_args() const { return last_args_; }
  std::uint64_t serial() const { return serial_; }  // the scene held (0: none)
  bool holds_impostors() const { return impostors_; }  // the scene came with colours and shapes

  CullPass() = default;
  CullPass(CullPass&& o) noexcept { *this = std::move(o); }
  CullPass& operator=(CullPass&& o) noexcept;
  CullPass(const CullPass&) = delete;
  CullPass& operator=(const CullPass&) = delete;
  ~CullPass();

 private:
  enum : std::size_t { kNodes, kParents, kState, kGeometry, kMeta, kLeaf, kCode, kParams, kCounts, kArgs, kLists, kOut, kBuffers };
  Context* ctx_ = nullptr;
  std::uint32_t nodes_ = 0, mark_ = 0, count_ = 0, scan_ = 0, args_ = 0, scatter_ = 0;
  std::array<std::uint32_t, kBuffers> buffers_{};
  // The scene on the device: its serial, particles and level offsets.
  std::uint64_t serial_ = 0;
  std::size_t n_ = 0;
  std::array<std::uint32_t, kLevels + 1> offset_{};
  bool impostors_ = false;
  std::array<DrawArgs, 5> last_args_{};
};

// The pinhole camera of a frame as the impostor pass needs it (render::CameraFrame and the image
// size): the ray through pixel centre (x + 0.5, y + 0.5) has direction
// normalize(forward + right sx + up sy), sx = (x + 0.5 - width / 2) / focal_px,
// sy = (height / 2 - y - 0.5) / focal_px.
struct ImpostorCamera {
  render::Vec3 position, right, up, forward;
  double focal_px = 0;
  std::uint32_t width = 0, height = 0;
};

// One analytic impostor: the particle, its shape, centre, bounding radius, albedo and the pixel
// rectangle [x0, x1) x [y0, y1) outside which it is not drawn.
struct ImpostorItem {
  std::uint32_t particle = 0;
  Shape shape = Shape::kSphere;
  render::Vec3 center;
  double radius = 0;
  render::Vec3 color;
  std::int32_t x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

// The T1/T2 impostor pass (R1-BKD-065, R1-BKD-068): per pixel, the nearest hit of the pixel's
// ray with the items whose rectangle holds the pixel (ties to the earlier item), shaded by the
// headlight 0.25 + 0.75 max(0, -n.d); t is infinity and owner -1 where nothing is hit. The
// reference's fp64 intersections (reference/render/shapes.cpp) operation for operation.
//  - kCompute: one compute invocation a pixel over the items binned into 16-pixel tiles; the
//    nearest hit compared in fp64, as the reference does.
//  - kRaster: one indirect draw of a quad per item (its rectangle) through a graphics pipeline,
//    the ray cast in the fragment shader, the nearest kept by a 32-bit float depth test on t: two
//    hits whose t round to the same float keep the earlier item, where the reference keeps the
//    nearer.
class ImpostorPass {
 public:
  enum class Mode { kCompute, kRaster };
  static Result<ImpostorPass> build(Context& ctx, Mode mode = Mode::kCompute);
  Status draw(const ImpostorCamera& camera, std::span<const ImpostorItem> items, std::span<double> t,
              std::span<render::Vec3> color, std::span<std::int64_t> owner);
  Mode mode() const { return mode_; }
  // The raster pass fed by the cull (R1-BKD-077): three indirect draws, the cull's T0, T1 and T2
  // records over its tier lists and the scene's particles it holds, each quad its particle's
  // bounding-cube rectangle found in the vertex shader. `far` bounds the ray parameter of every
  // hit (the depth scale). For frames with no T0 particle that opens into content (R1-RND-130),
  // whose impostor list is then the cull's T0..T2 particles with a non-empty rectangle.
  Status draw_culled(const ImpostorCamera& camera, const CullPass& cull, double far, std::span<double> t,
                     std::span<render::Vec3> color, std::span<std::int64_t> owner);

 private:
  Status raster(std::uint32_t pipeline, std::span<const Slot> slots, std::uint32_t indirect, std::uint32_t draws, double far,
                const ImpostorCamera& cam, std::span<double> t, std::span<render::Vec3> color, std::span<std::int64_t> owner);
  static constexpr std::uint32_t kNoTarget = 0xffffffffu;
  Status reserve(std::size_t which, std::size_t bytes);
  Status upload(std::size_t which, std::span<const std::uint8_t> bytes);
  Status draw_compute(const ImpostorCamera& camera, std::span<const ImpostorItem> items, std::span<double> t,
                      std::span<render::Vec3> color, std::span<std::int64_t> owner);
  Status draw_raster(const ImpostorCamera& camera, std::span<const ImpostorItem> items, std::span<double> t,
                     std::span<render::Vec3> color, std::span<std::int64_t> owner);
  Context* ctx_ = nullptr;
  Mode mode_ = Mode::kCompute;
  std::uint32_t pipeline_ = 0, culled_pipeline_ = 0;
  std::array<std::uint32_t, 8> buffers_{};
  std::uint32_t target_ = kNoTarget;
  std::array<std::uint32_t, 2> target_size_{};
};

// The frame's edge tubes flattened for the device (R1-BKD-075; the host makes them with the
// reference's edge_tubes): per tube 16 doubles (a, b, rho, stripes, speed, colour at a, colour at
// b, 0) and 4 words (its first row, its rows, where its spans start, 0); per row from the first
// the span [x0, x1) (x0 >= x1: none in that row). `time` drives the flow strip.
struct EdgeData {
  std::vector<double> tubes;
  std::vector<std::uint32_t> rows;
  std::vector<std::int32_t> spans;
  double time = 0;
};

// The edge pass (R1-BKD-075): over the opaque layer the impostors left, per pixel the tubes
// binned into its 16-pixel tile, in tube order, each whose row span holds the pixel: the
// reference's open-wall intersection in fp64 (every expression `precise`), a hit nearer than the
// layer's t taking it with owner -2 and the headlight-shaded strip colour. The strip's cosine is
// the device's own (det_cos: a Cody-Waite reduction by pi/2 and Taylor series to degree 19),
// within a few ulps of the host's libm.
class EdgePass {
 public:
  // A tile list longer than this stays below lavapipe's loop limit (R1-BKD-073) only on the host:
  // draw then declines.
  static constexpr std::size_t kMaxTileTubes = 65000;
  static Result<EdgePass> build(Context& ctx);
  // Draws the tubes over the layer (t, colour, owner; width x height) in place: true when drawn,
  // false when declined (a tile of more than kMaxTileTubes tubes), the layer then untouched.
  Result<bool> draw(const ImpostorCamera& camera, const EdgeData& edges, std::span<double> t, std::span<render::Vec3> color,
                    std::span<std::int64_t> owner);

  EdgePass() = default;
  EdgePass(EdgePass&& o) noexcept { *this = std::move(o); }
  EdgePass& operator=(EdgePass&& o) noexcept;
  EdgePass(const EdgePass&) = delete;
  EdgePass& operator=(const EdgePass&) = delete;
  ~EdgePass();

 private:
  Context* ctx_ = nullptr;
  std::uint32_t pipeline_ = 0;
  std::array<std::uint32_t, 8> buffers_{};
};

// A trained neural field (R1-NRF-001..006) as the device's inference reads it (R1-BKD-076): the
// architecture, the cube and tau range, and every parameter in one float array: the hash grid
// (levels x 2^log2_table x 2), then w1, b1, w2, b2, w3, b3 (row-major, as NeuralField holds them),
// then with the Clifford render block (R1-NRF-003) its wc, bc, wg, bg, gamma.
struct NeuralData {
  std::uint32_t levels = 0, log2_table = 0, hidden = 0;
  std::uint32_t block = 0;                 // the Clifford block's width d (0: none; else hidden = 2 d)
  std::vector<std::uint32_t> resolution;  // cells per side, per level
  render::Vec3 lo, centroid;
  double size = 1, tau_lo = 1, tau_hi = 1, kappa = 0;
  double log2_range = 0;                   // log2(tau_hi / tau_lo), the host's
  // The Gaussian prior's parts (R1-NRF-007, 008), 17 doubles each: mass, spread s^2, centroid (3),
  // mean colour (3), colour gradient (9); none: no prior.
  std::vector<double> prior;
  std::uint32_t fade_power = 4;            // the fine levels' fade exponent (R1-NRF-002): 4 or 2
  std::vector<float> params;
  std::uint32_t inputs() const { return levels * 2 + 1; }
};

// The T-infinity field of one frame, flattened (R1-BKD-070; the host builds it from the
// reference's FieldFrame). Nodes of every level in one table, level l's node id at global index
// level_offset[l] + id.
inline constexpr std::size_t kFieldNodeDoubles = 24;
struct FieldData {
  // kFieldNodeDoubles a node: weight (0: not in the field), centroid, colour, extent, the colour
  // spread's gradient (9, row-major: row a channel, column an axis), its colour's low end (3) and
  // high end (3), 0 (R1-RND-055).
  std::vector<double> nodes;
  std::array<std::uint32_t, kLevels + 1> level_offset{};
  std::vector<std::uint32_t> child_ptr, child;  // per node of levels 1 and up (global index - level_offset[1]): children, global indices
  std::vector<std::uint32_t> next, parent;      // per node: its next sibling and its parent (0xffffffff: none)
  std::vector<std::uint32_t> member_ptr;        // per level-0 node: its members in `members`
  std::vector<double> members;                  // 8 doubles a member: weight, position, colour, 0
  std::vector<std::uint32_t> top_ptr, top;      // per 16-pixel tile: the top-level node ids a ray may meet
  std::uint32_t tiles_x = 0, samples = 128;
  double tau_cam = 0, t_far = 0, kappa = 0, cutoff = 0, theta = 0, stop = 0;
  std::uint64_t seed = 0;  // the jitter's counter-based seed (the scene's)
  bool enabled = true;     // the view draws the field
  // The frame is drawn with this neural field (R1-NRF-031: a pure T-infinity frame) when set.
  const NeuralData* neural = nullptr;
};

// The T3 splats of one frame in depth order, binned into 16-pixel tiles.
struct SplatData {
  std::vector<double> splats;  // 12 doubles a splat: depth, px, py, ca, cb, cc, opacity, colour, 0, 0
  std::vector<std::uint32_t> tile_ptr, tile;
};

// The field and composite pass (R1-BKD-070): per pixel the reference's T-infinity march and its
// front-to-back composite with the splats and the opaque layer (4 doubles a pixel: t, colour),
// into RGBA (4 floats a pixel) and flow (3 floats a pixel, left empty when every pixel's is 0).
// A ray that meets more candidate nodes than the shader holds (max_candidates) is left to the
// host, its index listed in host_pixels and its RGBA not written; with the neural field such a
// ray stays on the device and walks the hierarchy again at each sample (rewalked()). The walk
// needs no stack (next-sibling and parent links).
class CompositePass {
 public:
  // 64: with 160, lavapipe (Mesa 22.3) returned wrong samples for rays holding more than about 64
  // candidates (BA 10^6, 1080p: 177 pixels off); with 64 every pixel of that frame is the
  // reference's within 1e-6.
  static constexpr std::uint32_t kMaxCandidates = 64;
  static Result<CompositePass> build(Context& ctx, const ExpConstants& constants, std::uint32_t max_candidates = kMaxCandidates);
  // Whether a neural field of this architecture is inferred on the device (R1-BKD-076): its
  // loops stay below lavapipe's limit (R1-BKD-073) and its layers fit the shader's arrays.
  static bool infers(const NeuralData& n);
  // The samples the last draw inferred the neural field at: every sample a candidate reaches,
  // also those past the march's early end, which the host never evaluates.
  std::uint64_t inferred() const { return inferred_; }
  // The rays of the last draw past the candidate cap that the neural field walked again per sample.
  std::uint64_t rewalked() const { return rewalked_; }
  // The network's raw outputs (7 floats each) at `queries` (x, y, z, sigma each): the inference
  // pass alone, as the frame runs it.
  Result<std::vector<float>> infer(const NeuralData& n, std::span<const double> queries);
  Status draw(const ImpostorCamera& camera, const FieldData& field, const SplatData& splats, std::span<const double> opaque,
              std::span<float> rgba, std::vector<float>& flow, std::vector<std::uint32_t>& host_pixels);

 private:
  Context* ctx_ = nullptr;
  ExpConstants exp_;
  // Checks the field, uploads its parameters (buffers 11..13) and returns the inference pass's
  // push constants (the pixel count left 0).
  Result<std::array<std::uint32_t, 18>> upload_neural(const NeuralData& n, std::uint32_t slots);
  std::uint32_t pipeline_ = 0, infer_ = 0;
  std::array<std::uint32_t, 14> buffers_{};
  std::uint64_t inferred_ = 0, rewalked_ = 0;
};

}  // namespace r1::vk
