// The anchor file's bytes (R1-FRM-020..023, R1-FMT-020): the codec of r1::Anchor, its digest.
// Reading and writing the file is the caller's (reference/frame.hpp read_anchor, write_anchor).
#pragma once

#include <cstdint>
#include <span>
#include <string>

#include "r1/fixedpoint/hemera.hpp"
#include "r1/spec/anchor.hpp"
#include "r1/spec/status.hpp"

namespace r1 {

// The file bytes of R1-FRM-021. Input error when the anchor itself breaks a rule of the format.
Result<std::string> anchor_bytes(const Anchor& anchor);
// Parses file bytes; `name` places errors ("NAME: byte N: ...").
Result<Anchor> parse_anchor(std::span<const std::uint8_t> bytes, const std::string& name);
// hemera::root_hash of anchor_bytes (R1-FRM-022).
Result<hemera::Digest> anchor_digest(const Anchor& anchor);

}  // namespace r1
