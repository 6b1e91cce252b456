// The adapter over the reference's stage list (R1-BKD-020, R1-BKD-040): a backend whose epoch
// stages are ReferenceStages (with the switches and kernels it was made with) and whose frame is
// the reference renderer; it counts its calls (R1-BKD-004). Internal to backends/adapters.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "r1/backends/backend.hpp"
#include "r1/backends/device.hpp"
#include "r1/reference/epoch.hpp"
#include "render/neural_field.hpp"
#include "render/renderer.hpp"
#include "render/scene.hpp"

namespace r1::backends {

class StageBackend final : public Backend {
 public:
  StageBackend(std::string name, std::string summary, ReferenceStages stages, Domain domain)
      : name_(std::move(name)), summary_(std::move(summary)), stages_(std::move(stages)), domain_(domain) {}
  // With frame passes of its own (render/passes.hpp; the reference's where `passes` has none) and
  // a 13.1 device.
  StageBackend(std::string name, std::string summary, ReferenceStages stages, Domain domain, render::FramePasses passes,
               std::unique_ptr<Device> device)
      : StageBackend(std::move(name), std::move(summary), std::move(stages), domain) {
    passes_ = std::move(passes);
    device_ = std::move(device);
  }

  std::string_view name() const override { return name_; }
  std::string_view summary() const override { return summary_; }
  bool deterministic_mode() const override { return true; }
  // The canonical epoch is Q32 (fp64 for the fp64 backend's spectral and focus stages); the frame
  // is fp64 either way (pixels are not canonical, R-1.0 12.3).
  Domain numeric_domain() const override { return domain_; }
  Device* device() override { return device_.get(); }

  Result<Spectrum<Q32>> spectral(const Graph& g, const EpochOptions& o, const ProgressFn& p) override {
    ++calls_[Stage::kSpectral];
    return stages_.spectral(g, o, p);
  }
  Result<Focus<Q32>> focus(const Graph& g, const EpochOptions& o, double lambda2, const ProgressFn& p) override {
    ++calls_[Stage::kFocus];
    return stages_.focus(g, o, lambda2, p);
  }
  Result<Focus<Q32>> focus_update(const Graph& g, const EpochOptions& o, double lambda2, Focus<Q32> start,
                                  std::span<const std::uint32_t> region, const ProgressFn& p) override {
    ++calls_[Stage::kFocus];
    return stages_.focus_update(g, o, lambda2, std::move(start), region, p);
  }
  Result<Frame> frame(const Snapshot& s, const Spectrum<Q32>& c, const Anchor* a, const std::string& an) override {
    ++calls_[Stage::kFrame];
    return stages_.frame(s, c, a, an);
  }
  Result<Encoding> encoding(const Snapshot& s, const Graph& g, const Focus<Q32>& f, const Spectrum<Q32>& c,
                            const EncodingOptions& o, const ProgressFn& p) override {
    ++calls_[Stage::kEncoding];
    return stages_.encoding(s, g, f, c, o, p);
  }
  Result<Hierarchy> hierarchy(const std::vector<std::array<Q32, 3>>& pos, std::span<const Q32> phi,
                              std::span<const Color> color, std::span<const ParticleId> ids,
                              const HierarchyOptions& o, const ProgressFn& p) override {
    ++calls_[Stage::kHierarchy];
    return stages_.hierarchy(pos, phi, color, ids, o, p);
  }
  Result<render::Image> render(const Epoch& e, const render::View& v, const render::RenderOptions& o,
                               render::FrameStats* stats, const ProgressFn& progress) override {
    ++calls_[Stage::kRender];
    // The scene is built once per epoch and reused across views. It borrows the epoch's
    // hierarchy, so the key includes that storage's address besides the epoch's own and its
    // snapshot digest: a different epoch never reuses a stale scene.
    const Key key{&e, e.hierarchy.levels[0].data(), e.snapshot_digest};
    if (!scene_ || !(key_ == key)) {
      scene_ = render::make_scene(e);
      key_ = key;
      neural_.reset();
    }
    // The trained field (R1-NRF-031), decoded once per epoch and set of bytes.
    scene_->neural = nullptr;
    if (!o.neural_field.empty()) {
      if (!neural_ || neural_bytes_ != o.neural_field) {
        auto f = render::decode_neural_field(o.neural_field, "field.nrf", e.snapshot_digest);
        if (!f) return f.status();
        neural_ = std::move(f).value();
        neural_bytes_ = std::string(o.neural_field);
      }
      scene_->neural = &*neural_;
    }
    return render::render_frame(*scene_, v, o, stats, progress, passes_);
  }

 private:
  struct Key {
    const Epoch* epoch = nullptr;
    const ClusterNode* nodes = nullptr;
    hemera::Digest digest{};
    bool operator==(const Key&) const = default;
  };
  std::string name_, summary_;
  ReferenceStages stages_;
  Domain domain_;
  render::FramePasses passes_;
  std::unique_ptr<Device> device_;
  std::optional<render::Scene> scene_;
  Key key_;
  std::optional<render::NeuralField> neural_;
  std::string neural_bytes_;
};


}  // namespace r1::backends
