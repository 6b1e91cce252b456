// The T-infinity neural field (R-1.0 7; spec/neural.md R1-NRF-001..040): a multiresolution hash
// grid over the scene cube and a small MLP that maps (x, tau) to the analytic field's density,
// colour and flow, trained per epoch on samples of the analytic field (the oracle, field.hpp).
// 7.5's fall-back: no graph-context conditioning (r1 has no CT-0 model).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <span>
#include <string_view>
#include <vector>

#include "field.hpp"
#include "r1/fixedpoint/hemera.hpp"
#include "r1/spec/progress.hpp"
#include "r1/spec/status.hpp"

namespace r1::render {

// Architecture and training (R1-NRF-001..021). The defaults are r1's profile.
struct NeuralConfig {
  std::uint32_t levels = 16;        // L hash-grid levels
  std::uint32_t log2_table = 15;    // T = 2^15 entries per level (2 features each)
  std::uint32_t base_resolution = 16;
  std::uint32_t hidden = 64;        // two hidden layers of this width
  // The Clifford render block's channel width d between the two hidden layers (R1-NRF-003): 0 for
  // none (R-1.0 7.5's fall-back network), else hidden = 2 d (the first layer's halves are H and C).
  std::uint32_t block = 0;
  std::uint32_t samples = 1u << 16; // training set: points of the scene cube and tau range
  std::uint32_t batch = 1u << 11;
  std::uint32_t steps = 120;
  double lr_grid = 1e-2;            // Adam step of the hash-grid entries
  double lr_mlp = 1e-2;             // Adam step of the MLP (R-1.0 7.3 says 1e-3: R1-NRF-011)
  std::uint32_t threads = 0;        // 0: every core; the result does not depend on it
};

inline constexpr std::uint32_t kNeuralFeatures = 2;  // per hash-grid entry
inline constexpr std::uint32_t kNeuralOutputs = 7;   // density, colour (3), flow (3)
// The Clifford render block's shift set S (R-1.0 7.1 item 3).
inline constexpr std::array<std::int32_t, 5> kNeuralShifts = {1, 2, 4, 8, 16};

struct NeuralField {
  NeuralConfig config;
  std::vector<std::uint32_t> resolution;  // per level: grid cells per cube side
  Vec3 lo;                                // the cube [lo, lo + size]^3 the grid covers
  double size = 1;
  Vec3 centroid;                          // the scene's phi-weighted centroid (R1-NRF-005)
  double tau_lo = 1, tau_hi = 1;          // the trained tau range (R1-NRF-001, R1-NRF-005)
  double kappa = 0.25;                    // R1-RND-052's density gain
  // The Gaussian prior (R1-NRF-007, 008): the scene as isotropic Gaussians, one per occupied cell
  // of a grid over the particles' box; none in fields before version 3.
  struct PriorPart {
    double mass = 0, s2 = 0;          // the cell's far-field mass and spread per axis
    Vec3 centroid;                    // its weighted centroid
    Vec3 colour;                      // its mean colour and the colour's covariance with
    std::array<double, 9> gradient{}; // position (channel k, axis a at 3 k + a)
  };
  std::vector<PriorPart> prior_parts;
  // The grid the parts were made on: prior_cells per side of the box [prior_lo, prior_hi] (0 in
  // fields before version 4, whose one part is kept as it is).
  std::uint32_t prior_cells = 0;
  Vec3 prior_lo, prior_hi;
  // Whether some particle may lie within `reach` of x, from the parts alone (R1-NRF-033): a
  // part's particles share its grid cell, so each lies within a cell's diagonal of its centroid
  // (fields without the grid: the cube's diagonal). Never false where a particle is in reach.
  bool may_reach(const Vec3& x, double reach) const;
  // The prior at (x, sigma): its kernel sum, the parts' Gaussians convolved with the kernel (1 when
  // the field has none), and its colour over 3, each channel in [1e-3, 1 - 1e-3] (R1-NRF-008).
  struct PriorValue {
    double weight = 1;
    Vec3 colour;
  };
  PriorValue prior_at(const Vec3& x, double sigma) const;
  std::uint64_t seed = 0;                 // R1-NRF-020
  std::uint32_t fade_power = 4;           // the fine levels' fade exponent: 4 (2 in fields before version 3)
  std::vector<float> grid;                // levels x 2^log2_table x 2
  std::vector<float> w1, b1, w2, b2, w3, b3;  // row-major: w1 is hidden x inputs
  // The Clifford render block (config.block = d > 0; empty without it), row-major like the layers:
  // wc is d x (2 |S| d), wg is d x 2 d; gamma the residual scale (R1-NRF-003).
  std::vector<float> wc, bc, wg, bg, gamma;
  double loss_first = 0, loss_last = 0;   // mean training loss of the first and last step
  // Local updates since the field was trained whole (R1-NRF-050), and the last one's box (zero
  // when none).
  std::uint32_t local_updates = 0;
  Vec3 update_lo, update_hi;

  std::uint32_t inputs() const { return config.levels * kNeuralFeatures + 1; }
  // The field at x with kernel width sigma (tau = sigma^2), as field_hierarchical returns it
  // (weight: the kernel sum the density head predicts).
  FieldValue evaluate(const Vec3& x, double sigma) const;
};

// The field made ready for many evaluations (a frame's): each layer's weights input-major, so a
// layer's outputs share vector lanes while each output is still summed over its inputs in
// ascending order (R1-NRF-006). It gives NeuralField::evaluate's bits, which is built on it.
// Holds a reference to the field, which must outlive it.
class NeuralInference {
 public:
  explicit NeuralInference(const NeuralField& f);
  FieldValue evaluate(const Vec3& x, double sigma) const;

 private:
  const NeuralField& f_;
  std::vector<float> w1t_, w2t_, w3t_, wct_, wgt_;  // w[j][i] at [i * outputs + j]
};

// The field's value from the network's 7 raw outputs at (x, sigma) (R1-NRF-004, 007, 008): what
// a device that runs the layers itself decodes them to.
FieldValue decode_neural_outputs(const NeuralField& f, const float* outputs, const Vec3& x, double sigma);

// The training seed (R1-NRF-020): the first 8 bytes of Hemera(snapshot digest || "nrf").
std::uint64_t neural_seed(std::span<const std::uint8_t> snapshot_digest);

// Trains the field of a scene from its analytic far field (every particle at field weight n phi).
Result<NeuralField> train_neural_field(const Scene& s, const NeuralConfig& c, std::uint64_t seed,
                                       const ProgressFn& progress = {});

// A local update for an incremental epoch (R1-NRF-050): `prev`, trained for the earlier epoch, is
// trained further on `samples` points of scene s inside the box [lo, hi] (the changed particles'
// box, grown by the finest kernel's reach and kept inside the cube) for `steps` Adam steps. Only
// grid entries those points reach receive gradient; the MLP, the cube and the tau range stay.
Result<NeuralField> update_neural_field(const Scene& s, const NeuralField& prev, const Vec3& lo, const Vec3& hi,
                                        std::uint64_t seed, std::uint32_t samples, std::uint32_t steps,
                                        const ProgressFn& progress = {});

// What changed for the far field between two epochs of a chain (R1-NRF-050): comparable when
// both have the same particles in the same order (else `reason` says why not); `changed` counts
// the particles whose position, phi or colour differ, [lo, hi] bounds their old and new positions.
struct SceneChange {
  bool comparable = false;
  std::string reason;
  std::size_t changed = 0;
  Vec3 lo, hi;
};
SceneChange scene_change(std::span<const hemera::Digest> prev_ids, const Scene& prev, std::span<const hemera::Digest> next_ids,
                         const Scene& next);

// The analytic far field the field is trained on: every particle at weight n phi, walked over the
// hierarchy's nodes at their scene aggregates (kHierarchy, the frames' field: no FarTree) or over
// a spatial octree of the particles (kOctree, the training targets', R1-NRF-014).
enum class FarLayout { kHierarchy, kOctree };
FieldFrame far_field_frame(const Scene& s, const FieldParams& p = {}, FarLayout layout = FarLayout::kHierarchy);

namespace detail {
// The second layer's input from the first layer's output `h1` (config.hidden floats) into `x2`
// (as many): h1 itself without a block, [B | C] with one (R1-NRF-003). What NeuralInference runs.
void neural_block(const NeuralField& f, const float* h1, float* x2);
// The training loss of f on the first `points` points of the training set training would draw
// for scene s with `seed` (R1-NRF-010, 011; the batch mean of the points' terms) and its gradient
// with respect to the network's parameters in the order w1, b1, w2, b2, w3, b3, wc, bc, wg, bg,
// gamma, as a training step computes them: for checking the backward pass.
struct LossGradient {
  double loss = 0;
  std::vector<float> gradient;
};
LossGradient neural_loss_gradient(const Scene& s, const NeuralField& f, std::uint32_t points, std::uint64_t seed);
}  // namespace detail

// File bytes (R1-NRF-030) and back; `snapshot` is the digest of the snapshot the epoch was made from (R1-NRF-030).
std::string encode_neural_field(const NeuralField& f, std::span<const std::uint8_t> snapshot);
Result<NeuralField> decode_neural_field(std::string_view bytes, const std::string& name,
                                        std::span<const std::uint8_t> snapshot);

}  // namespace r1::render
