// Synthetic graph generators behind `r1 gen`: lattices, random models and the crystal default
// (R1-GEN-001..046, spec/generators.md).
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "r1/spec/progress.hpp"
#include "r1/spec/snapshot.hpp"
#include "r1/spec/status.hpp"

namespace r1 {

enum class GenKind : std::uint8_t { kRing, kPath, kStar, kGrid, kTorus, kComplete, kSbm, kBa, kRgg, kCrystal, kRmat };

// The options a kind may take, as bits of GenKindInfo::options (R1-GEN-003).
enum GenOption : std::uint32_t {
  kGenOptN = 1u << 0,       // --n: nodes
  kGenOptM = 1u << 1,       // --m: links per new node (ba), links per node (rmat)
  kGenOptK = 1u << 2,       // --k: blocks (sbm)
  kGenOptSizes = 1u << 3,   // --sizes: block sizes (sbm)
  kGenOptDims = 1u << 4,    // --dims: WxH (grid) or AxBxC (torus)
  kGenOptPIn = 1u << 5,     // --p-in: probability inside a block / crystal domain
  kGenOptPOut = 1u << 6,    // --p-out: probability across blocks / crystal triads
  kGenOptPTriad = 1u << 7,  // --p-triad: crystal, between domains of one triad
  kGenOptRadius = 1u << 8,  // --radius: rgg link radius
};

// Parameters of one generated snapshot. An unset option takes the kind's default; setting an
// option the kind does not take is an input error. Integers are signed so that a negative value
// reaches validation and gets a message naming the option.
struct GenParams {
  GenKind kind = GenKind::kRing;
  std::uint64_t seed = 1;
  std::optional<std::int64_t> n;
  std::optional<std::int64_t> m;
  std::optional<std::int64_t> k;
  std::vector<std::int64_t> sizes;  // empty = unset
  std::vector<std::int64_t> dims;   // empty = unset
  std::optional<double> p_in;
  std::optional<double> p_out;
  std::optional<double> p_triad;
  std::optional<double> radius;
};

struct GenKindInfo {
  GenKind kind;
  std::string_view name;     // the KIND word of `r1 gen KIND`
  std::string_view summary;  // one line
  std::uint32_t options;     // GenOption bits this kind takes (besides --seed)
  std::string_view defaults; // the options with their defaults and limits, for help text
};

// Every kind, in the order the help text lists them.
std::span<const GenKindInfo> gen_kinds();
const GenKindInfo& gen_kind_info(GenKind kind);
Result<GenKind> gen_kind_from_name(std::string_view name);
// A multi-line listing of the kinds, their options and defaults (for `r1 gen --help`).
std::string gen_help_text();
// Parses "32x32" or "10x10x10" (also 'X' or ','); positive decimal integers only.
Result<std::vector<std::int64_t>> parse_dims(std::string_view text);

// Limits that keep generation within a few GiB (R1-GEN-004).
inline constexpr std::int64_t kGenMaxNodes = std::int64_t{1} << 24;
inline constexpr std::int64_t kGenMaxLinks = std::int64_t{1} << 25;
// sbm decides every node pair: O(n^2) counter-RNG draws, about 10 s at this size on 2 cores.
inline constexpr std::int64_t kGenMaxSbmNodes = 50'000;

// Generates the snapshot: names, links and (crystal) titles and crystal metadata, through
// SnapshotBuilder with text_input_config(). Same parameters, same snapshot, on any machine and
// any thread count (R1-GEN-002).
Result<Snapshot> generate(const GenParams& params, const ProgressFn& progress = {});

// The command line that reproduces `params` with every default filled in, e.g.
// "r1 gen ring --n 1000 --seed 1"; written into the snapshot's card. Input error when invalid.
Result<std::string> gen_command_line(const GenParams& params);

}  // namespace r1
