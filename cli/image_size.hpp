// An image size option, WIDTHxHEIGHT, shared by the commands that take one.
#pragma once

#include <charconv>
#include <string>
#include <utility>

#include "r1/spec/status.hpp"

namespace r1::cli {

// WIDTHxHEIGHT, each 1..16384; `option` names the option in the error ("render: --size").
inline Result<std::pair<int, int>> parse_image_size(const std::string& text, const std::string& option) {
  const auto x = text.find('x');
  int w = 0, h = 0;
  const char* end = text.data() + text.size();
  if (x == std::string::npos || std::from_chars(text.data(), text.data() + x, w).ptr != text.data() + x ||
      std::from_chars(text.data() + x + 1, end, h).ptr != end || w < 1 || h < 1 || w > 16384 || h > 16384)
    return Status::input(option + " must be WIDTHxHEIGHT, each 1..16384 (e.g. 1920x1080; got '" + text + "')");
  return std::pair<int, int>{w, h};
}

}  // namespace r1::cli
