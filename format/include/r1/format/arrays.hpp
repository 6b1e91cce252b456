// Fixed-width per-particle arrays as little-endian bytes (R1-FMT-010, R1-EPO-011): Q32 columns
// and row-major Q32 / u32 matrices of the epoch directory, and the layout edge rows of edges.bin.
// Readers take bytes whose size the caller has checked against the particle count.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "r1/fixedpoint/q32.hpp"
#include "r1/spec/epoch.hpp"

namespace r1::format {

// i64 raws, one per entry (focus.q32, radius.q32, ...).
std::string q32_column(std::span<const fx::Q32> v);
// Row-major: row i holds columns[0][i], columns[1][i], ... as i64 raws (spectral.q32: 5 columns).
std::string q32_rows(std::span<const std::vector<fx::Q32>> columns, std::size_t rows);
// x, y, z raws per particle (positions.q32, the anchor's and the golden positions' coordinates).
std::string q32_triples(std::span<const std::array<fx::Q32, 3>> v);
// u64 per entry (outrows.u64).
std::string u64_column(std::span<const std::uint64_t> v);
std::vector<std::uint64_t> read_u64_column(std::string_view b, std::size_t n);
// IEEE binary64 per entry, bit for bit (betweenness.f64).
// Signed 128-bit integers, 16 bytes each, low 64 bits first (Spectrum::image, R1-EPO-011).
std::string i128_column(std::span<const i128> v);
std::vector<i128> read_i128_column(std::string_view b, std::size_t n);
std::string f64_column(std::span<const double> v);
std::vector<double> read_f64_column(std::string_view b, std::size_t n);
// Row-major 32-byte values: row i holds columns[0][i], columns[1][i], ... (particles.ids: one
// column; records.chunks: SHA-256 and leaf). Every column has `rows` entries.
using Bytes32 = std::array<std::uint8_t, 32>;
std::string bytes32_rows(std::span<const std::span<const Bytes32>> columns, std::size_t rows);
// Entry k of each of n rows of `stride` 32-byte values.
std::vector<Bytes32> read_bytes32_column(std::string_view b, std::size_t n, std::size_t stride = 1, std::size_t k = 0);
// Row-major u32: row i holds columns[0][i], columns[1][i], ... (clusters.u32: one per level).
std::string u32_rows(std::span<const std::vector<std::uint32_t>> columns, std::size_t rows);

// Entry k of each of n rows of `stride` i64 raws.
std::vector<fx::Q32> read_q32_column(std::string_view b, std::size_t n, std::size_t stride = 1, std::size_t k = 0);
std::vector<std::array<fx::Q32, 3>> read_q32_triples(std::string_view b, std::size_t n);
// Entry k of each of n rows of `stride` u32.
std::vector<std::uint32_t> read_u32_column(std::string_view b, std::size_t n, std::size_t stride = 1, std::size_t k = 0);

// edges.bin (R1-EPO-011): per layout edge u32 p, u32 q, i64 w, i64 a2.
inline constexpr std::size_t kEdgeBytes = 24;
std::string edge_rows(std::span<const LayoutEdge> edges);
// Row k of edges.bin; the caller checked that b holds it.
LayoutEdge edge_at(std::string_view b, std::size_t k);

}  // namespace r1::format
