// Tensor buffers of the trait's Clifford calls (R1-BKD-013, R1-FMT-030).
#include "r1/format/tensor.hpp"

#include <string>

#include "r1/format/bytes.hpp"

namespace r1::format {

std::vector<std::uint8_t> tensor_bytes(std::uint32_t n, std::uint32_t d, std::span<const double> values) {
  std::string s;
  s.reserve(8 + values.size() * 8);
  put_u32(s, n);
  put_u32(s, d);
  for (const double v : values) put_f64(s, v);
  return std::vector<std::uint8_t>(s.begin(), s.end());
}

Result<std::pair<std::array<std::uint32_t, 2>, std::vector<double>>> parse_tensor_bytes(std::span<const std::uint8_t> b) {
  if (b.size() < 8) return Status::input("tensor buffer: byte 0: shorter than its 8-byte header");
  const std::uint32_t n = load_u32(b.data()), d = load_u32(b.data() + 4);
  const std::uint64_t count = std::uint64_t{n} * d;
  if (count > (b.size() - 8) / 8 || b.size() != 8 + count * 8)
    return Status::input("tensor buffer: byte 0: " + std::to_string(n) + " x " + std::to_string(d) +
                         " does not match its " + std::to_string(b.size()) + " bytes");
  std::vector<double> v(count);
  for (std::uint64_t i = 0; i < count; ++i) v[i] = load_f64(b.data() + 8 + i * 8);
  return std::pair{std::array<std::uint32_t, 2>{n, d}, std::move(v)};
}

}  // namespace r1::format
