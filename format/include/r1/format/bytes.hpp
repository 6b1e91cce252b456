// The little-endian byte codec, written once (R1-FMT-001..003): appending fixed-width integers
// and IEEE doubles to a byte string, loading them back, and a bounds-checked reader whose errors
// name the file and the byte offset. Every r1 binary format is built from these.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <string_view>
#include <utility>

#include "r1/spec/status.hpp"

namespace r1::format {

// ---- writing (R1-FMT-001): least significant byte first, two's complement for signed ----------

inline void put_u8(std::string& out, std::uint8_t v) { out.push_back(static_cast<char>(v)); }
inline void put_u32(std::string& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xFFu));
}
inline void put_u64(std::string& out, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xFFu));
}
inline void put_i64(std::string& out, std::int64_t v) { put_u64(out, static_cast<std::uint64_t>(v)); }
// An IEEE binary64 or binary32 by its bits (no rounding, NaN payloads kept).
inline void put_f64(std::string& out, double v) { put_u64(out, std::bit_cast<std::uint64_t>(v)); }
inline void put_f32(std::string& out, float v) { put_u32(out, std::bit_cast<std::uint32_t>(v)); }
inline void put_bytes(std::string& out, std::span<const std::uint8_t> b) {
  out.append(reinterpret_cast<const char*>(b.data()), b.size());
}

// ---- loading from a place the caller has bounds-checked (R1-FMT-001) --------------------------

inline std::uint32_t load_u32(const void* p) {
  const auto* b = static_cast<const unsigned char*>(p);
  std::uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= static_cast<std::uint32_t>(b[i]) << (8 * i);
  return v;
}
inline std::uint64_t load_u64(const void* p) {
  const auto* b = static_cast<const unsigned char*>(p);
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v |= static_cast<std::uint64_t>(b[i]) << (8 * i);
  return v;
}
inline std::int64_t load_i64(const void* p) { return static_cast<std::int64_t>(load_u64(p)); }
inline double load_f64(const void* p) { return std::bit_cast<double>(load_u64(p)); }

// ---- bounds-checked reading (R1-FMT-002) -------------------------------------------------------

// Reads fields in order from `bytes`; a read past the end returns false and leaves the value
// alone. error() places a message at the current offset: "NAME: byte N: why".
class ByteReader {
 public:
  ByteReader(std::string_view bytes, std::string name, std::size_t base = 0)
      : b_(bytes), name_(std::move(name)), base_(base) {}
  ByteReader(std::span<const std::uint8_t> bytes, std::string name, std::size_t base = 0)
      : ByteReader(std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()), std::move(name), base) {}

  bool u8(std::uint8_t& v) { return take(1, [&](const char* p) { v = static_cast<std::uint8_t>(*p); }); }
  bool u32(std::uint32_t& v) { return take(4, [&](const char* p) { v = load_u32(p); }); }
  bool u64(std::uint64_t& v) { return take(8, [&](const char* p) { v = load_u64(p); }); }
  bool i64(std::int64_t& v) { return take(8, [&](const char* p) { v = load_i64(p); }); }
  bool f64(double& v) { return take(8, [&](const char* p) { v = load_f64(p); }); }
  // Copies `out.size()` raw bytes.
  bool bytes(std::span<std::uint8_t> out) {
    return take(out.size(), [&](const char* p) { std::memcpy(out.data(), p, out.size()); });
  }
  bool skip(std::size_t k) { return take(k, [](const char*) {}); }

  // Offset of the next read within the whole file (base + bytes consumed).
  std::size_t offset() const { return base_ + at_; }
  std::size_t left() const { return b_.size() - at_; }
  std::string_view rest() const { return b_.substr(at_); }
  const std::string& name() const { return name_; }
  Status error(const std::string& why) const { return error_at(offset(), why); }
  Status error_at(std::size_t offset, const std::string& why) const {
    return Status::input(name_ + ": byte " + std::to_string(offset) + ": " + why);
  }

 private:
  template <class F>
  bool take(std::size_t k, F f) {
    if (b_.size() - at_ < k) return false;
    f(b_.data() + at_);
    at_ += k;
    return true;
  }
  std::string_view b_;
  std::string name_;
  std::size_t base_ = 0;
  std::size_t at_ = 0;
};

}  // namespace r1::format
