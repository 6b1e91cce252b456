// The coordinate frame (R-1.0 4, decision 7, R1-FRM-001..039): sign convention, genesis scale to
// R_scene, the anchor file, similarity Procrustes alignment with SC-R.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "r1/fixedpoint/hemera.hpp"
#include "r1/format/anchor.hpp"
#include "r1/spec/anchor.hpp"
#include "r1/spec/epoch.hpp"
#include "r1/spec/epoch_options.hpp"
#include "r1/spec/snapshot.hpp"
#include "r1/spec/status.hpp"

namespace r1 {

// ---- sign convention (R1-FRM-001) -------------------------------------------------------------

// Makes the entry of largest magnitude of each u_2..u_6 positive (ties: lowest index); all-zero
// vectors stay. Returns which vectors were negated.
std::array<bool, 5> apply_sign_convention(Spectrum<Q32>& spectrum);
std::array<bool, 5> apply_sign_convention(Spectrum<double>& spectrum);
// The index of the entry that decides the sign of one vector (largest |x|, lowest index), or
// -1 when every entry is zero.
std::int64_t sign_pivot(std::span<const Q32> u);
std::int64_t sign_pivot(std::span<const double> u);

// ---- genesis (R1-FRM-010..013) ----------------------------------------------------------------

// Positions X' = s (u_2, u_3, u_4) with s = R_scene / max |X| (R1-FRM-010), from a
// sign-conventioned spectrum with `n` particles. Internal error when the spectrum's shape is wrong.
Result<Frame> genesis_frame(const Spectrum<Q32>& conventioned, std::uint32_t n);
// (u_2, u_3, u_4)(p) times `scale`, one rounding per coordinate (R1-FRM-010); a missing vector
// gives 0. Internal error when a coordinate leaves the Q32 range.
Result<std::vector<std::array<Q32, 3>>> scaled_positions(const std::array<std::vector<Q32>, 5>& u, std::size_t n, Q32 scale);

// ---- anchor file (R1-FRM-020..023) ------------------------------------------------------------
// The bytes (anchor_bytes, parse_anchor, anchor_digest) are the format library's,
// r1/format/anchor.hpp.

// The first anchor_count(|P|) particles with their positions in `frame`.
Anchor make_anchor(const Snapshot& snapshot, const Frame& frame);
Result<Anchor> read_anchor(const std::string& path);
// Reads the anchor file at `path` into options.anchor and names it options.anchor_name: the frame
// stage receives the anchor as a value (R1-BKD-014). An empty path leaves the options unchanged.
Status load_anchor(EpochOptions& options, const std::string& path);
// Writes atomically (R1-ERR-003) and returns the digest of the bytes written.
Result<hemera::Digest> write_anchor(const Anchor& anchor, const std::string& path);

// ---- Procrustes (R1-FRM-031..037) ---------------------------------------------------------------

// The SVD H = U diag(sigma) V^T of a 3x3 matrix by one-sided Jacobi (R1-FRM-032). Matrices are
// row-major; the columns of u and v are the singular vectors, sigma descending.
struct Svd3 {
  std::array<double, 9> u{}, v{};
  std::array<double, 3> sigma{};
  int sweeps = 0;
};
Svd3 svd3(const std::array<double, 9>& h);

// The similarity that maps `from` onto `to` (R1-FRM-031..035) and the transform applied to
// positions (R1-FRM-036).
struct Similarity {
  std::array<double, 9> rotation{1, 0, 0, 0, 1, 0, 0, 0, 1};  // R, row-major, det +1
  double scale = 1;
  std::array<double, 3> translation{};
  bool reflected = false;    // SC-R: the third axis of `from` is inverted before R applies
  bool planar = false;       // sigma_3 <= tau sigma_1: handedness not determined by the data
  bool collinear = false;    // sigma_2 <= tau sigma_1: spin about the line not determined
  bool translation_only = false;
  std::array<Q32, 9> m{};    // RNE(s R), row-major
  std::array<Q32, 3> t{};    // RNE(translation)
};
// `from` and `to` have equal length in 1..1024 (internal error otherwise); a coordinate beyond
// |raw| <= 2^52, or a transform that does not fit Q32, is an input error.
Result<Similarity> similarity_procrustes(std::span<const std::array<Q32, 3>> from, std::span<const std::array<Q32, 3>> to);
// Sets sim.m and sim.t from sim.scale, sim.rotation and sim.translation (R1-FRM-036); input error
// when they do not fit Q32.
Status set_applied_transform(Similarity& sim);
// The similarity an epoch's alignment records (not genesis), with the transform it applied: the
// same bits as the Procrustes solution that produced it.
Result<Similarity> similarity_of(const Alignment& a);
// X' = M (F y) + T with one rounding per coordinate; nullopt when it leaves the Q32 range.
std::optional<std::array<Q32, 3>> apply_similarity(const Similarity& sim, const std::array<Q32, 3>& y);

// ---- the frame stage --------------------------------------------------------------------------

// Minimum matched anchor particles for an alignment (R1-FRM-030).
inline constexpr std::uint32_t kMinAnchorMatches = 4;

// Genesis frame, then (when `anchor` is set) the Procrustes alignment to it (R1-FRM-030..038).
// `spectrum` must already be sign-conventioned. `anchor_name` names the anchor in messages.
Result<Frame> compute_frame(const Snapshot& snapshot, const Spectrum<Q32>& conventioned, const Anchor* anchor = nullptr,
                            const std::string& anchor_name = "anchor");

}  // namespace r1
