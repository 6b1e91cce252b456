// Some rows of L~ and the exact sums an incremental epoch carries (spec/incremental.md R1-INC-038):
// the entries of R1-SPEC-003 for the listed rows only, and the application of R1-SPEC-005 (rho = 0)
// on them. Every row is an exact sum rounded once, so these rows are bit for bit those of
// SpectralOperator<Q32>::apply_block.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <stdexcept>

#include "r1/solvers/panel.hpp"
#include "r1/solvers/spectral.hpp"

namespace r1 {

namespace {

// Rows below this many stored entries in all stay on one thread.
constexpr std::uint64_t kParallelEntries = std::uint64_t{1} << 16;

template <class Body>
void for_rows(std::size_t count, std::uint64_t entries, bool parallel, const Body& body) {
  if (parallel && entries >= kParallelEntries) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 64),
                      [&](const tbb::blocked_range<std::size_t>& r) { body(r.begin(), r.end()); });
  } else {
    body(0, count);
  }
}

i128 term(std::int64_t a, std::int64_t b) { return static_cast<i128>(a) * b; }

}  // namespace

RowOperatorQ32 RowOperatorQ32::build(std::span<const std::uint64_t> row_ptr, std::span<const std::uint32_t> col,
                                     std::span<const std::int64_t> w, std::span<const std::uint64_t> degree,
                                     std::span<const std::uint32_t> rows, bool parallel) {
  RowOperatorQ32 op;
  op.rows.assign(rows.begin(), rows.end());
  op.ptr.assign(rows.size() + 1, 0);
  for (std::size_t a = 0; a < rows.size(); ++a) op.ptr[a + 1] = op.ptr[a] + (row_ptr[rows[a] + 1] - row_ptr[rows[a]]);
  op.col.resize(op.ptr.back());
  op.m.resize(op.ptr.back());
  for_rows(rows.size(), op.ptr.back(), parallel, [&](std::size_t lo, std::size_t hi) {
    for (std::size_t a = lo; a < hi; ++a) {
      const std::uint32_t i = rows[a];
      std::uint64_t o = op.ptr[a];
      for (std::uint64_t k = row_ptr[i]; k < row_ptr[i + 1]; ++k, ++o) {
        op.col[o] = col[k];
        op.m[o] = spectral::m_entry(w[k], degree[i], degree[col[k]]);
      }
    }
  });
  return op;
}

namespace {

// x_i 2^32 - sum_k M_ik x_k over one row's entries (R1-SPEC-005 with rho = 0), exact.
template <class Col, class M>
i128 row_numerator(std::int64_t xi, std::uint64_t b, std::uint64_t e, const Col& col_of, const M& m_of,
                   const std::vector<fx::Q32>& x, std::int64_t scale) {
  spectral::FastExact acc;
  acc.add(static_cast<i128>(xi * scale) * (i128{1} << 32));
  for (std::uint64_t k = b; k < e; ++k) acc.add(-term(m_of(k), x[col_of(k)].raw * scale));
  const fx::ExactSum total = acc.total();
  const auto l = total.limbs();
  // |numerator| < 2^113 for every graph r1 holds (x below 2^49, M below 2^33, fewer than 2^32
  // entries): the high limb is the sign extension.
  if (l[2] != (static_cast<std::int64_t>(l[1]) < 0 ? ~std::uint64_t{0} : 0)) fx::detail::throw_overflow("spectral image");
  return static_cast<i128>((static_cast<u128>(l[1]) << 64) | l[0]);
}

}  // namespace

void RowOperatorQ32::numerators(std::span<const std::vector<fx::Q32>> cols, int shift, std::vector<i128>& image, bool parallel) const {
  const std::int64_t scale = std::int64_t{1} << shift;
  for_rows(rows.size(), ptr.back(), parallel, [&](std::size_t lo, std::size_t hi) {
    for (std::size_t a = lo; a < hi; ++a)
      for (std::size_t c = 0; c < 5; ++c)
        image[std::size_t{rows[a]} * 5 + c] = row_numerator(
            cols[c][rows[a]].raw, ptr[a], ptr[a + 1], [&](std::uint64_t k) { return col[k]; },
            [&](std::uint64_t k) { return m[k].raw; }, cols[c], scale);
  });
}

namespace spectral {

std::int64_t image_raw(i128 numerator) {
  const i128 r = fx::detail::rne_shift(numerator, 32);
  if (!fx::detail::fits_i64(r)) fx::detail::throw_overflow("spectral image");
  return static_cast<std::int64_t>(r);
}

void add_row_sums(std::span<const std::vector<fx::Q32>> cols, int shift, std::uint32_t i, const i128* numerators, int sign,
                  ResidualSums& sums) {
  for (std::size_t c = 0; c < 5; ++c) {
    const std::int64_t x = cols[c][i].raw * (std::int64_t{1} << shift), y = image_raw(numerators[c]);
    sums[c][0].add_term(sign * term(x, x));
    sums[c][1].add_term(sign * term(x, y));
    sums[c][2].add_term(sign * term(y, y));
  }
}

void image_and_sums(const SpectralOperator<fx::Q32>& op, std::span<const std::vector<fx::Q32>> cols, int shift,
                    std::vector<i128>& image, ResidualSums& sums, bool parallel) {
  if (cols.size() != 5 || op.rho.raw != 0) throw std::invalid_argument("image_and_sums: five vectors and rho = 0 expected");
  const Graph& g = *op.graph;
  const std::size_t n = op.n;
  const std::int64_t scale = std::int64_t{1} << shift;
  image.assign(n * 5, 0);
  spectral::for_row_blocks(n, parallel && n >= spectral::kParallelMin, [&](std::size_t lo, std::size_t hi) {
    for (std::size_t i = lo; i < hi; ++i)
      for (std::size_t c = 0; c < 5; ++c)
        image[i * 5 + c] = row_numerator(
            cols[c][i].raw, g.row_ptr[i], g.row_ptr[i + 1], [&](std::uint64_t k) { return g.col[k]; },
            [&](std::uint64_t k) { return op.m[k].raw; }, cols[c], scale);
  });
  sums = {};
  for (std::uint32_t i = 0; i < n; ++i) add_row_sums(cols, shift, i, &image[std::size_t{i} * 5], 1, sums);
}

}  // namespace spectral

void residual_sums(const SpectralOperator<fx::Q32>& op, Spectrum<fx::Q32>& s, bool parallel) {
  s.sums_shift = -1;
  s.sums = {};
  s.image.clear();
  if (s.found < 5 || op.rho.raw != 0 || op.n != s.n) return;
  spectral::image_and_sums(op, s.u, op.e / 2, s.image, s.sums, parallel);
  s.sums_shift = op.e / 2;
}

}  // namespace r1
