// The self-test backends (R1-BKD-022): the reference with one contract broken each, so the
// conformance suite shows that it catches that break and names it.
//   selftest-position: every position moved by 2e-3 R_scene along +x (fails P_RENDER_POS)
//   selftest-topology: the ids of the first two level-0 clusters swapped (fails P_RENDER_TOPO)
//   selftest-hue:      every rendered pixel's hue turned by 60 degrees (fails P_RENDER_PIX)
#include <cmath>
#include <utility>

#include "adapters.hpp"

namespace r1::backends {

namespace {

// Twice the position bound: 15.2 allows 1e-3 R_scene.
constexpr std::int64_t kShiftUnits = 2 * kSceneRadius / 1000;

// Swaps level-0 clusters a and b everywhere they are named: a consistent tree whose labels are
// no longer canonical.
void swap_clusters(Hierarchy& h, std::uint32_t a, std::uint32_t b) {
  auto& nodes = h.levels[0];
  std::swap(nodes[a], nodes[b]);
  nodes[a].id = a;
  nodes[b].id = b;
  for (auto& c : h.cluster_of[0]) c = c == a ? b : (c == b ? a : c);
  for (auto& parent : h.levels[1])
    for (auto& c : parent.children) c = c == a ? b : (c == b ? a : c);
}

// Rotates a linear RGB colour about the grey axis by `deg` (Rodrigues): the same luminance-ish
// brightness, another hue.
void rotate_hue(float* rgb, double deg) {
  const double t = deg * 3.14159265358979323846 / 180.0;
  const double c = std::cos(t), s = std::sin(t), k = 1.0 / 3.0;
  const double sq = std::sqrt(k);
  const double r = static_cast<double>(rgb[0]), g = static_cast<double>(rgb[1]), b = static_cast<double>(rgb[2]);
  const double m0 = c + (1 - c) * k, m1 = (1 - c) * k - sq * s, m2 = (1 - c) * k + sq * s;
  rgb[0] = static_cast<float>(m0 * r + m1 * g + m2 * b);
  rgb[1] = static_cast<float>(m2 * r + m0 * g + m1 * b);
  rgb[2] = static_cast<float>(m1 * r + m2 * g + m0 * b);
}

class SelfTestBackend final : public Backend {
 public:
  explicit SelfTestBackend(SelfTestFault f) : fault_(f), inner_(make_reference_backend()) {}

  std::string_view name() const override { return self_test_name(fault_); }
  std::string_view summary() const override { return self_test_summary(fault_); }
  bool deterministic_mode() const override { return true; }
  Domain numeric_domain() const override { return Domain::kFixedQ32; }

  Result<Spectrum<Q32>> spectral(const Graph& g, const EpochOptions& o, const ProgressFn& p) override {
    ++calls_[Stage::kSpectral];
    return inner_->spectral(g, o, p);
  }
  Result<Focus<Q32>> focus(const Graph& g, const EpochOptions& o, double l2, const ProgressFn& p) override {
    ++calls_[Stage::kFocus];
    return inner_->focus(g, o, l2, p);
  }
  Result<Focus<Q32>> focus_update(const Graph& g, const EpochOptions& o, double l2, Focus<Q32> start,
                                  std::span<const std::uint32_t> region, const ProgressFn& p) override {
    ++calls_[Stage::kFocus];
    return inner_->focus_update(g, o, l2, std::move(start), region, p);
  }
  Result<Frame> frame(const Snapshot& s, const Spectrum<Q32>& c, const Anchor* a, const std::string& an) override {
    ++calls_[Stage::kFrame];
    R1_ASSIGN(Frame f, inner_->frame(s, c, a, an));
    if (fault_ == SelfTestFault::kPosition)
      for (auto& x : f.position) x[0] = x[0] + Q32::from_int(kShiftUnits);
    return f;
  }
  Result<Encoding> encoding(const Snapshot& s, const Graph& g, const Focus<Q32>& f, const Spectrum<Q32>& c,
                            const EncodingOptions& o, const ProgressFn& p) override {
    ++calls_[Stage::kEncoding];
    return inner_->encoding(s, g, f, c, o, p);
  }
  Result<Hierarchy> hierarchy(const std::vector<std::array<Q32, 3>>& pos, std::span<const Q32> phi,
                              std::span<const Color> color, std::span<const ParticleId> ids,
                              const HierarchyOptions& o, const ProgressFn& p) override {
    ++calls_[Stage::kHierarchy];
    R1_ASSIGN(Hierarchy h, inner_->hierarchy(pos, phi, color, ids, o, p));
    if (fault_ == SelfTestFault::kTopology && h.levels[0].size() >= 2) swap_clusters(h, 0, 1);
    return h;
  }
  Result<render::Image> render(const Epoch& e, const render::View& v, const render::RenderOptions& o,
                               render::FrameStats* stats, const ProgressFn& progress) override {
    ++calls_[Stage::kRender];
    R1_ASSIGN(render::Image img, inner_->render(e, v, o, stats, progress));
    if (fault_ == SelfTestFault::kHue)
      for (std::size_t i = 0; i + 3 < img.rgba.size(); i += 4) rotate_hue(&img.rgba[i], 60.0);
    return img;
  }

 private:
  SelfTestFault fault_;
  std::unique_ptr<Backend> inner_;
};

}  // namespace

std::string_view self_test_name(SelfTestFault f) {
  switch (f) {
    case SelfTestFault::kPosition: return "selftest-position";
    case SelfTestFault::kTopology: return "selftest-topology";
    case SelfTestFault::kHue: return "selftest-hue";
  }
  return "selftest";
}

std::string_view self_test_summary(SelfTestFault f) {
  switch (f) {
    case SelfTestFault::kPosition: return "reference with every position moved by 2e-3 R_scene (must fail P_RENDER_POS)";
    case SelfTestFault::kTopology: return "reference with two level-0 cluster ids swapped (must fail P_RENDER_TOPO)";
    case SelfTestFault::kHue: return "reference with every pixel's hue turned 60 degrees (must fail P_RENDER_PIX)";
  }
  return "";
}

std::unique_ptr<Backend> make_self_test_backend(SelfTestFault f) { return std::make_unique<SelfTestBackend>(f); }

}  // namespace r1::backends
