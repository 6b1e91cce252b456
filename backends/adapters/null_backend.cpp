// The null backend (R1-BKD-021): always built, every stage returns data of the right shape that
// passes the epoch's structural checks but is wrong, so the conformance suite can show that it
// fails every check. It never calls a reference stage.
#include <algorithm>

#include "adapters.hpp"

namespace r1::backends {

namespace {

class NullBackend final : public Backend {
 public:
  std::string_view name() const override { return "null"; }
  std::string_view summary() const override { return "well-formed, wrong results (fails the suite by design)"; }
  bool deterministic_mode() const override { return true; }
  Domain numeric_domain() const override { return Domain::kFixedQ32; }

  Result<Spectrum<Q32>> spectral(const Graph& g, const EpochOptions& o, const ProgressFn&) override {
    ++calls_[Stage::kSpectral];
    Spectrum<Q32> s;
    s.n = g.n;
    s.rho = o.spectral.rho.value_or(0.0);
    s.found = std::min<std::uint32_t>(5, g.n > 0 ? g.n - 1 : 0);
    for (auto& u : s.u) u.assign(g.n, Q32{});  // all zero: no layout information at all
    return s;
  }
  Result<Focus<Q32>> focus(const Graph& g, const EpochOptions&, double, const ProgressFn&) override {
    ++calls_[Stage::kFocus];
    // Uniform focus whose raws still sum to exactly 2^32 (well-formed, R1-FOC-010): the
    // largest-remainder share of equal weights, floor(2^32 / n) each and one more raw for the
    // first 2^32 mod n particles (equal remainders go to the lower index).
    Focus<Q32> f;
    const std::uint64_t total = std::uint64_t{1} << 32;
    for (std::uint64_t i = 0; i < g.n; ++i)
      f.phi.push_back(Q32::from_raw(static_cast<std::int64_t>(total / g.n + (i < total % g.n ? 1 : 0))));
    for (std::uint32_t i = 0; i < g.n && i < kCyberankPlaces; ++i) f.cyberank.push_back(i);
    return f;
  }
  Result<Focus<Q32>> focus_update(const Graph& g, const EpochOptions& o, double l2, Focus<Q32>,
                                  std::span<const std::uint32_t>, const ProgressFn& p) override {
    return focus(g, o, l2, p);  // the same uniform focus: no graph information either way
  }
  Result<Frame> frame(const Snapshot& s, const Spectrum<Q32>&, const Anchor*, const std::string&) override {
    ++calls_[Stage::kFrame];
    // Particles scattered over a fixed integer lattice inside |x|, |y|, |z| <= 500, by index
    // alone: right shape and range, unrelated to the graph.
    Frame f;
    f.scale = 1;
    const std::uint64_t n = s.particles.size();
    for (std::uint64_t i = 0; i < n; ++i)
      f.position.push_back({Q32::from_int(static_cast<std::int64_t>((i * 37) % 1001) - 500),
                            Q32::from_int(static_cast<std::int64_t>((i * 101) % 1001) - 500),
                            Q32::from_int(static_cast<std::int64_t>((i * 211) % 1001) - 500)});
    return f;
  }
  Result<Encoding> encoding(const Snapshot& s, const Graph&, const Focus<Q32>& focus, const Spectrum<Q32>&,
                            const EncodingOptions& o, const ProgressFn&) override {
    ++calls_[Stage::kEncoding];
    const std::size_t n = s.particles.size();
    Encoding e;
    e.overlay = o.overlay;
    e.radius.assign(n, Q32::from_int(4));
    // Luminosity still sums to exactly 1 (L0), the invariant readers check.
    e.luminosity = focus.phi;
    e.hue.assign(n, Q32{});
    e.saturation.assign(n, Q32{});
    e.role.assign(n, Role::kNone);
    e.shape.assign(n, Shape::kSphere);
    e.color.assign(n, {128, 128, 128});
    return e;
  }
  Result<Hierarchy> hierarchy(const std::vector<std::array<Q32, 3>>& pos, std::span<const Q32> phi,
                              std::span<const Color>, std::span<const ParticleId>, const HierarchyOptions&,
                              const ProgressFn&) override {
    ++calls_[Stage::kHierarchy];
    // Runs of 16 consecutive particles, then runs of 16 consecutive clusters: a valid tree with
    // at most 16 children that ignores the geometry.
    Hierarchy h;
    const std::size_t n = pos.size();
    for (int l = 0; l < kLevels; ++l) {
      const std::size_t below = l == 0 ? n : h.levels[l - 1].size();
      h.radius_raw[l] = std::int64_t{1} << (32 + l);
      for (std::size_t c = 0; c * kMaxChildren < below; ++c) {
        ClusterNode node;
        node.level = static_cast<std::uint32_t>(l);
        node.id = static_cast<std::uint32_t>(c);
        node.color = {128, 128, 128};
        const std::size_t end = std::min(below, (c + 1) * kMaxChildren);
        for (std::size_t k = c * kMaxChildren; k < end; ++k) node.children.push_back(static_cast<std::uint32_t>(k));
        h.levels[l].push_back(std::move(node));
      }
    }
    h.cluster_of[0].resize(n);
    for (std::size_t i = 0; i < n; ++i) h.cluster_of[0][i] = static_cast<std::uint32_t>(i / kMaxChildren);
    for (int l = 1; l < kLevels; ++l) {
      h.cluster_of[l].resize(n);
      for (std::size_t i = 0; i < n; ++i) h.cluster_of[l][i] = h.cluster_of[l - 1][i] / kMaxChildren;
      for (auto& child : h.levels[l - 1]) child.parent = child.id / kMaxChildren;
    }
    // Aggregates bottom up, so the tree is well-formed for the renderer and the epoch files.
    for (std::size_t i = 0; i < n; ++i) {
      for (int l = 0; l < kLevels; ++l) {
        ClusterNode& node = h.levels[l][h.cluster_of[l][i]];
        if (node.particles == 0) node.lo = node.hi = pos[i];
        for (int a = 0; a < 3; ++a) {
          node.lo[a] = std::min(node.lo[a], pos[i][a]);
          node.hi[a] = std::max(node.hi[a], pos[i][a]);
        }
        node.phi_raw += phi[i].raw;
        ++node.particles;
      }
    }
    return h;
  }
  Result<render::Image> render(const Epoch&, const render::View& v, const render::RenderOptions&,
                               render::FrameStats*, const ProgressFn&) override {
    ++calls_[Stage::kRender];
    return render::Image(v.width, v.height);  // nothing drawn: the background alone
  }
};

}  // namespace

std::unique_ptr<Backend> make_null_backend() { return std::make_unique<NullBackend>(); }

}  // namespace r1::backends
