// The backend interface (R-1.0 section 13; spec/backends.md R1-BKD-001..030): the stage-level
// API every backend implements and the conformance harness drives, plus the section 13.1 trait
// for backends with GPU-like resources.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "r1/reference/epoch.hpp"
#include "r1/spec/epoch.hpp"
#include "r1/spec/status.hpp"
#include "render/renderer.hpp"

namespace r1::backends {

// 13.1 numeric_domain().
enum class Domain { kFp32, kFp64, kFixedQ32, kGoldilocks };
std::string_view domain_name(Domain d);

class Device;  // the 13.1 trait, device.hpp

// How many times each stage of a backend ran: the record that proves which backend did the work
// (R1-BKD-004). A backend counts its own calls; the harness reads them after a run.
struct StageCalls {
  std::uint64_t spectral = 0, focus = 0, frame = 0, encoding = 0, hierarchy = 0, render = 0;
  std::uint64_t total() const { return spectral + focus + frame + encoding + hierarchy + render; }
};

// The stage-level interface (R1-BKD-010). Every stage is a pure function of its arguments; the
// arguments and results are those of the reference stages (r1/reference/epoch.hpp EpochStages,
// r1::render::render_frame). Errors are values; no exception crosses this interface (R1-ERR-004).
class Backend {
 public:
  virtual ~Backend() = default;

  // The registry name ("reference", "null", ...).
  virtual std::string_view name() const = 0;
  // 13.1: the backend promises a fixed reduce order, no FMA contraction, fixed dispatch.
  virtual bool deterministic_mode() const = 0;
  virtual Domain numeric_domain() const = 0;
  // One line on what this backend is, for `r1 backends` and reports.
  virtual std::string_view summary() const = 0;

  // ---- epoch stages (R-1.0 3, 4, 5, 10) --------------------------------------------------
  virtual Result<Spectrum<Q32>> spectral(const Graph& graph, const EpochOptions& options, const ProgressFn& progress) = 0;
  virtual Result<Focus<Q32>> focus(const Graph& graph, const EpochOptions& options, double lambda2,
                                   const ProgressFn& progress) = 0;
  virtual Result<Frame> frame(const Snapshot& snapshot, const Spectrum<Q32>& conventioned, const Anchor* anchor,
                              const std::string& anchor_name) = 0;
  virtual Result<Encoding> encoding(const Snapshot& snapshot, const Graph& graph, const Focus<Q32>& focus,
                                    const Spectrum<Q32>& conventioned, const EncodingOptions& options,
                                    const ProgressFn& progress) = 0;
  virtual Result<Hierarchy> hierarchy(const std::vector<std::array<Q32, 3>>& pos, std::span<const Q32> phi,
                                      std::span<const Color> color, std::span<const ParticleId> ids,
                                      const HierarchyOptions& options, const ProgressFn& progress) = 0;

  // ---- frame stage (R-1.0 6-9) -----------------------------------------------------------
  // Renders `view` of `epoch` into linear premultiplied RGBA (r1::render::Image).
  virtual Result<render::Image> render(const Epoch& epoch, const render::View& view,
                                       const render::RenderOptions& options, render::FrameStats* stats) = 0;

  // The 13.1 trait, for a backend with GPU-like resources; nullptr when it has none.
  virtual Device* device() { return nullptr; }

  const StageCalls& calls() const { return calls_; }

 protected:
  StageCalls calls_;
};

// The epoch through `backend`'s stages, in the reference's order (R1-BKD-011): the one pipeline
// r1::run_epoch runs, with every stage replaced.
Result<Epoch> run_epoch(Backend& backend, const Snapshot& snapshot, const Graph& graph, const EpochOptions& options,
                        const ProgressFn& progress = {});

}  // namespace r1::backends
