// The backend interface (R-1.0 section 13; spec/backends.md R1-BKD-001..030, R1-BKD-014): the stage-level
// API every backend implements and the conformance harness drives, plus the section 13.1 trait
// for backends with GPU-like resources.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string_view>

#include "r1/spec/epoch.hpp"
#include "r1/spec/epoch_options.hpp"
#include "r1/spec/graph.hpp"
#include "r1/spec/progress.hpp"
#include "r1/spec/snapshot.hpp"
#include "r1/spec/stages.hpp"
#include "r1/spec/status.hpp"

namespace r1::backends {

// 13.1 numeric_domain().
enum class Domain { kFp32, kFp64, kFixedQ32, kGoldilocks };
std::string_view domain_name(Domain d);

class Device;  // the 13.1 trait, device.hpp

// How many times each stage of a backend ran: the record that proves which backend did the work
// (R1-BKD-004). A backend counts its own calls; the harness reads them after a run.
// Indexed by the stage list of r1/spec/stages.hpp, so a new stage needs no new field here.
struct StageCalls {
  std::array<std::uint64_t, kStageNames.size()> count{};
  std::uint64_t& operator[](Stage s) { return count[static_cast<std::size_t>(s)]; }
  std::uint64_t operator[](Stage s) const { return count[static_cast<std::size_t>(s)]; }
  std::uint64_t total() const {
    std::uint64_t t = 0;
    for (const std::uint64_t c : count) t += c;
    return t;
  }
};

// The stage-level interface (R1-BKD-010): the stage list of r1/spec/stages.hpp, written once,
// plus what names and describes a backend. Every stage is a pure function of its arguments; the
// arguments and results are spec/ values (R1-BKD-014). Errors are values; no exception crosses
// this interface (R1-ERR-004).
class Backend : public EpochStages, public FrameStage {
 public:
  // The registry name ("reference", "null", ...).
  virtual std::string_view name() const = 0;
  // 13.1: the backend promises a fixed reduce order, no FMA contraction, fixed dispatch.
  virtual bool deterministic_mode() const = 0;
  virtual Domain numeric_domain() const = 0;
  // One line on what this backend is, for `r1 backends` and reports.
  virtual std::string_view summary() const = 0;

  // The 13.1 trait, for a backend with GPU-like resources; nullptr when it has none.
  virtual Device* device() { return nullptr; }

  const StageCalls& calls() const { return calls_; }

 protected:
  StageCalls calls_;
};

// The epoch through `backend`'s stages, in the reference's order (R1-BKD-011): the one pipeline
// r1::run_epoch runs, with every stage the backend's (backends/pipeline.cpp).
Result<Epoch> run_epoch(Backend& backend, const Snapshot& snapshot, const Graph& graph, const EpochOptions& options,
                        const ProgressFn& progress = {});

}  // namespace r1::backends
