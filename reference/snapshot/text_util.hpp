// Text-input helpers shared by the readers: UTF-8 validation, exact decimal weights, line
// splitting and the backslash escapes of r1's TSV sections (R1-IN-013, R1-IN-016).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "r1/fixedpoint/int128.hpp"

namespace r1::text {

// Byte offset of the first invalid UTF-8 sequence in `s` (overlongs, surrogates and code points
// above U+10FFFF are invalid), or nullopt when all of `s` is valid.
std::optional<std::size_t> find_invalid_utf8(std::string_view s);

// A link weight as written in a text input, converted exactly to amount = round(weight * 2^32)
// with ties to even. Accepts [+]digits[.digits][(e|E)[+-]digits] and .digits; the error text
// says why anything else was refused (negative, zero, not finite, too large, syntax).
struct WeightResult {
  u128 amount = 0;
  std::string error;  // empty on success
};
WeightResult parse_weight(std::string_view field);

// The exact decimal of amount / 2^32 (no exponent, no trailing zeros): parse_weight inverts it.
std::string format_weight(u128 amount);

// Valence field: -1, 0, 1 or +1.
std::optional<std::int8_t> parse_valence(std::string_view field);

// Unsigned decimal integer without sign or spaces; nullopt on syntax error or overflow.
std::optional<std::uint64_t> parse_u64(std::string_view field);

// Backslash escapes for TSV cells: \\ \t \n \r. unescape() fails on any other escape.
std::string escape_cell(std::string_view s);
std::optional<std::string> unescape_cell(std::string_view s);

// Iterates the lines of a text, giving each without its LF (and without a CR before it) and its
// 1-based number and byte offset.
class LineReader {
 public:
  explicit LineReader(std::string_view text) : text_(text) {}
  bool next(std::string_view& line);
  std::size_t line_number() const { return number_; }
  std::size_t line_offset() const { return offset_; }
  std::size_t position() const { return pos_; }

 private:
  std::string_view text_;
  std::size_t pos_ = 0, number_ = 0, offset_ = 0;
};

// Splits a line on TAB into `out` (cleared first); fields are views into the line.
void split_tabs(std::string_view line, std::vector<std::string_view>& out);

// True when the line is empty or only spaces and tabs.
bool is_blank(std::string_view line);
// Strips a leading UTF-8 byte-order mark.
std::string_view strip_bom(std::string_view text);

}  // namespace r1::text
