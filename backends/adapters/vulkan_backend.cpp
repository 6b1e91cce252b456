// The vulkan backend (spec/backends.md R1-BKD-065..070): on accel/vulkan's context the frame's
// cull, its T1/T2 impostor pass (a graphics pipeline, or a compute shader), its edge tubes, the
// splats' depth sort and its field and composite pass, and the spectral solver's and the focus's
// exact kernels; edge bundling, splat binning, labels and the other epoch work on the host (the
// reference's passes, the cpu backend's stages). Its epochs are the reference's bytes. Its 13.1
// device is the Vulkan device on the same context.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <numeric>
#include <stdexcept>
#include <string>

#include "adapters.hpp"
#include "stage_backend.hpp"
#include "r1/accel/vulkan_panel.hpp"
#include "vulkan_adapters.hpp"
#include "vulkan_passes.hpp"
#include "render/content_pass.hpp"
#if R1_BACKEND_CPU
#include "r1/accel/cpu/panel_kernels.hpp"
#endif

namespace r1::backends {

namespace {

// The focus's exact products on the device (R1-FOC-092): vk::ExactSpmv, which keeps the context
// alive while it holds its buffers. Columns past the matrix's last (a vector's tail that no entry
// reads) are not uploaded.
class DeviceProduct final : public ExactProduct {
 public:
  DeviceProduct(std::shared_ptr<vk::Context> ctx, vk::ExactSpmv spmv) : ctx_(std::move(ctx)), spmv_(std::move(spmv)) {}
  Result<std::vector<std::int64_t>> apply(std::span<const std::int64_t> x) override {
    return spmv_.apply(x.size() > spmv_.columns() ? x.first(spmv_.columns()) : x);
  }

 private:
  std::shared_ptr<vk::Context> ctx_;
  vk::ExactSpmv spmv_;
};

// Whether $var (device or host) leaves a stage's kernels on the device: unset or empty, yes.
bool on_device_unless(const char* var) {
  const char* env = std::getenv(var);
  if (env == nullptr || *env == '\0') return true;
  const std::string m = env;
  if (m != "host" && m != "device") throw std::invalid_argument(std::string(var) + "=" + m + ": device or host");
  return m == "device";
}

ExactProductFactory device_products(std::shared_ptr<vk::Context> ctx) {
  return [ctx](std::span<const std::uint64_t> ptr, std::span<const std::uint32_t> col, std::span<const std::int64_t> val,
               bool identity) -> Result<std::unique_ptr<ExactProduct>> {
    // A row too long for lavapipe's loops: declined, the focus keeps its row loops (R1-BKD-073).
    if (!vk::rows_fit_the_loop_limit(ptr)) return std::unique_ptr<ExactProduct>();
    R1_ASSIGN(vk::ExactSpmv spmv, vk::ExactSpmv::build(*ctx, ptr, col, val, identity));
    return std::unique_ptr<ExactProduct>(std::make_unique<DeviceProduct>(ctx, std::move(spmv)));
  };
}

struct PassState {
  std::shared_ptr<vk::Context> ctx;
  vk::CullPass cull;
  // Set by the frame's cull when it ran on the device and the impostor draw may read its records
  // (R1-BKD-077), with the bound on the hits' ray parameter; the impostor pass clears it.
  bool cull_feeds_impostors = false;
  double impostor_far = 1;
  vk::EdgePass edges;
  vk::DepthSort splat_sort;
  vk::ImpostorPass impostors;
  vk::CompositePass composite;
};

vk::ImpostorCamera camera_of(const render::View& v, const render::CameraFrame& f) {
  vk::ImpostorCamera cam;
  cam.position = v.camera.position;
  cam.right = f.right, cam.up = f.up, cam.forward = f.forward;
  cam.focal_px = f.focal_px;
  cam.width = static_cast<std::uint32_t>(v.width), cam.height = static_cast<std::uint32_t>(v.height);
  return cam;
}

Status draw_on_device(PassState& st, std::span<const render::Impostor> list, const render::View& v, const render::CameraFrame& f,
                      render::OpaqueLayer& layer) {
  const vk::ImpostorCamera cam = camera_of(v, f);
  if (std::exchange(st.cull_feeds_impostors, false) && st.impostors.mode() == vk::ImpostorPass::Mode::kRaster)
    return st.impostors.draw_culled(cam, st.cull, st.impostor_far, layer.t, layer.color, layer.owner);
  std::vector<vk::ImpostorItem> items(list.size());
  for (std::size_t i = 0; i < list.size(); ++i) {
    const render::Impostor& im = list[i];
    items[i] = {im.particle, im.shape, im.center, im.radius, im.color, im.rect.x0, im.rect.y0, im.rect.x1, im.rect.y1};
  }
  return st.impostors.draw(cam, items, layer.t, layer.color, layer.owner);
}

// The scene as vk::CullPass reads it (R1-BKD-074, 077).
void flatten_scene(const render::Scene& s, std::array<std::vector<double>, kLevels>& node,
                   std::array<std::vector<std::uint32_t>, kLevels>& parent, std::vector<double>& position, std::vector<double>& color,
                   std::vector<std::uint32_t>& leaf, vk::CullScene& scene) {
  constexpr std::uint32_t kNone = 0xffffffffu;
  for (int l = 0; l < kLevels; ++l) {
    const auto L = static_cast<std::size_t>(l);
    for (const render::NodeData& d : s.nodes[L]) {
      const double row[8] = {d.lo.x, d.lo.y, d.lo.z, d.hi.x, d.hi.y, d.hi.z, d.max_radius, 0.0};
      node[L].insert(node[L].end(), row, row + 8);
    }
    if (l > 0) {
      parent[L - 1].assign(s.nodes[L - 1].size(), kNone);
      for (std::uint32_t id = 0; id < s.nodes[L].size(); ++id)
        for (const std::uint32_t c : s.hierarchy->levels[L][id].children) parent[L - 1][c] = id;
    }
  }
  position.resize(std::size_t{s.n} * 3);
  color.resize(std::size_t{s.n} * 3);
  leaf.assign(s.n, kNone);
  for (std::uint32_t p = 0; p < s.n; ++p) {
    const std::size_t k = std::size_t{p} * 3;
    position[k] = s.position[p].x, position[k + 1] = s.position[p].y, position[k + 2] = s.position[p].z;
    color[k] = s.color[p].x, color[k + 1] = s.color[p].y, color[k + 2] = s.color[p].z;
  }
  for (std::uint32_t id = 0; id < s.nodes[0].size(); ++id)
    for (const std::uint32_t p : s.hierarchy->levels[0][id].children) leaf[p] = id;
  for (std::size_t l = 0; l < kLevels; ++l) scene.node[l] = node[l], scene.parent[l] = parent[l];
  scene.position = position, scene.radius = s.radius, scene.leaf = leaf;
  scene.color = color, scene.shape = s.shape;
}

}  // namespace

Status cull_on_device(vk::CullPass& pass, const render::Scene& s, const render::View& v, const render::CameraFrame& f,
                      render::CullResult& out, render::CullStats& stats) {
  // The scene flattened, once per scene (the pass keeps it under its serial): node boxes with
  // their largest member radius, parents from the children lists (the walk's own links),
  // positions, radii, colours, shapes and each particle's level-0 node.
  std::array<std::vector<double>, kLevels> node;
  std::array<std::vector<std::uint32_t>, kLevels> parent;
  std::vector<double> position, color;
  std::vector<std::uint32_t> leaf;
  vk::CullScene scene;
  scene.serial = s.serial;
  if (s.serial == 0 || pass.serial() != s.serial) flatten_scene(s, node, parent, position, color, leaf, scene);
  const render::Frustum fr = render::make_frustum(v, f);
  vk::CullView view;
  view.normal = fr.normal, view.offset = fr.offset;
  view.position = v.camera.position, view.forward = f.forward;
  view.focal_px = f.focal_px, view.near = render::kNear;
  view.t0 = v.tiers.t0, view.t1 = v.tiers.t1, view.t2 = v.tiers.t2, view.t3 = v.tiers.t3, view.band = v.tiers.band;
  R1_ASSIGN(const vk::CullOutput got, pass.run(scene, view));
  out = {};
  out.visible.resize(got.particle.size());
  for (std::size_t i = 0; i < got.particle.size(); ++i)
    out.visible[i] = {got.particle[i], got.depth[i], got.size[i], static_cast<render::Tier>(got.tier[i])};
  // The far nodes in the reference's walk order and its counts, from the device's decisions: the
  // walk without its tests, visiting exactly the nodes the device tested.
  stats = {};
  std::vector<std::pair<int, std::uint32_t>> stack;
  for (std::uint32_t id = static_cast<std::uint32_t>(s.nodes[kLevels - 1].size()); id-- > 0;) stack.push_back({kLevels - 1, id});
  while (!stack.empty()) {
    const auto [l, id] = stack.back();
    stack.pop_back();
    const auto L = static_cast<std::size_t>(l);
    ++stats.nodes_tested;
    const std::uint8_t state = got.state[L][id];
    const auto& children = s.hierarchy->levels[L][id].children;
    if (state == vk::CullOutput::kCulled) {
      ++stats.nodes_culled;
    } else if (state == vk::CullOutput::kFar) {
      out.far.push_back({l, id});
      out.far_particles += s.nodes[L][id].count;
    } else if (state != vk::CullOutput::kOpen) {
      return Status::internal("vulkan cull: node " + std::to_string(id) + " of level " + std::to_string(l) +
                              " is on the walk but the device did not test it");
    } else if (l == 0) {
      stats.particles_tested += children.size();
    } else {
      for (std::size_t c = children.size(); c-- > 0;) stack.push_back({l - 1, children[c]});
    }
  }
  return Status::ok();
}

vk::NeuralData neural_data(const render::NeuralField& f) {
  vk::NeuralData n;
  n.levels = f.config.levels, n.log2_table = f.config.log2_table, n.hidden = f.config.hidden, n.block = f.config.block;
  n.resolution = f.resolution;
  n.lo = f.lo, n.centroid = f.centroid;
  n.size = f.size, n.tau_lo = f.tau_lo, n.tau_hi = f.tau_hi, n.kappa = f.kappa;
  for (const render::NeuralField::PriorPart& p : f.prior_parts) {
    const double head[8] = {p.mass, p.s2, p.centroid.x, p.centroid.y, p.centroid.z, p.colour.x, p.colour.y, p.colour.z};
    n.prior.insert(n.prior.end(), head, head + 8);
    n.prior.insert(n.prior.end(), p.gradient.begin(), p.gradient.end());
  }
  n.fade_power = f.fade_power;
  n.log2_range = f.tau_hi > f.tau_lo ? std::log2(f.tau_hi / f.tau_lo) : 0.0;
  for (const std::vector<float>* part : {&f.grid, &f.w1, &f.b1, &f.w2, &f.b2, &f.w3, &f.b3, &f.wc, &f.bc, &f.wg, &f.bg, &f.gamma})
    n.params.insert(n.params.end(), part->begin(), part->end());
  return n;
}

Status edges_on_device(vk::EdgePass& pass, std::span<const render::EdgeTube> tubes, const render::View& v,
                       const render::CameraFrame& f, render::OpaqueLayer& layer) {
  vk::EdgeData ed;
  ed.time = v.time;
  for (const render::EdgeTube& tube : tubes) {
    if (tube.rows.empty()) continue;
    const double row[16] = {tube.a.x, tube.a.y, tube.a.z, tube.b.x,  tube.b.y,  tube.b.z,  tube.rho,  tube.stripes,
                            tube.speed, tube.ca.x, tube.ca.y, tube.ca.z, tube.cb.x, tube.cb.y, tube.cb.z, 0.0};
    const int first = tube.rows.front().y, count = tube.rows.back().y - first + 1;
    if (first < 0 || count <= 0 || first + count > v.height)
      return Status::internal("vulkan edges: a tube's rows are not ascending rows of the image");
    const auto at = static_cast<std::uint32_t>(ed.spans.size() / 2);
    ed.tubes.insert(ed.tubes.end(), row, row + 16);
    const std::uint32_t meta[4] = {static_cast<std::uint32_t>(first), static_cast<std::uint32_t>(count), at, 0};
    ed.rows.insert(ed.rows.end(), meta, meta + 4);
    ed.spans.resize(ed.spans.size() + static_cast<std::size_t>(count) * 2, 0);
    for (const render::RowSpan& r : tube.rows) {
      if (r.y < first || r.y >= first + count) return Status::internal("vulkan edges: a tube's rows are not ascending rows of the image");
      const std::size_t k = (std::size_t{at} + static_cast<std::size_t>(r.y - first)) * 2;
      ed.spans[k] = r.x0, ed.spans[k + 1] = r.x1;
    }
  }
  R1_ASSIGN(const bool drawn, pass.draw(camera_of(v, f), ed, layer.t, layer.color, layer.owner));
  if (!drawn) render::draw_edge_tubes(tubes, v, f, layer);  // a tile past lavapipe's loop limit (R1-BKD-073)
  return Status::ok();
}

namespace {

// The frame's field flattened for the device: every node's field aggregates (FieldFrame::node),
// the children tables, and per level-0 node the members with field weight (add_members' list).
vk::FieldData field_data(const render::FieldFrame& ff, const render::View& v) {
  const render::Scene& s = *ff.scene;
  vk::FieldData fd;
  std::uint32_t total = 0;
  for (int l = 0; l < kLevels; ++l) {
    fd.level_offset[static_cast<std::size_t>(l)] = total;
    total += static_cast<std::uint32_t>(s.nodes[static_cast<std::size_t>(l)].size());
  }
  fd.level_offset[kLevels] = total;
  fd.nodes.reserve(std::size_t{total} * vk::kFieldNodeDoubles);
  for (int l = 0; l < kLevels; ++l)
    for (std::uint32_t id = 0; id < s.nodes[static_cast<std::size_t>(l)].size(); ++id) {
      const render::NodeField nd = ff.node(l, id);
      const render::ColourSpread sp = nd.spread != nullptr ? *nd.spread : render::ColourSpread{};
      const double row[vk::kFieldNodeDoubles] = {
          nd.weight,   nd.centroid.x, nd.centroid.y, nd.centroid.z, nd.color.x,  nd.color.y,  nd.color.z,  nd.extent,
          sp.grad[0],  sp.grad[1],    sp.grad[2],    sp.grad[3],    sp.grad[4],  sp.grad[5],  sp.grad[6],  sp.grad[7],
          sp.grad[8],  sp.lo.x,       sp.lo.y,       sp.lo.z,       sp.hi.x,     sp.hi.y,     sp.hi.z,     0.0};
      fd.nodes.insert(fd.nodes.end(), row, row + vk::kFieldNodeDoubles);
    }
  fd.child_ptr.push_back(0);
  fd.next.assign(total, 0xffffffffu);
  fd.parent.assign(total, 0xffffffffu);
  for (int l = 1; l < kLevels; ++l)
    for (std::uint32_t id = 0; id < s.nodes[static_cast<std::size_t>(l)].size(); ++id) {
      const auto& children = s.hierarchy->levels[static_cast<std::size_t>(l)][id].children;
      const std::uint32_t self = fd.level_offset[static_cast<std::size_t>(l)] + id;
      for (std::size_t k = 0; k < children.size(); ++k) {
        const std::uint32_t c = fd.level_offset[static_cast<std::size_t>(l - 1)] + children[k];
        fd.child.push_back(c);
        fd.parent[c] = self;
        if (k + 1 < children.size()) fd.next[c] = fd.level_offset[static_cast<std::size_t>(l - 1)] + children[k + 1];
      }
      fd.child_ptr.push_back(static_cast<std::uint32_t>(fd.child.size()));
    }
  fd.member_ptr.push_back(0);
  const double n = s.n;
  for (std::uint32_t id = 0; id < s.nodes[0].size(); ++id) {
    const std::uint32_t slot = ff.slot[0].empty() ? render::FieldFrame::kFarSlot : ff.slot[0][id];
    const auto add = [&fd](double w, const render::Vec3& pos, const render::Vec3& c) {
      const double row[8] = {w, pos.x, pos.y, pos.z, c.x, c.y, c.z, 0.0};
      fd.members.insert(fd.members.end(), row, row + 8);
    };
    if (slot == render::FieldFrame::kFarSlot) {
      for (std::uint32_t q : s.hierarchy->levels[0][id].children) {
        const double w = n * s.phi[q];
        if (w > 0) add(w, s.position[q], s.color[q]);
      }
    } else if (slot != render::FieldFrame::kBehindSlot) {
      const auto [begin, end] = ff.member_range[slot];
      for (std::uint32_t k = begin; k < end; ++k) add(ff.members[k].weight, ff.members[k].position, ff.members[k].color);
    }
    fd.member_ptr.push_back(static_cast<std::uint32_t>(fd.members.size() / 8));
  }
  fd.top_ptr.push_back(0);
  for (const auto& list : ff.top_by_tile) {
    fd.top.insert(fd.top.end(), list.begin(), list.end());
    fd.top_ptr.push_back(static_cast<std::uint32_t>(fd.top.size()));
  }
  if (ff.top_by_tile.empty()) fd.top_ptr.clear();
  fd.tiles_x = static_cast<std::uint32_t>(ff.tiles_x);
  fd.samples = static_cast<std::uint32_t>(ff.params.samples);
  fd.tau_cam = ff.tau_cam, fd.t_far = ff.t_far;
  fd.kappa = ff.params.kappa, fd.cutoff = ff.params.cutoff, fd.theta = ff.params.theta, fd.stop = ff.params.stop;
  fd.seed = s.seed;
  fd.enabled = v.field;
  return fd;
}

Status composite_on_device(PassState& st, const render::CompositeInput& in, render::Image& image, render::FrameStats& stats) {
  const render::View& v = in.view;
  if (in.splats.tiles_x != (v.width + 15) / 16) return Status::internal("vulkan composite: splat tiles are not 16 pixels");
  render::PixelCompositor host(in);  // builds the frame's field; draws the pixels the device leaves
  vk::FieldData fd = field_data(host.field(), v);
  vk::SplatData sd;
  for (const render::Splat& sp : in.splats.splats) {
    const double row[12] = {sp.depth, sp.px, sp.py, sp.ca, sp.cb, sp.cc, sp.opacity, sp.color.x, sp.color.y, sp.color.z, 0, 0};
    sd.splats.insert(sd.splats.end(), row, row + 12);
  }
  sd.tile_ptr.push_back(0);
  for (const auto& list : in.splats.tiles) {
    sd.tile.insert(sd.tile.end(), list.begin(), list.end());
    sd.tile_ptr.push_back(static_cast<std::uint32_t>(sd.tile.size()));
  }
  const std::size_t pixels = static_cast<std::size_t>(v.width) * static_cast<std::size_t>(v.height);
  std::vector<double> opaque(pixels * 4);
  for (std::size_t k = 0; k < pixels; ++k) {
    opaque[k * 4] = in.opaque.t[k];
    opaque[k * 4 + 1] = in.opaque.color[k].x, opaque[k * 4 + 2] = in.opaque.color[k].y, opaque[k * 4 + 3] = in.opaque.color[k].z;
  }
  std::vector<float> flow;
  std::vector<std::uint32_t> left;
  const render::NeuralField* nf = host.field().scene->neural;
  vk::NeuralData nd;
  if (nf != nullptr && host.field().mixed.empty()) nd = neural_data(*nf);
  if (nf != nullptr && host.field().mixed.empty() && (!vk::CompositePass::infers(nd) || host.field().params.literal)) {
    // A frame drawn with a neural field whose network the device does not infer, or with the
    // literal march (R1-BKD-076, R1-NRF-033): the host draws every pixel with the reference's code.
    left.resize(pixels);
    for (std::size_t k = 0; k < pixels; ++k) left[k] = static_cast<std::uint32_t>(k);
  } else {
    if (nf != nullptr && host.field().mixed.empty()) fd.neural = &nd;  // a pure T-infinity frame (R1-NRF-031)
    R1_TRY(st.composite.draw(camera_of(v, in.frame), fd, sd, opaque, image.rgba, flow, left));
    if (fd.neural != nullptr) {
      stats.field_neural = st.composite.inferred();
      stats.field_rewalked = st.composite.rewalked();
    }
  }
  stats.host_pixels = left.size();
  for (const std::uint32_t k : left) {
    float f[3] = {0, 0, 0};
    host.pixel(static_cast<int>(k % static_cast<std::uint32_t>(v.width)), static_cast<int>(k / static_cast<std::uint32_t>(v.width)),
               &image.rgba[std::size_t{k} * 4], f);
    // The host's flow replaces whatever the device left at this pixel, zero included.
    if (flow.empty() && (f[0] != 0 || f[1] != 0 || f[2] != 0)) flow.assign(pixels * 3, 0.0f);
    if (!flow.empty()) std::copy(f, f + 3, flow.begin() + static_cast<std::ptrdiff_t>(std::size_t{k} * 3));
  }
  if (!flow.empty()) image.flow = std::move(flow);
  return Status::ok();
}

}  // namespace

std::unique_ptr<Backend> make_vulkan_backend() {
  auto ctx = vk::Context::create();
  if (!ctx.is_ok()) throw std::invalid_argument(ctx.status().message());
  auto state = std::make_shared<PassState>();
  state->ctx = std::move(ctx).value();
  // The raster pipeline where the device has one (R1-BKD-068); $R1_VULKAN_IMPOSTORS = compute or
  // raster picks one.
  vk::ImpostorPass::Mode mode = state->ctx->info().graphics ? vk::ImpostorPass::Mode::kRaster : vk::ImpostorPass::Mode::kCompute;
  if (const char* env = std::getenv("R1_VULKAN_IMPOSTORS"); env != nullptr && *env != '\0') {
    const std::string m = env;
    if (m == "compute") mode = vk::ImpostorPass::Mode::kCompute;
    else if (m == "raster" && state->ctx->info().graphics) mode = vk::ImpostorPass::Mode::kRaster;
    else
      throw std::invalid_argument("R1_VULKAN_IMPOSTORS=" + m + ": compute" +
                                  (state->ctx->info().graphics ? " or raster" : " (this device has no graphics queue)"));
  }
  auto pass = vk::ImpostorPass::build(*state->ctx, mode);
  if (!pass.is_ok()) throw std::invalid_argument(pass.status().message());
  state->impostors = std::move(pass).value();
  // The field and composite pass (R1-BKD-070), det_exp with the reference's constants.
  // $R1_VULKAN_FIELD_CANDIDATES caps the candidate nodes a ray holds on the device (tests use a
  // small cap to send rays to the host's fall-back).
  std::uint32_t max_candidates = vk::CompositePass::kMaxCandidates;
  if (const char* env = std::getenv("R1_VULKAN_FIELD_CANDIDATES"); env != nullptr && *env != '\0') {
    char* end = nullptr;
    const unsigned long c = std::strtoul(env, &end, 10);
    if (end == env || *end != '\0' || c < 1 || c > 4096)
      throw std::invalid_argument("R1_VULKAN_FIELD_CANDIDATES=" + std::string(env) + ": a count in 1..4096");
    max_candidates = static_cast<std::uint32_t>(c);
  }
  auto composite = vk::CompositePass::build(*state->ctx, reference_exp_constants(), max_candidates);
  if (!composite.is_ok()) throw std::invalid_argument(composite.status().message());
  state->composite = std::move(composite).value();
  // The cull (R1-BKD-074) unless $R1_VULKAN_CULL=host; beyond the device's particles, the host's.
  const bool cull_on_the_device = on_device_unless("R1_VULKAN_CULL");
  auto cull = vk::CullPass::build(*state->ctx);
  if (!cull.is_ok()) throw std::invalid_argument(cull.status().message());
  state->cull = std::move(cull).value();
  // The edge tubes (R1-BKD-075) unless $R1_VULKAN_EDGES=host.
  const bool edges_on_the_device = on_device_unless("R1_VULKAN_EDGES");
  auto edges = vk::EdgePass::build(*state->ctx);
  if (!edges.is_ok()) throw std::invalid_argument(edges.status().message());
  state->edges = std::move(edges).value();
  // The splats' depth sort (R1-BKD-072, R1-RND-079); beyond the device sort's keys, the host's.
  auto sort = vk::DepthSort::build(*state->ctx);
  if (!sort.is_ok()) throw std::invalid_argument(sort.status().message());
  state->splat_sort = std::move(sort).value();
  auto device = make_vulkan_device_on(state->ctx);
  if (!device.is_ok()) throw std::invalid_argument(device.status().message());
  const std::string name = (*device)->describe();
  render::FramePasses passes;
  if (cull_on_the_device)
    passes.cull = [state](const render::Scene& s, const render::View& v, const render::CameraFrame& f, render::CullResult& out,
                          render::CullStats& stats) -> Status {
      std::size_t nodes = 0;
      for (const auto& level : s.nodes) nodes += level.size();
      state->cull_feeds_impostors = false;
      if (!state->cull.fits(s.n, nodes)) {
        out = render::cull_frame(s, v, f, &stats);
        return Status::ok();
      }
      R1_TRY(cull_on_device(state->cull, s, v, f, out, stats));
      // The impostor draw reads the cull's T0..T2 records unless a T0 particle opens into content
      // (the content pass draws it; the host's list leaves it out). Its depth scale bounds every
      // hit by the drawn particles' bounding spheres, as the list's draw does.
      bool opens = false;
      double far = 1;
      for (const render::Visible& vis : out.visible) {
        if (vis.tier > render::Tier::kT2) continue;
        opens = opens || (vis.tier == render::Tier::kT0 && s.content != nullptr && s.content->has(vis.particle));
        far = std::max(far, render::length(s.position[vis.particle] - v.camera.position) + s.radius[vis.particle]);
      }
      state->cull_feeds_impostors = !opens && state->cull.holds_impostors();
      state->impostor_far = far;
      return Status::ok();
    };
  if (edges_on_the_device)
    passes.edges = [state](std::span<const render::EdgeTube> tubes, const render::View& v, const render::CameraFrame& f,
                           render::OpaqueLayer& layer) { return edges_on_device(state->edges, tubes, v, f, layer); };
  passes.impostors = [state](std::span<const render::Impostor> list, const render::View& v, const render::CameraFrame& f,
                             render::OpaqueLayer& layer) { return draw_on_device(*state, list, v, f, layer); };
  passes.composite = [state](const render::CompositeInput& in, render::Image& image, render::FrameStats& st) {
    return composite_on_device(*state, in, image, st);
  };
  passes.splat_sort = [state](std::span<const double> depth, std::vector<std::uint32_t>& order) -> Status {
    if (depth.size() > vk::DepthSort::kMaxKeys) {
      order.resize(depth.size());
      std::iota(order.begin(), order.end(), 0u);
      std::stable_sort(order.begin(), order.end(), [&depth](std::uint32_t a, std::uint32_t b) { return depth[a] < depth[b]; });
      return Status::ok();
    }
    R1_ASSIGN(order, state->splat_sort.order(depth));
    return Status::ok();
  };
  // The spectral solver's inner products and combinations on the device (R1-BKD-069) and the full
  // focus's sparse products (R1-FOC-092, R1-BKD-064), unless $R1_VULKAN_SPECTRAL=host or
  // $R1_VULKAN_FOCUS=host keeps them on the host.
  const bool spectral_on_device = on_device_unless("R1_VULKAN_SPECTRAL");
  const bool focus_on_device = on_device_unless("R1_VULKAN_FOCUS");
  StageKernels kernels;
  std::string epoch;
  if (spectral_on_device) {
    auto factory = vk::panel_kernel_factory(state->ctx);
    if (!factory.is_ok()) throw std::invalid_argument(factory.status().message());
    kernels.panel = std::move(factory).value();
    auto rows = vk::rows_factory(state->ctx);
    if (!rows.is_ok()) throw std::invalid_argument(rows.status().message());
    kernels.rows = std::move(rows).value();
    epoch = "the spectral solver's exact inner products, combinations and operator rows on the device";
  } else {
#if R1_BACKEND_CPU
    std::string error;
    const accel::cpu::Simd level = accel::cpu::chosen_simd(&error);
    if (!error.empty()) throw std::invalid_argument(error);
    kernels.panel = accel::cpu::kernel_factory(level);
    kernels.rows = accel::cpu::rows_factory(level, true);
    epoch = "the spectral stage the cpu backend's on the host";
#else
    epoch = "the spectral stage the reference's with its TBB switch, on the host";
#endif
  }
  if (focus_on_device) {
    kernels.focus = device_products(state->ctx);
    epoch += "; the full focus's sparse products (the heat kernel's walks, the diffusion's in-link sums) exact on the device, "
             "its springs, combinations and local updates on the host";
  } else {
    epoch += "; the focus on the host";
  }
  epoch += "; encoding and hierarchy with their TBB switches on the host";
  ReferenceStages stages(true, false, std::move(kernels));
  return std::make_unique<StageBackend>(
      "vulkan",
      "on " + name + ": the T1/T2 impostor pass " +
          (mode == vk::ImpostorPass::Mode::kRaster ? "a graphics pipeline (a quad per impostor, one indirect draw)"
                                                     : "a compute shader over 16-pixel tiles") +
          " ray-casting in fp64 with the reference's intersections; the T-infinity field and composite a compute shader "
          "(fp64; rays beyond " + std::to_string(max_candidates) + " candidate nodes on the host), the neural field's "
          "network a compute pass at the samples it lists; the cull a compute pass over the hierarchy"
          + std::string(cull_on_the_device ? "" : " (off: R1_VULKAN_CULL=host)") +
          "; the edge tubes a compute pass over 16-pixel tiles" + std::string(edges_on_the_device ? "" : " (off: R1_VULKAN_EDGES=host)") +
          "; the splats' depth sort a radix sort on the device; bundling, splat binning and labels the reference's on "
          "the host; " + epoch + " (the reference's bytes)",
      std::move(stages), Domain::kFixedQ32, std::move(passes), std::move(device).value());
}

}  // namespace r1::backends
