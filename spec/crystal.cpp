// Crystal-v5 name lookups (R1-IN-030).
#include "r1/spec/crystal.hpp"

#include <cctype>

namespace r1 {

namespace {
bool iequal(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(a[i])) != std::tolower(static_cast<unsigned char>(b[i]))) return false;
  return true;
}
template <std::size_t N>
std::optional<std::uint8_t> find(const std::array<std::string_view, N>& table, std::string_view name) {
  for (std::size_t i = 0; i < N; ++i)
    if (iequal(table[i], name)) return static_cast<std::uint8_t>(i);
  return std::nullopt;
}
}  // namespace

std::optional<std::uint8_t> crystal_type_index(std::string_view name) { return find(kCrystalTypes, name); }
std::optional<std::uint8_t> crystal_domain_index(std::string_view name) { return find(kCrystalDomains, name); }
std::optional<std::uint8_t> crystal_size_index(std::string_view name) { return find(kCrystalSizes, name); }

}  // namespace r1
