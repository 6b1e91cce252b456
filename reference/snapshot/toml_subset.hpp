// Untrusted TOML is parsed narrowly (R1-IN-005): a line-level check admits only the constructs
// r1's files use before toml++ sees the text, which keeps known parser defects out of reach.
#pragma once

#include <toml++/toml.h>

#include <optional>
#include <string>
#include <string_view>

#include "r1/spec/status.hpp"

namespace r1::toml_subset {

inline constexpr std::size_t kMaxBytes = 1u << 20;  // front matter and config are small
inline constexpr std::size_t kMaxLine = 4096;

// Checks `text` against r1's TOML subset. `name` and `first_line` place errors in the file
// ("NAME:LINE: ..."): the text may start part-way into a file.
Status check(std::string_view text, const std::string& name, std::size_t first_line = 1);

// A decimal given as an integer or as a string "12.5" / "-0.25" (R1-RND-005: the subset has no
// floats, so decimals travel as strings and are read correctly rounded). No exponent, no inf or
// nan; nullopt for anything else.
std::optional<double> decimal(const toml::node& n);

// check(), then toml++; errors carry the file line.
Result<toml::table> parse(std::string_view text, const std::string& name, std::size_t first_line = 1);

}  // namespace r1::toml_subset
