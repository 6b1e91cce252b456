// The stage list, written once (R-1.0 3-10; spec/backends.md R1-BKD-010..011, R1-BKD-014): the
// five epoch stages and the frame stage as one interface. The reference implements it
// (r1::ReferenceStages), every backend implements it (r1::backends::Backend), and the one epoch
// pipeline (r1::run_epoch) calls it. Arguments and results are spec/ values; errors are values.
#pragma once

#include <array>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "r1/spec/anchor.hpp"
#include "r1/spec/epoch.hpp"
#include "r1/spec/epoch_options.hpp"
#include "r1/spec/graph.hpp"
#include "r1/spec/image.hpp"
#include "r1/spec/progress.hpp"
#include "r1/spec/render_options.hpp"
#include "r1/spec/snapshot.hpp"
#include "r1/spec/status.hpp"
#include "r1/spec/view.hpp"

namespace r1 {

// The stages in pipeline order, by the names the epoch's timings and reports use.
enum class Stage { kSpectral, kFocus, kFrame, kEncoding, kHierarchy, kRender };
inline constexpr std::array<std::string_view, 6> kStageNames = {"spectral", "focus", "frame", "encoding", "hierarchy", "render"};
inline constexpr std::string_view stage_name(Stage s) { return kStageNames[static_cast<std::size_t>(s)]; }

// The epoch's computing stages (R-1.0 3, 4, 5, 10). Each is a pure function of its arguments.
class EpochStages {
 public:
  virtual ~EpochStages() = default;

  // The spectrum in the domain of `options.domain`, as Q32 (fp64 rounded entry by entry), before
  // the sign convention.
  virtual Result<Spectrum<Q32>> spectral(const Graph& graph, const EpochOptions& options, const ProgressFn& progress) = 0;
  // phi* in Q32 (an fp64 focus projected onto the Q32 simplex, R1-EPO-004).
  virtual Result<Focus<Q32>> focus(const Graph& graph, const EpochOptions& options, double lambda2,
                                   const ProgressFn& progress) = 0;
  // The local focus update of an incremental epoch (spec/incremental.md R1-INC-050..054): the same
  // steps on `region` (ascending) only, every other particle frozen at `start.phi` (one Q32 per
  // particle: the earlier epoch's phi, 0 for an added particle), the heat term from `start.heat`
  // (the earlier epoch's carried heat, likewise) and the syntropy from `start.plogp`. The start's
  // arrays are the update's to take over. Q32 domain only.
  virtual Result<Focus<Q32>> focus_update(const Graph& graph, const EpochOptions& options, double lambda2,
                                          Focus<Q32> start, std::span<const std::uint32_t> region,
                                          const ProgressFn& progress) = 0;
  // Genesis frame, then the alignment to `anchor` when set; `anchor_name` names it in messages.
  virtual Result<Frame> frame(const Snapshot& snapshot, const Spectrum<Q32>& conventioned, const Anchor* anchor,
                              const std::string& anchor_name) = 0;
  virtual Result<Encoding> encoding(const Snapshot& snapshot, const Graph& graph, const Focus<Q32>& focus,
                                    const Spectrum<Q32>& conventioned, const EncodingOptions& options,
                                    const ProgressFn& progress) = 0;
  virtual Result<Hierarchy> hierarchy(const std::vector<std::array<Q32, 3>>& pos, std::span<const Q32> phi,
                                      std::span<const Color> color, std::span<const ParticleId> ids,
                                      const HierarchyOptions& options, const ProgressFn& progress) = 0;
};

// The frame stage (R-1.0 6-9): `view` of `epoch` as linear premultiplied RGBA.
class FrameStage {
 public:
  virtual ~FrameStage() = default;
  virtual Result<render::Image> render(const Epoch& epoch, const render::View& view, const render::RenderOptions& options,
                                       render::FrameStats* stats, const ProgressFn& progress) = 0;
};

}  // namespace r1
