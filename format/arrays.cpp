// Per-particle arrays as little-endian bytes (R1-FMT-010, R1-EPO-011).
#include "r1/format/arrays.hpp"

#include <cstring>

#include "r1/format/bytes.hpp"

namespace r1::format {

std::string q32_column(std::span<const fx::Q32> v) {
  std::string o;
  o.reserve(v.size() * 8);
  for (const fx::Q32 q : v) put_i64(o, q.raw);
  return o;
}

std::string q32_rows(std::span<const std::vector<fx::Q32>> columns, std::size_t rows) {
  std::string o;
  o.reserve(rows * columns.size() * 8);
  for (std::size_t i = 0; i < rows; ++i)
    for (const auto& c : columns) put_i64(o, c[i].raw);
  return o;
}

std::string q32_triples(std::span<const std::array<fx::Q32, 3>> v) {
  std::string o;
  o.reserve(v.size() * 24);
  for (const auto& p : v)
    for (const fx::Q32 c : p) put_i64(o, c.raw);
  return o;
}

std::string u64_column(std::span<const std::uint64_t> v) {
  std::string o;
  o.reserve(v.size() * 8);
  for (const std::uint64_t x : v) put_u64(o, x);
  return o;
}

std::string bytes32_rows(std::span<const std::span<const Bytes32>> columns, std::size_t rows) {
  std::string o;
  o.reserve(rows * columns.size() * 32);
  for (std::size_t i = 0; i < rows; ++i)
    for (const auto& c : columns) o.append(reinterpret_cast<const char*>(c[i].data()), 32);
  return o;
}

std::vector<Bytes32> read_bytes32_column(std::string_view b, std::size_t n, std::size_t stride, std::size_t k) {
  std::vector<Bytes32> v(n);
  for (std::size_t i = 0; i < n; ++i) std::memcpy(v[i].data(), b.data() + (i * stride + k) * 32, 32);
  return v;
}

std::vector<std::uint64_t> read_u64_column(std::string_view b, std::size_t n) {
  std::vector<std::uint64_t> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = load_u64(b.data() + i * 8);
  return v;
}

std::string i128_column(std::span<const i128> v) {
  std::string o;
  o.reserve(v.size() * 16);
  for (const i128 x : v) {
    put_u64(o, static_cast<std::uint64_t>(static_cast<u128>(x)));
    put_u64(o, static_cast<std::uint64_t>(static_cast<u128>(x) >> 64));
  }
  return o;
}

std::vector<i128> read_i128_column(std::string_view b, std::size_t n) {
  std::vector<i128> v(n);
  for (std::size_t i = 0; i < n; ++i)
    v[i] = static_cast<i128>((static_cast<u128>(load_u64(b.data() + i * 16 + 8)) << 64) | load_u64(b.data() + i * 16));
  return v;
}

std::string f64_column(std::span<const double> v) {
  std::string o;
  o.reserve(v.size() * 8);
  for (const double x : v) put_f64(o, x);
  return o;
}

std::vector<double> read_f64_column(std::string_view b, std::size_t n) {
  std::vector<double> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = load_f64(b.data() + i * 8);
  return v;
}

std::string u32_rows(std::span<const std::vector<std::uint32_t>> columns, std::size_t rows) {
  std::string o;
  o.reserve(rows * columns.size() * 4);
  for (std::size_t i = 0; i < rows; ++i)
    for (const auto& c : columns) put_u32(o, c[i]);
  return o;
}

std::vector<fx::Q32> read_q32_column(std::string_view b, std::size_t n, std::size_t stride, std::size_t k) {
  std::vector<fx::Q32> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = fx::Q32::from_raw(load_i64(b.data() + (i * stride + k) * 8));
  return v;
}

std::vector<std::array<fx::Q32, 3>> read_q32_triples(std::string_view b, std::size_t n) {
  std::vector<std::array<fx::Q32, 3>> v(n);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t c = 0; c < 3; ++c) v[i][c] = fx::Q32::from_raw(load_i64(b.data() + (i * 3 + c) * 8));
  return v;
}

std::vector<std::uint32_t> read_u32_column(std::string_view b, std::size_t n, std::size_t stride, std::size_t k) {
  std::vector<std::uint32_t> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = load_u32(b.data() + (i * stride + k) * 4);
  return v;
}

std::string edge_rows(std::span<const LayoutEdge> edges) {
  std::string s;
  s.reserve(edges.size() * kEdgeBytes);
  for (const LayoutEdge& e : edges) {
    put_u32(s, e.p);
    put_u32(s, e.q);
    put_i64(s, e.w_raw);
    put_i64(s, e.a2_raw);
  }
  return s;
}

LayoutEdge edge_at(std::string_view b, std::size_t k) {
  const char* r = b.data() + k * kEdgeBytes;
  return {load_u32(r), load_u32(r + 4), load_i64(r + 8), load_i64(r + 16)};
}

}  // namespace r1::format
