// The visual encoding (R-1.0 5, R1-ENC-001..050): radius, luminosity, hue, saturation, colour,
// roles from degree and betweenness, shapes, and the metadata overlays.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "r1/spec/epoch.hpp"
#include "r1/spec/epoch_options.hpp"
#include "r1/spec/graph.hpp"
#include "r1/spec/overlay.hpp"
#include "r1/spec/progress.hpp"
#include "r1/spec/snapshot.hpp"
#include "r1/spec/status.hpp"

namespace r1 {

using Rgb8 = std::array<std::uint8_t, 3>;

// ---- colour (R1-ENC-005..006) ----------------------------------------------------------------

// Lightness of the schemaless base colour, per mille (R1-ENC-005).
inline constexpr std::uint32_t kBaseLightnessPermille = 550;

// HSL to 8-bit display sRGB with one rounding per channel (R1-ENC-006). `hue_sixths` is 6 x hue
// in turns, in [0, 6); `saturation` in [0, 1]; lightness in per mille, 0..1000.
Rgb8 hsl_to_srgb8(Q32 hue_sixths, Q32 saturation, std::uint32_t lightness_permille);

// ---- schemaless fields (R1-ENC-001..004) --------------------------------------------------------

// r_0^2 = R_scene^2 as a Q32 raw: R-1.0's scene-scale constant as r1 fixed it before R1-ENC-007.
inline constexpr std::int64_t kSceneR0SquaredRaw = kSceneRadius * kSceneRadius * (std::int64_t{1} << 32);

// r_0 sqrt(phi) x multiplier (R1-ENC-001), r_0^2 given as a Q32 raw (> 0, at most R_scene^2).
Q32 radius_of(Q32 phi, Q32 multiplier = Q32::one(), std::int64_t r0_squared_raw = kSceneR0SquaredRaw);

// r_0 from the layout (R1-ENC-007): the median particle's radius half the median spacing between
// distinct positions.
struct RadiusScale {
  std::int64_t r0_squared_raw = kSceneR0SquaredRaw;
  std::uint64_t distinct = 0;  // distinct positions
  u128 spacing2 = 0;           // the median squared spacing, exact (Q64: units of 2^-64 scene units squared)
  std::int64_t median_phi_raw = 0;
};
RadiusScale radius_scale_from_layout(std::span<const std::array<Q32, 3>> position, std::span<const Q32> phi,
                                     bool parallel = false);
// L0 phi apportioned so the raws sum to exactly L0's raw (R1-ENC-002); `phi` must sum to 2^32.
std::vector<Q32> apportion_luminosity(std::span<const Q32> phi, Q32 total = Q32::one());
// The angle of (u5, u6) in turns, [0, 1) (R1-ENC-003).
Q32 hue_of(Q32 u5, Q32 u6);
// Per-particle saturation from the graph's a2 and w (R1-ENC-004).
std::vector<Q32> saturation_from_a2(const Graph& g);

// ---- betweenness and roles (R1-ENC-010..019) -------------------------------------------------

struct Betweenness {
  std::vector<double> value;  // b(p) of R1-ENC-012, exact or estimated
  bool exact = true;
  std::uint32_t sources = 0;  // BFS sources used: n when exact, k pivots otherwise
};

// How betweenness runs, never what it computes: every combination gives the same bits
// (R1-ENC-020..021).
struct BetweennessRun {
  bool parallel = false;  // batches of sources on TBB workers (R1-ENC-020)
  bool batched = true;    // seven sources per traversal; off: one source at a time (R1-ENC-021)
};

// The k particles with the smallest Hemera(id || "r1-pivot"), ascending particle index (R1-ENC-015);
// `parallel` spreads the hashing over TBB workers (the same digests).
std::vector<std::uint32_t> choose_pivots(std::span<const ParticleId> ids, std::uint32_t k, bool parallel = false);
// Sum over `sources` (ascending index) of the Brandes dependencies, times `scale` (R1-ENC-013).
// scale = 0.5 with every particle a source gives b exactly.
std::vector<double> betweenness_from_sources(const Graph& g, std::span<const std::uint32_t> sources, double scale,
                                             const ProgressFn& progress = {}, const BetweennessRun& run = {});
// The sources R1-ENC-014 gives a graph of n particles and nnz stored entries: n (exact), or the
// number of hashed pivots.
std::uint32_t betweenness_sources(std::uint32_t n, std::uint64_t nnz, const BetweennessOptions& options = {});
// Exact or pivot-estimated betweenness by the rule of R1-ENC-014.
Betweenness betweenness(const Graph& g, std::span<const ParticleId> ids, const BetweennessOptions& options = {},
                        const ProgressFn& progress = {}, const BetweennessRun& run = {});
// The R1-ENC-016 bound on |b_est - b| holding with probability 1 - delta per particle.
double betweenness_error_bound(std::uint32_t n, std::uint32_t k, double delta);

struct RoleStats {
  double degree_mean = 0, degree_sigma = 0;   // for the manifest; the hub test is exact (R1-ENC-010)
  double betweenness_mean = 0, betweenness_sigma = 0;
  double bridge_threshold = 0;                // theta of R1-ENC-017
  std::array<std::uint32_t, 4> count{};       // by Role
};
// Hub, bridge, leaf by R1-ENC-010..018 from the graph and its betweenness.
std::vector<Role> infer_roles(const Graph& g, std::span<const double> betweenness, RoleStats* stats = nullptr);
// Hub test of R1-ENC-010 for one degree given n, S_1 = sum d and S_2 = sum d^2.
bool is_hub(std::uint64_t degree, std::uint64_t n, u128 s1, u128 s2);

// ---- overlays (R1-ENC-030..043) ----------------------------------------------------------------

// The crystal-v5 preset as tables (R1-ENC-031).
const CustomOverlay& crystal_v5_overlay();
// Parses the custom TOML format; errors are "NAME:LINE: reason" (R1-ENC-042).
Result<CustomOverlay> parse_custom_overlay(std::string_view text, const std::string& name);
Result<CustomOverlay> read_custom_overlay(const std::string& path);
// Reads the overlay file at `path` into options.custom and names it options.custom_name: the
// stage receives the overlay as a value (R1-BKD-014). An empty path leaves the options unchanged.
Status load_custom_overlay(EncodingOptions& options, const std::string& path);
// Canonical TOML text of an overlay (R1-ENC-043): parse_custom_overlay gives it back.
std::string custom_overlay_text(const CustomOverlay& overlay);
// The style of one particle: tables through its crystal metadata, then its own entry.
OverlayStyle overlay_style(const CustomOverlay& overlay, const CrystalTag& tag, const OverlayStyle* own = nullptr);

// ---- the encoding stage ------------------------------------------------------------------------

// What the manifest reports beside the Encoding.
struct EncodingInfo {
  RoleStats roles;
  bool betweenness_exact = true;
  std::uint32_t betweenness_sources = 0;
  std::uint32_t overlay_particles = 0;  // particles whose style the overlay changed
};

// The stage (R1-ENC-050). `conventioned` is the sign-conventioned spectrum (u_5 = u[3], u_6 = u[4]).
Result<Encoding> encode(const Snapshot& snapshot, const Graph& graph, const Focus<Q32>& focus,
                        const Spectrum<Q32>& conventioned, const EncodingOptions& options = {},
                        EncodingInfo* info = nullptr, const ProgressFn& progress = {});
// The same with the overlay given as tables (nullptr: none); options.overlay only labels
// Encoding::overlay and options.custom_name names the overlay in messages.
Result<Encoding> encode_with_overlay(const Snapshot& snapshot, const Graph& graph, const Focus<Q32>& focus,
                                     const Spectrum<Q32>& conventioned, const EncodingOptions& options,
                                     const CustomOverlay* overlay, EncodingInfo* info = nullptr,
                                     const ProgressFn& progress = {});

}  // namespace r1
