// The frame's cull on a Vulkan device (R1-BKD-074): the reference's hierarchy walk (cull_frame,
// R1-RND-025) as one dispatch per level, top down, each node deciding from its parent's decision;
// then the particles of the open level-0 nodes tested and classified one invocation each, and the
// visible ones compacted in particle order by per-block counts, a scan and an in-order scatter,
// which also writes the per-tier particle lists and one indirect-draw record per tier.
#include <algorithm>
#include <cstring>
#include <string>
#include <utility>

#include "r1/accel/vulkan.hpp"
#include "shader_common.hpp"

namespace r1::vk {

namespace {

constexpr std::uint32_t kBlock = 256;      // particles a count and scatter invocation walks
constexpr std::uint32_t kColumns = 6;      // counted per block: every visible particle, then each tier's
constexpr std::uint32_t kNone = 0xffffffffu;

// The box and sphere tests of reference/render/cull.cpp, in its order of operations. prm holds
// the frustum's planes (4 doubles each: normal, offset), the camera position and forward axis,
// focal_px, the near plane, t0..t3 and the band, the slack coefficient, 1 + 1e-9 and the size of
// a sphere reaching the near plane.
constexpr const char* kPrelude = R"(#version 460
layout(local_size_x = 64) in;
layout(push_constant) uniform P { uint n; uint count; uint offset; uint parent_offset; uint top; uint blocks; } p;
layout(std430, binding = 7) readonly buffer Params { double prm[]; };

uint invocation() { return gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 64u; }
double dot3(dvec3 a, dvec3 b) { precise double r = a.x * b.x + a.y * b.y + a.z * b.z; return r; }
double l1(dvec3 a) { precise double r = abs(a.x) + abs(a.y) + abs(a.z); return r; }
dvec3 plane_normal(uint k) { return dvec3(prm[4u * k], prm[4u * k + 1u], prm[4u * k + 2u]); }
double plane_offset(uint k) { return prm[4u * k + 3u]; }
dvec3 camera() { return dvec3(prm[20], prm[21], prm[22]); }
dvec3 forward() { return dvec3(prm[23], prm[24], prm[25]); }
double near_plane() { return prm[27]; }
double slack_of(double m) { precise double r = prm[33] * (1.0lf + m); return r; }
double screen_diameter(double r, double depth) { precise double s = 2.0lf * r * prm[26] / depth; return s; }

bool sphere_visible(dvec3 c, double r) {
  for (uint k = 0u; k < 5u; ++k) {
    precise double d = dot3(plane_normal(k), c) + plane_offset(k);
    if (d < -r) return false;
  }
  return true;
}

// The view depth and screen diameter of a particle, and its tier (0 = T0 .. 4 = T-infinity).
uint classify(dvec3 c, double r, out double depth, out double s) {
  precise dvec3 rel = c - camera();
  depth = dot3(rel, forward());
  precise double reach = r + near_plane();
  s = depth > reach ? screen_diameter(r, depth) : prm[35];
  if (s > prm[28]) return 0u;
  if (s > prm[29]) return 1u;
  if (s > prm[30]) return 2u;
  if (s > prm[31]) return 3u;
  return 4u;
}
)";

// One invocation a node of the level: untested under a parent that is not open, else culled, far
// or open by box_outside, box_inside and far_class.
constexpr const char* kNodeShader = R"(
layout(std430, binding = 0) readonly buffer N { double node[]; };
layout(std430, binding = 1) readonly buffer Q { uint parent[]; };
layout(std430, binding = 2) buffer S { uint state[]; };

bool box_outside(dvec3 lo, dvec3 hi, double g) {
  for (uint k = 0u; k < 5u; ++k) {
    dvec3 nrm = plane_normal(k);
    double off = plane_offset(k);
    dvec3 far = dvec3(nrm.x >= 0.0lf ? hi.x : lo.x, nrm.y >= 0.0lf ? hi.y : lo.y, nrm.z >= 0.0lf ? hi.z : lo.z);
    precise double d = dot3(nrm, far) + off;
    precise double m = abs(off) + l1(far);
    precise double bound = -g - slack_of(m);
    if (d < bound) return true;
  }
  return false;
}

bool box_inside(dvec3 lo, dvec3 hi) {
  for (uint k = 0u; k < 5u; ++k) {
    dvec3 nrm = plane_normal(k);
    double off = plane_offset(k);
    dvec3 near = dvec3(nrm.x >= 0.0lf ? lo.x : hi.x, nrm.y >= 0.0lf ? lo.y : hi.y, nrm.z >= 0.0lf ? lo.z : hi.z);
    precise double d = dot3(nrm, near) + off;
    precise double m = abs(off) + l1(near);
    if (d < slack_of(m)) return false;
  }
  return true;
}

bool far_node(dvec3 lo, dvec3 hi, double max_radius) {
  dvec3 fw = forward(), o = camera();
  dvec3 near = dvec3(fw.x >= 0.0lf ? lo.x : hi.x, fw.y >= 0.0lf ? lo.y : hi.y, fw.z >= 0.0lf ? lo.z : hi.z);
  dvec3 far = dvec3(fw.x >= 0.0lf ? hi.x : lo.x, fw.y >= 0.0lf ? hi.y : lo.y, fw.z >= 0.0lf ? hi.z : lo.z);
  precise double m = l1(lo) + l1(hi) + l1(o);
  double slack = slack_of(m);
  precise dvec3 nr = near - o;
  precise dvec3 fr = far - o;
  precise double depth_min = dot3(nr, fw) - slack;
  precise double depth_max = dot3(fr, fw) + slack;
  if (depth_max <= near_plane()) return false;  // behind: not far
  precise double reach = max_radius + near_plane();
  if (!(depth_min > reach)) return false;
  precise double s_max = screen_diameter(max_radius, depth_min) * prm[34];
  precise double limit = prm[31] - prm[32];
  return s_max <= limit;
}

void main() {
  uint i = invocation();
  if (i >= p.count) return;
  uint g = p.offset + i;
  if (p.top == 0u && state[parent[g]] != 1u) {
    state[g] = 0u;
    return;
  }
  uint b = g * 8u;
  dvec3 lo = dvec3(node[b], node[b + 1u], node[b + 2u]), hi = dvec3(node[b + 3u], node[b + 4u], node[b + 5u]);
  double r = node[b + 6u];
  if (box_outside(lo, hi, r)) state[g] = 2u;
  else if (box_inside(lo, hi) && far_node(lo, hi, r)) state[g] = 3u;
  else state[g] = 1u;
}
)";

// One invocation a particle: 0 untested (its leaf is not open), 1 tested and not visible, 2 + tier.
constexpr const char* kMark = R"(
layout(std430, binding = 2) readonly buffer S { uint state[]; };
layout(std430, binding = 3) readonly buffer X { double geo[]; };
layout(std430, binding = 5) readonly buffer L { uint leaf[]; };
layout(std430, binding = 6) writeonly buffer C { uint code[]; };
void main() {
  uint q = invocation();
  if (q >= p.n) return;
  uint lf = leaf[q];
  uint c = 0u;
  if (lf != 0xffffffffu && state[lf] == 1u) {
    dvec3 x = dvec3(geo[8u * q], geo[8u * q + 1u], geo[8u * q + 2u]);
    double r = geo[8u * q + 3u];
    c = 1u;
    if (sphere_visible(x, r)) {
      double depth, s;
      c = 2u + classify(x, r, depth, s);
    }
  }
  code[q] = c;
}
)";

// Per block of 256 particles: its visible particles, then each tier's.
constexpr const char* kCount = R"(
layout(std430, binding = 1) writeonly buffer K { uint counts[]; };
layout(std430, binding = 6) readonly buffer C { uint code[]; };
void main() {
  uint b = invocation();
  if (b >= p.blocks) return;
  uint c[6] = uint[6](0u, 0u, 0u, 0u, 0u, 0u);
  uint lo = b * 256u, hi = min(p.n, lo + 256u);
  for (uint e = lo; e < hi; ++e) {
    uint k = code[e];
    if (k >= 2u) {
      c[0] += 1u;
      c[k - 1u] += 1u;
    }
  }
  for (uint j = 0u; j < 6u; ++j) counts[j * p.blocks + b] = c[j];
}
)";

// One invocation a column: the exclusive scan over the blocks, the column's total after them.
constexpr const char* kScan = R"(
layout(std430, binding = 1) buffer K { uint counts[]; };
void main() {
  uint j = invocation();
  if (j >= 6u) return;
  uint sum = 0u, base = j * p.blocks;
  for (uint b = 0u; b < p.blocks; ++b) {
    uint c = counts[base + b];
    counts[base + b] = sum;
    sum += c;
  }
  counts[6u * p.blocks + j] = sum;
}
)";

// One invocation: the indirect-draw record of each tier, its list after the lists of the tiers
// before it.
constexpr const char* kArgsShader = R"(
layout(std430, binding = 1) readonly buffer K { uint counts[]; };
layout(std430, binding = 2) writeonly buffer A { uint args[]; };
void main() {
  if (invocation() != 0u) return;
  uint base = 0u;
  for (uint t = 0u; t < 5u; ++t) {
    uint c = counts[6u * p.blocks + 1u + t];
    args[4u * t] = 6u;
    args[4u * t + 1u] = c;
    args[4u * t + 2u] = 0u;
    args[4u * t + 3u] = base;
    base += c;
  }
}
)";

// Per block, in particle order: the visible list (8 words a particle: index, tier, depth and
// size as two words each, 0, 0) and each tier's list.
constexpr const char* kScatter = R"(
layout(std430, binding = 0) writeonly buffer O { uint rec[]; };
layout(std430, binding = 1) readonly buffer K { uint counts[]; };
layout(std430, binding = 2) readonly buffer A { uint args[]; };
layout(std430, binding = 3) readonly buffer X { double geo[]; };
layout(std430, binding = 5) writeonly buffer T { uint lists[]; };
layout(std430, binding = 6) readonly buffer C { uint code[]; };
void main() {
  uint b = invocation();
  if (b >= p.blocks) return;
  uint next = counts[b];
  uint tnext[5];
  for (uint t = 0u; t < 5u; ++t) tnext[t] = args[4u * t + 3u] + counts[(1u + t) * p.blocks + b];
  uint lo = b * 256u, hi = min(p.n, lo + 256u);
  for (uint e = lo; e < hi; ++e) {
    uint k = code[e];
    if (k < 2u) continue;
    double depth, s;
    uint t = classify(dvec3(geo[8u * e], geo[8u * e + 1u], geo[8u * e + 2u]), geo[8u * e + 3u], depth, s);
    uvec2 dw = unpackDouble2x32(depth), sw = unpackDouble2x32(s);
    uint o = next * 8u;
    rec[o] = e;
    rec[o + 1u] = t;
    rec[o + 2u] = dw.x;
    rec[o + 3u] = dw.y;
    rec[o + 4u] = sw.x;
    rec[o + 5u] = sw.y;
    rec[o + 6u] = 0u;
    rec[o + 7u] = 0u;
    next += 1u;
    lists[tnext[t]] = e;
    tnext[t] += 1u;
  }
}
)";

std::string source(const char* body) { return std::string(kPrelude) + body; }

struct Push {
  std::uint32_t n = 0, count = 0, offset = 0, parent_offset = 0, top = 0, blocks = 0;
};

std::span<const std::uint8_t> push_bytes(const Push& p) { return {reinterpret_cast<const std::uint8_t*>(&p), sizeof p}; }

}  // namespace

CullPass& CullPass::operator=(CullPass&& o) noexcept {
  if (this == &o) return *this;
  this->~CullPass();
  ctx_ = std::exchange(o.ctx_, nullptr);
  nodes_ = o.nodes_, mark_ = o.mark_, count_ = o.count_, scan_ = o.scan_, args_ = o.args_, scatter_ = o.scatter_;
  buffers_ = std::exchange(o.buffers_, {});
  return *this;
}

CullPass::~CullPass() {
  if (ctx_ == nullptr) return;
  for (const std::uint32_t id : buffers_) ctx_->buffer_release(id);
  ctx_ = nullptr;
}

Result<CullPass> CullPass::build(Context& ctx) {
  CullPass c;
  c.ctx_ = &ctx;
  R1_ASSIGN(c.nodes_, ctx.compute_compile(source(kNodeShader), "cull_nodes"));
  R1_ASSIGN(c.mark_, ctx.compute_compile(source(kMark), "cull_mark"));
  R1_ASSIGN(c.count_, ctx.compute_compile(source(kCount), "cull_count"));
  R1_ASSIGN(c.scan_, ctx.compute_compile(source(kScan), "cull_scan"));
  R1_ASSIGN(c.args_, ctx.compute_compile(source(kArgsShader), "cull_args"));
  R1_ASSIGN(c.scatter_, ctx.compute_compile(source(kScatter), "cull_scatter"));
  return c;
}

bool CullPass::fits(std::size_t particles, std::size_t nodes) const {
  const std::size_t range = ctx_->info().max_buffer;
  return particles <= kMaxParticles && particles * 64 <= range && nodes * 64 <= range;
}

Result<CullOutput> CullPass::run(const CullScene& scene, const CullView& view, bool read_tier_lists) {
  Context& ctx = *ctx_;
  auto& b = buffers_;
  const auto ensure = [&ctx](std::uint32_t& id, std::size_t bytes) { return ctx.buffer_ensure(id, std::max<std::size_t>(bytes, 16)); };
  if (scene.serial == 0 || scene.serial != serial_) {
    // A new scene: checked, flattened and uploaded once, kept under its serial.
    serial_ = 0;
    const std::size_t n = scene.radius.size();
    if (scene.position.size() != 3 * n || scene.leaf.size() != n)
      return Status::input("vulkan cull: positions, radii and leaves of different particle counts");
    const bool impostors = !scene.color.empty() || !scene.shape.empty();
    if (impostors && (scene.color.size() != 3 * n || scene.shape.size() != n))
      return Status::input("vulkan cull: colours and shapes of different particle counts");
    std::array<std::uint32_t, kLevels + 1> offset{};
    for (int l = 0; l < kLevels; ++l) {
      const auto L = static_cast<std::size_t>(l);
      if (scene.node[L].size() % 8 != 0) return Status::input("vulkan cull: level " + std::to_string(l) + "'s nodes are not 8 doubles each");
      const std::size_t count = scene.node[L].size() / 8;
      if (l + 1 < kLevels && scene.parent[L].size() != count)
        return Status::input("vulkan cull: level " + std::to_string(l) + " has " + std::to_string(count) + " nodes and " +
                             std::to_string(scene.parent[L].size()) + " parents");
      offset[L + 1] = offset[L] + static_cast<std::uint32_t>(count);
    }
    const std::uint32_t total = offset[kLevels];
    if (!fits(n, total))
      return Status::input("vulkan cull: " + std::to_string(n) + " particles and " + std::to_string(total) +
                           " nodes pass the device's storage range of " + std::to_string(ctx.info().max_buffer) + " bytes");
    std::vector<double> nodes;
    nodes.reserve(std::size_t{total} * 8);
    std::vector<std::uint32_t> parents(total, kNone);
    for (int l = 0; l < kLevels; ++l) {
      const auto L = static_cast<std::size_t>(l);
      nodes.insert(nodes.end(), scene.node[L].begin(), scene.node[L].end());
      if (l + 1 == kLevels) continue;
      for (std::size_t i = 0; i < scene.parent[L].size(); ++i) {
        const std::uint32_t q = scene.parent[L][i];
        if (q >= offset[L + 2] - offset[L + 1])
          return Status::input("vulkan cull: node " + std::to_string(i) + " of level " + std::to_string(l) + " has no parent");
        parents[offset[L] + i] = offset[L + 1] + q;
      }
    }
    for (const std::uint32_t lf : scene.leaf)
      if (lf != kNone && lf >= offset[1]) return Status::input("vulkan cull: a particle's leaf is no level-0 node");
    std::vector<double> geo(n * 8, 0.0);
    std::vector<std::int32_t> meta(n * 8, 0);
    for (std::size_t q = 0; q < n; ++q) {
      std::copy(scene.position.begin() + static_cast<std::ptrdiff_t>(3 * q), scene.position.begin() + static_cast<std::ptrdiff_t>(3 * q + 3),
                geo.begin() + static_cast<std::ptrdiff_t>(8 * q));
      geo[8 * q + 3] = scene.radius[q];
      meta[8 * q + 4] = static_cast<std::int32_t>(q);
      if (!impostors) continue;
      std::copy(scene.color.begin() + static_cast<std::ptrdiff_t>(3 * q), scene.color.begin() + static_cast<std::ptrdiff_t>(3 * q + 3),
                geo.begin() + static_cast<std::ptrdiff_t>(8 * q + 4));
      meta[8 * q + 5] = static_cast<std::int32_t>(scene.shape[q]);
    }
    R1_TRY(ensure(b[kNodes], nodes.size() * 8));
    R1_TRY(ensure(b[kParents], parents.size() * 4));
    R1_TRY(ensure(b[kState], std::size_t{total} * 4));
    R1_TRY(ensure(b[kGeometry], n * 64));
    R1_TRY(ensure(b[kMeta], n * 32));
    R1_TRY(ensure(b[kLeaf], n * 4));
    R1_TRY(ensure(b[kCode], n * 4));
    R1_TRY(ctx.buffer_write(b[kNodes], detail::bytes_of(std::span<const double>(nodes)), 0));
    R1_TRY(ctx.buffer_write(b[kParents], detail::bytes_of(std::span<const std::uint32_t>(parents)), 0));
    R1_TRY(ctx.buffer_write(b[kGeometry], detail::bytes_of(std::span<const double>(geo)), 0));
    R1_TRY(ctx.buffer_write(b[kMeta], detail::bytes_of(std::span<const std::int32_t>(meta)), 0));
    R1_TRY(ctx.buffer_write(b[kLeaf], detail::bytes_of(scene.leaf), 0));
    n_ = n, offset_ = offset, impostors_ = impostors, serial_ = scene.serial;
  }
  const std::size_t n = n_;
  const std::array<std::uint32_t, kLevels + 1>& offset = offset_;
  const std::uint32_t total = offset[kLevels];
  std::vector<double> params(36, 0.0);
  for (std::size_t k = 0; k < 5; ++k) {
    params[4 * k] = view.normal[k].x, params[4 * k + 1] = view.normal[k].y, params[4 * k + 2] = view.normal[k].z;
    params[4 * k + 3] = view.offset[k];
  }
  const double fixed[] = {view.position.x, view.position.y, view.position.z, view.forward.x, view.forward.y, view.forward.z,
                          view.focal_px,   view.near,       view.t0,         view.t1,        view.t2,        view.t3,
                          view.band,       1e-9,            1 + 1e-9,        1e300};
  std::copy(std::begin(fixed), std::end(fixed), params.begin() + 20);

  CullOutput out;
  last_args_ = {};
  for (int l = 0; l < kLevels; ++l) out.state[static_cast<std::size_t>(l)].assign(offset[static_cast<std::size_t>(l) + 1] - offset[static_cast<std::size_t>(l)], 0);
  for (DrawArgs& a : out.args) a.vertex_count = 6;
  if (n == 0 && total == 0) return out;

  const auto blocks = static_cast<std::uint32_t>((n + kBlock - 1) / kBlock);
  R1_TRY(ensure(b[kParams], params.size() * 8));
  R1_TRY(ensure(b[kCounts], (std::size_t{blocks} + 1) * kColumns * 4));
  R1_TRY(ensure(b[kArgs], 5 * sizeof(DrawArgs)));
  R1_TRY(ctx.buffer_write(b[kParams], detail::bytes_of(std::span<const double>(params)), 0));

  Push push;
  push.n = static_cast<std::uint32_t>(n), push.blocks = blocks;
  const Slot prm{7, b[kParams]};
  for (int l = kLevels - 1; l >= 0; --l) {
    const auto L = static_cast<std::size_t>(l);
    push.count = offset[L + 1] - offset[L], push.offset = offset[L], push.top = l + 1 == kLevels ? 1 : 0;
    if (push.count == 0) continue;
    const Slot slots[] = {{0, b[kNodes]}, {1, b[kParents]}, {2, b[kState]}, prm};
    R1_TRY(ctx.dispatch(nodes_, slots, detail::groups_for(push.count), push_bytes(push)));
  }
  if (total > 0) {
    R1_ASSIGN(const auto st, ctx.buffer_read(b[kState], 0, std::size_t{total} * 4));
    for (int l = 0; l < kLevels; ++l)
      for (std::uint32_t g = offset[static_cast<std::size_t>(l)]; g < offset[static_cast<std::size_t>(l) + 1]; ++g) {
        std::uint32_t s = 0;
        std::memcpy(&s, st.data() + std::size_t{g} * 4, 4);
        out.state[static_cast<std::size_t>(l)][g - offset[static_cast<std::size_t>(l)]] = static_cast<std::uint8_t>(s);
      }
  }
  if (n == 0) return out;
  {
    const Slot slots[] = {{2, b[kState]}, {3, b[kGeometry]}, {5, b[kLeaf]}, {6, b[kCode]}, prm};
    R1_TRY(ctx.dispatch(mark_, slots, detail::groups_for(n), push_bytes(push)));
  }
  {
    const Slot slots[] = {{1, b[kCounts]}, {6, b[kCode]}, prm};
    R1_TRY(ctx.dispatch(count_, slots, detail::groups_for(blocks), push_bytes(push)));
    R1_TRY(ctx.dispatch(scan_, slots, {1, 1, 1}, push_bytes(push)));
    const Slot args[] = {{1, b[kCounts]}, {2, b[kArgs]}, prm};
    R1_TRY(ctx.dispatch(args_, args, {1, 1, 1}, push_bytes(push)));
  }
  R1_ASSIGN(const auto args, ctx.buffer_read(b[kArgs], 0, 5 * sizeof(DrawArgs)));
  std::memcpy(out.args.data(), args.data(), args.size());
  last_args_ = out.args;
  std::size_t visible = 0;
  for (const DrawArgs& a : out.args) visible += a.instance_count;
  R1_TRY(ensure(b[kOut], visible * 32));
  R1_TRY(ensure(b[kLists], visible * 4));
  {
    const Slot slots[] = {{0, b[kOut]}, {1, b[kCounts]}, {2, b[kArgs]}, {3, b[kGeometry]}, {5, b[kLists]}, {6, b[kCode]}, prm};
    R1_TRY(ctx.dispatch(scatter_, slots, detail::groups_for(blocks), push_bytes(push)));
  }
  if (visible == 0) return out;
  R1_ASSIGN(const auto rec, ctx.buffer_read(b[kOut], 0, visible * 32));
  out.particle.resize(visible), out.depth.resize(visible), out.size.resize(visible), out.tier.resize(visible);
  for (std::size_t i = 0; i < visible; ++i) {
    const std::uint8_t* r = rec.data() + i * 32;
    std::uint32_t tier = 0;
    std::memcpy(&out.particle[i], r, 4);
    std::memcpy(&tier, r + 4, 4);
    std::memcpy(&out.depth[i], r + 8, 8);
    std::memcpy(&out.size[i], r + 16, 8);
    out.tier[i] = static_cast<std::uint8_t>(tier);
  }
  if (read_tier_lists) {
    R1_ASSIGN(const auto lists, ctx.buffer_read(b[kLists], 0, visible * 4));
    out.tier_lists.resize(visible);
    std::memcpy(out.tier_lists.data(), lists.data(), visible * 4);
  }
  return out;
}

}  // namespace r1::vk
