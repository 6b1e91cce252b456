// The data an epoch computes (R-1.0 sections 3, 4, 5, 10; spec/epoch.md): parameters with their
// defaults and the results of each stage. Every stage is a pure function of its inputs; the
// canonical numeric domain is Q32 (decision 5), fp64 is the second domain.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "r1/fixedpoint/exact_sum.hpp"
#include "r1/fixedpoint/hemera.hpp"
#include "r1/fixedpoint/q32.hpp"
#include "r1/spec/snapshot.hpp"

namespace r1 {

using fx::Q32;

enum class NumericDomain { kQ32, kFp64 };

// ---- focus (tri-kernel, REFERENCE.md 2) ------------------------------------------------------

struct TriKernelParams {
  // Defaults of the tru reference code; every one is a command-line option of `r1 epoch`.
  Q32 lambda_d = Q32::from_decimal("0.5");   // diffusion weight
  Q32 lambda_s = Q32::from_decimal("0.3");   // springs weight
  Q32 lambda_h = Q32::from_decimal("0.2");   // heat weight
  Q32 teleport = Q32::from_decimal("0.15");  // diffusion teleport t
  Q32 mu = Q32::from_int(1);                 // springs screening
  Q32 tau = Q32::from_int(1);                // heat time
  Q32 eps = Q32::from_decimal("0.000001");   // target error for T(eps)
  std::uint32_t max_steps = 500;             // cap on T(eps)
  std::uint32_t chebyshev_degree = 8;        // heat kernel polynomial degree K
};

// The places of the cyberank order a focus keeps (R1-FOC-070): the manifest names ten, the
// terminal five; phi holds the rest of the order.
inline constexpr std::uint32_t kCyberankPlaces = 1024;

template <class Scalar>  // fx::Q32 (canonical) or double
struct Focus {
  std::vector<Scalar> phi;        // per particle, canonical order. Q32: raws sum to exactly 2^32, all > 0
  std::uint32_t steps = 0;        // T(eps) actually run
  double kappa = 0;               // contraction estimate that fixed T(eps)
  double lambda_max = 0;          // bound 2 max d on the largest eigenvalue of L = D - A_sym (Gershgorin, R1-FOC-060)
  double syntropy = 0;            // KL(phi || uniform), nats
  // The first min(n, kCyberankPlaces) particle indices by phi descending, ties by lower index
  // (R1-FOC-070).
  std::vector<std::uint32_t> cyberank;
  // Q32: phi is known to hold the invariant above (raws summing to exactly 2^32, each at least 1):
  // set by the focus stages and by read_epoch after checking, so that a local update (R1-INC-051)
  // need not pass over every particle to find the frozen mass.
  bool on_simplex = false;
  // Q32: sum_i phi_i fx::log(phi_i), exact (units of 2^-64, R1-FOC-071), which syntropy rounds
  // with ln n added. Carried in the manifest so that an incremental epoch updates it on its
  // region (R1-INC-054); unset in the fp64 domain and for an epoch read without it.
  std::optional<fx::ExactSum> plogp;
  // The heat term H(phi) of the result (R1-FOC-043 applied to phi; Q32 with lambda_h > 0, else
  // empty): what the next incremental epoch's local update starts from (spec/incremental.md
  // R1-INC-052).
  std::vector<Scalar> heat;
};

// ---- spectral embedding (R-1.0 3) ------------------------------------------------------------

struct SpectralParams {
  std::optional<double> rho;      // regularisation (decision 4); unset = auto: 0 if connected, else mean weighted degree
  std::uint32_t basis = 14;       // block Krylov steps per restart cycle, 7 vectors each (R1-SPEC-021)
  double tolerance = 1e-9;        // residual target ||L u - lambda u|| for the wanted pairs
  std::uint32_t max_restarts = 0; // 0 = the solver's documented default
  std::uint32_t filter_degree = 12; // Chebyshev filter after the first cycle, 0 or 1: none (R1-SPEC-080)
};

template <class Scalar>
struct Spectrum {
  std::uint32_t n = 0;
  double rho = 0;                             // the regularisation actually used
  std::array<double, 6> eigenvalues{};        // lambda_1..lambda_6 of the normalized Laplacian (lambda_1 = 0)
  std::array<double, 6> residuals{};          // ||L u - lambda u|| of each (u_1 = D^(1/2) 1 normalised)
  std::array<std::vector<Scalar>, 5> u;       // u_2..u_6, unit 2-norm, per particle; missing ones all 0
  std::uint32_t found = 0;                    // how many of u_2..u_6 exist (n - 1 when n < 7)
  // Work done, for the manifest: restarts, vectors L~ was applied to, and block applications
  // (passes over the operator, each for a block of up to 7 vectors) (R1-SPEC-063).
  std::uint32_t restarts = 0, matvecs = 0, passes = 0;
  // What an incremental epoch carries instead of passing over every particle (spec/incremental.md
  // R1-INC-038; Q32 only). For each stored vector c, x = u_c's raws times 2^sums_shift:
  // image[i * 5 + c] = the exact numerator x_i 2^32 - sum_k M_ik x_k of row i of L~ x (R1-SPEC-005
  // before its one rounding, y_i = RNE(numerator / 2^32)), and sums[c] = {sum x_i^2, sum x_i y_i,
  // sum y_i^2} in raws squared. sums_shift < 0: none (fp64, fewer than 5 vectors, rho > 0).
  int sums_shift = -1;
  std::array<std::array<fx::ExactSum, 3>, 5> sums{};
  std::vector<i128> image;
};

// ---- frame (R-1.0 4, decision 7) ---------------------------------------------------------------

inline constexpr std::int64_t kSceneRadius = 1000;  // R_scene

struct Alignment {
  bool genesis = true;               // no anchor given: sign convention + scale only
  std::array<double, 9> rotation{};  // row-major Q (right-handed after SC-R)
  double scale = 1;                  // s
  std::array<double, 3> translation{};
  bool reflected = false;            // SC-R flipped the third axis
  std::uint32_t matched = 0;         // anchor particles found in this snapshot
  double rms = 0;                    // RMS distance over the matched anchor after alignment
};

struct Frame {
  std::vector<std::array<Q32, 3>> position;  // X'(p), scene units (|X'| <= R_scene at genesis)
  double scale = 0;                          // R_scene / max |X(p)| applied to the raw eigenvectors
  Alignment alignment;
};

// ---- visual encoding (R-1.0 5) ---------------------------------------------------------------

enum class Role : std::uint8_t { kNone = 0, kHub = 1, kBridge = 2, kLeaf = 3 };
enum class Shape : std::uint8_t { kSphere = 0, kTorus = 1, kTetrahedron = 2, kCube = 3, kOctahedron = 4, kCylinder = 5 };

struct Encoding {
  std::vector<Q32> radius;                     // r0 sqrt(phi) (times the overlay's size multiplier)
  std::vector<Q32> luminosity;                 // L0 phi: raws sum to exactly L0's raw
  std::vector<Q32> hue;                        // turns in [0, 1): angle of (u5, u6) / 2 pi
  std::vector<Q32> saturation;                 // [0, 1]
  std::vector<Role> role;
  std::vector<Shape> shape;
  std::vector<std::array<std::uint8_t, 3>> color;  // display sRGB, 8 bits per channel
  std::string overlay = "none";                // none | crystal-v5 | custom
  std::string radius_scale = "scene";          // how r_0 was chosen: spacing | scene (R1-ENC-007..008)
  std::int64_t r0_squared_raw = kSceneRadius * kSceneRadius * (std::int64_t{1} << 32);  // r_0^2, Q32 raw
  // b(p) of R1-ENC-012..014 behind the roles (empty when role shapes are off): an incremental
  // epoch carries it instead of computing it again (R1-INC-037).
  std::vector<double> betweenness;
};

// ---- hierarchy (R-1.0 10) ----------------------------------------------------------------------

inline constexpr int kLevels = 4;
inline constexpr int kMaxChildren = 16;

struct ClusterNode {
  std::uint32_t level = 0;                 // 0 finest .. 3 coarsest
  std::uint32_t id = 0;                    // canonical id within the level (R-1.0 10.2)
  std::uint32_t parent = 0xFFFFFFFFu;      // id at level + 1; none for level 3
  std::vector<std::uint32_t> children;     // level 0: particle indices; else ids at level - 1; <= 16
  std::array<Q32, 3> lo{}, hi{};           // AABB of the contained particles' positions
  std::int64_t phi_raw = 0;                // sum of the members' Q32 phi raws (exact)
  std::array<std::uint8_t, 3> color{};     // dominant colour (R-1.0 10.1)
  std::uint32_t particles = 0;             // members (all levels below)
};

struct Hierarchy {
  std::array<std::vector<ClusterNode>, kLevels> levels;            // index = canonical id
  std::array<std::vector<std::uint32_t>, kLevels> cluster_of;      // per particle: its cluster id per level
  std::array<std::int64_t, kLevels> radius_raw{};                  // clustering radius per level (Q32 raw, scene units)
  double tau0 = 0;                                                 // the finest heat-kernel scale used
};

}  // namespace r1

// ---- the epoch as a whole (spec/epoch.md) -------------------------------------------------------

namespace r1 {

// One undirected pair of the layout graph (R1-EPO-011 edges.bin): the edges the renderer draws
// (R-1.0 8). p < q; w_raw is A_sym(p, q) in Q32 (in (0, 1]); a2_raw is A2(p, q) in Q32, the
// bivector oriented p -> q (|a2| <= w).
struct LayoutEdge {
  std::uint32_t p = 0, q = 0;
  std::int64_t w_raw = 0;
  std::int64_t a2_raw = 0;
  bool operator==(const LayoutEdge&) const = default;
};

// How an epoch computed from an earlier one came about (R1-INC-040, spec/incremental.md): the
// edit batch, the neighbourhood N_h, whether the spectral stage was updated locally or solved in
// full, and the certificate. Present only in epochs made with `r1 epoch --from`.
struct UpdateInfo {
  bool incremental = false;          // positions updated on N_h; false: a full solve
  std::string reason;                // why a full solve ran ("" when incremental)
  std::uint32_t epochs_since_full = 0;
  std::uint32_t hops = 0;            // h
  std::uint64_t touched = 0;         // particles whose row of the layout graph changed (new ones included)
  std::uint64_t added = 0, dropped = 0;
  std::uint64_t resized_since_full = 0;  // particles added or dropped since the last full solve
  std::uint64_t region = 0;          // |N_h|
  std::uint64_t rows = 0;            // |N_(h+1)|: the rows the local update reads (R1-INC-031)
  bool focus_local = false;          // phi updated on N_h only (R1-INC-050); false: the full iteration
  bool certified = false;            // incremental with certificate <= eps_x (false: kept by --keep-local)
  bool betweenness_carried = false;  // roles from the earlier epoch's betweenness (R1-INC-037)
  bool hierarchy_radius_kept = false;  // the hierarchy built at the earlier epoch's r_0, no search (R1-INC-035)
  bool radius_scale_kept = false;      // the encoding's r_0 the earlier epoch's, not measured again (R1-INC-035)
  double delta_norm = 0;             // bound on ||L~_next - L~_prev||_2 of this batch
  double delta_norm_since_full = 0;  // the bound summed since the last full solve
  std::array<double, 6> full_eigenvalues{}, full_residuals{};  // of the last full solve
  // Per u_2..u_6: a bound on ||u - u*|| (u* the exact unit eigenvector of L~_next, sign-matched);
  // infinity where none holds (u_6: the solve does not bound lambda_7).
  std::array<double, 5> vector_bound{};
  double certificate = 0;            // bound on the position error, scene units (infinity: none)
  double eps_x = 0;                  // the bound an incremental epoch must meet, scene units
};

struct StageTiming {
  std::string stage;
  double seconds = 0;
};

// Everything an epoch publishes (R1-EPO-010): what `r1 epoch` writes and `read_epoch` returns.
struct Epoch {
  std::string source;                      // snapshot path as given
  hemera::Digest snapshot_digest{};        // R1-IN-040
  RecordChunks record_chunks;              // per chunk of the record stream: SHA-256 and leaf (R1-EPO-017)
  NumericDomain domain = NumericDomain::kQ32;
  std::vector<hemera::Digest> ids;         // particles, canonical order
  std::vector<std::string> titles;         // display title per particle ("" = none)
  std::uint64_t links = 0;
  std::uint64_t components = 0;
  TriKernelParams trikernel;
  SpectralParams spectral_params;
  Focus<Q32> focus;                        // Q32 whatever the domain (fp64 phi projected, R1-EPO-004)
  Spectrum<Q32> spectrum;                  // u_2..u_6 after the sign convention
  Frame frame;
  Encoding encoding;
  Hierarchy hierarchy;
  std::vector<LayoutEdge> edges;           // layout graph pairs, by (p, q) ascending
  std::vector<std::uint64_t> out_rows;     // per particle: digest of its directed A0 row (R1-EPO-011)
  std::vector<StageTiming> timings;
  std::optional<UpdateInfo> update;        // epochs made from an earlier one (r1 epoch --from)
};

}  // namespace r1
