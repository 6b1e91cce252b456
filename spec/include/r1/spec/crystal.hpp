// Crystal-v5 metadata: 6 types, 21 domains in 7 triads, 5 sizes (R1-IN-030, REFERENCE.md 6).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>

namespace r1 {

inline constexpr std::array<std::string_view, 6> kCrystalTypes = {"entity", "process", "property",
                                                                  "relation", "measure", "pattern"};
// Type shares of the crystal's own axioms, 10:4:3:2:1:1 (sum 21).
inline constexpr std::array<int, 6> kCrystalTypeShares = {10, 4, 3, 2, 1, 1};
inline constexpr std::array<std::string_view, 21> kCrystalDomains = {
    "math", "info", "comp",      // FORM
    "quantum", "chemo", "energo",  // MASS
    "cosmo", "geo", "eco",       // SPACE
    "bio", "neuro", "sense",     // LIFE
    "lang", "spiri", "meta",     // WORD
    "ai", "tech", "cyber",       // WORK
    "socio", "crypto", "game"};  // PLAY
inline constexpr std::array<std::string_view, 7> kCrystalTriads = {"FORM", "MASS", "SPACE", "LIFE",
                                                                   "WORD", "WORK", "PLAY"};
inline constexpr std::array<std::string_view, 5> kCrystalSizes = {"atom", "enzyme", "bridge", "article", "deep"};
inline constexpr std::array<int, 5> kCrystalSizeBytes = {256, 512, 1024, 4096, 16384};

struct CrystalTag {
  // A particle without metadata keeps kUnknown in every field.
  static constexpr std::uint8_t kUnknown = 0xFF;
  std::uint8_t type = kUnknown;    // index into kCrystalTypes
  std::uint8_t domain = kUnknown;  // index into kCrystalDomains; triad = domain / 3
  std::uint8_t size = kUnknown;    // index into kCrystalSizes
  bool known() const { return type != kUnknown; }
  friend bool operator==(const CrystalTag&, const CrystalTag&) = default;
};

// Case-insensitive lookups of the names above; nullopt when unknown.
std::optional<std::uint8_t> crystal_type_index(std::string_view name);
std::optional<std::uint8_t> crystal_domain_index(std::string_view name);
std::optional<std::uint8_t> crystal_size_index(std::string_view name);

}  // namespace r1
