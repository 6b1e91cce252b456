// The cpu backend's rows of the spectral operator (R1-SPEC-073, R1-BKD-041) on AVX-512 IFMA: a
// block application y = L~ x on a compact n x count block, every row the exact sum
// x_i 2^32 - sum_k M_ik x_k - g_i c rounded once, as SpectralOperator<Q32>::apply_block forms it.
//
// A lane per block column (up to 8). Each stored entry's block row is one masked load, offset to
// x' = x + 2^51 (in [0, 2^52) whenever |x| < 2^51, which magnitude bits check per lane), and
// M_ik (a 32-bit raw, R1-SPEC-076) is broadcast against it: the low and the high 52 bits
// of M_ik x'_k accumulate in two lanes, so sum_k M_ik x'_k = LO + 2^52 HI, and
// sum_k M_ik x_k = LO + 2^52 HI - 2^51 sum_k M_ik. A lane takes at most kFlush entries (below
// 2^11 terms of under 2^52 each, so no lane passes 2^63) before it is added into 128 bits.
// Every quantity is formed modulo 2^128; the true numerator is below 2^118 in magnitude, so its
// i128 reading is exact and the one rounding is apply_block's. A column whose row gathers an
// entry beyond the offset range takes the exact scalar sum instead.
#if defined(__x86_64__)
#include <immintrin.h>
#endif

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <vector>

#include <tbb/enumerable_thread_specific.h>

#include "r1/accel/cpu/panel_kernels.hpp"
#include "r1/fixedpoint/prefetch.hpp"
#include "r1/solvers/exact_round.hpp"
#include "r1/solvers/panel.hpp"
#if defined(__x86_64__)
#include "wide_lanes.hpp"
#endif

namespace r1::accel::cpu {

#if defined(__x86_64__)
namespace {

constexpr int kOffsetBits = 51;
constexpr std::uint64_t kOffset = std::uint64_t{1} << kOffsetBits;
constexpr std::size_t kFlush = 2048;         // entries a lane takes before it is widened
// Stored entries a gather is prefetched ahead (fx::gather_hint: into the second-level cache).
// BA 10^6, a block application of 7 columns on two cores: 109-133 ms with first-level hints 32
// ahead, 59-81 ms with second-level ones 64 or 96 ahead, 73-84 ms 160 ahead.
constexpr std::uint64_t kAhead = 96;
constexpr std::size_t kLanes = 8;
constexpr std::size_t kPadFrom = std::size_t{1} << 15;  // rows from which x is copied line-aligned

struct RowSums {
  u128 lo[kLanes], hi[kLanes];
  std::uint64_t bits[kLanes];
};

R1_MASKED_SHIFT_WARNING_OFF
// Entries [k0, k1) of a row for the block columns c0 .. (the lanes `mask` sets): the low and high
// 52 bits of M_ik x'_k added to lo and hi (at most kFlush entries between widenings), the
// gathered entries' magnitude bits OR-ed into bits.
__attribute__((target("avx512f,avx512ifma"), always_inline)) inline void ifma_entries(
    const std::uint32_t* col, const std::uint32_t* m, std::uint64_t k0, std::uint64_t k1, std::uint64_t nnz, const fx::Q32* x,
    std::size_t ld, std::size_t c0, __mmask8 mask, __m512i& lo, __m512i& hi, __m512i& bits) {
  const __m512i off = _mm512_set1_epi64(static_cast<long long>(kOffset));
  for (std::uint64_t k = k0; k < k1; ++k) {
    if (k + kAhead < nnz) {
      const fx::Q32* ahead = x + static_cast<std::size_t>(col[k + kAhead]) * ld + c0;
      fx::gather_hint(ahead);
      fx::gather_hint(ahead + kLanes - 1);
    }
    const __m512i v = _mm512_maskz_loadu_epi64(mask, &x[static_cast<std::size_t>(col[k]) * ld + c0].raw);
    const __m512i xo = _mm512_maskz_add_epi64(mask, v, off);
    bits = _mm512_or_si512(bits, _mm512_xor_si512(v, _mm512_srai_epi64(v, 63)));
    const __m512i mk = _mm512_set1_epi64(static_cast<long long>(m[k]));
    lo = _mm512_madd52lo_epu64(lo, xo, mk);
    hi = _mm512_madd52hi_epu64(hi, xo, mk);
  }
}

// Entries [b, e) of one row for the block columns c0 .. (the lanes `mask` sets): the lane sums of
// M x' widened into `s`, and the OR of the gathered entries' magnitude bits per lane.
__attribute__((target("avx512f,avx512ifma"))) void ifma_row(const std::uint32_t* col, const std::uint32_t* m, std::uint64_t b,
                                                             std::uint64_t e, std::uint64_t nnz, const fx::Q32* x,
                                                             std::size_t ld, std::size_t c0, __mmask8 mask, RowSums& s) {
  __m512i bits = _mm512_setzero_si512();
  for (std::uint64_t k0 = b; k0 < e; k0 += kFlush) {
    __m512i lo = _mm512_setzero_si512(), hi = _mm512_setzero_si512();
    ifma_entries(col, m, k0, std::min<std::uint64_t>(e, k0 + kFlush), nnz, x, ld, c0, mask, lo, hi, bits);
    alignas(64) std::uint64_t l[kLanes], h[kLanes];
    _mm512_store_si512(l, lo);
    _mm512_store_si512(h, hi);
    for (std::size_t c = 0; c < kLanes; ++c) {
      s.lo[c] += l[c];
      s.hi[c] += h[c];
    }
  }
  alignas(64) std::uint64_t bl[kLanes];
  _mm512_store_si512(bl, bits);
  for (std::size_t c = 0; c < kLanes; ++c) s.bits[c] = bl[c];
}

// Rows lo .. hi - 1 of an n x count block with rows ld apart (count < 8) into rows of 8 entries,
// 64-byte aligned: one masked load and one store a row (the lanes past count are written 0, never
// read).
__attribute__((target("avx512f"))) void pad_rows(const fx::Q32* x, std::size_t ld, std::size_t count, fx::Q32* out,
                                                 std::size_t lo, std::size_t hi) {
  const auto mask = static_cast<__mmask8>((1u << count) - 1);
  for (std::size_t i = lo; i < hi; ++i)
    _mm512_store_si512(out + i * kLanes, _mm512_maskz_loadu_epi64(mask, x + i * ld));
}

// A whole row for a block of at most 8 columns (the lanes `mask` sets) when its entries fit one
// lane flush (e - b <= kFlush) and no rank-one term enters: the lane sums of ifma_row, then per
// lane apply_block's numerator x_i 2^32 - (LO + 2^52 HI - 2^51 msum), formed modulo 2^128 as two
// 64-bit halves (the true value is far inside i128), rounded once (RNE of . / 2^32) and written to
// y. False, with nothing written, when a gathered entry lies beyond the offset range or a result
// beyond 64 bits: the caller's exact path then takes the row.
__attribute__((target("avx512f,avx512ifma"))) bool ifma_row_rounded(const std::uint32_t* col, const std::uint32_t* m, std::uint64_t b,
                                                                     std::uint64_t e, std::uint64_t nnz, const fx::Q32* x,
                                                                     std::size_t ld, std::size_t i, __mmask8 mask, u128 msum,
                                                                     fx::Q32* y) {
  __m512i bits = _mm512_setzero_si512(), lo = _mm512_setzero_si512(), hi = _mm512_setzero_si512();
  ifma_entries(col, m, b, e, nnz, x, ld, 0, mask, lo, hi, bits);
  if (_mm512_test_epi64_mask(_mm512_srli_epi64(bits, kOffsetBits), _mm512_set1_epi64(-1)) != 0) return false;
  // T = x_i 2^32 - MX with MX = LO + 2^52 HI - 2^51 msum (the sum of M x over the row).
  const __m512i xi = _mm512_maskz_loadu_epi64(mask, &x[i * ld].raw);
  const u128 ms = msum << kOffsetBits;
  Wide t{_mm512_slli_epi64(xi, 32), _mm512_srai_epi64(xi, 32)};
  t = wide_sub(t, lo, _mm512_setzero_si512());
  t = wide_sub(t, _mm512_slli_epi64(hi, 52), _mm512_srli_epi64(hi, 12));
  t = wide_add(t, _mm512_set1_epi64(static_cast<long long>(static_cast<std::uint64_t>(ms))),
               _mm512_set1_epi64(static_cast<long long>(static_cast<std::uint64_t>(ms >> 64))));
  __mmask8 ok = 0;
  const __m512i r = wide_rne_shift<32>(t, ok);
  if ((static_cast<__mmask8>(~ok) & mask) != 0) return false;
  _mm512_mask_storeu_epi64(&y->raw, mask, r);
  return true;
}
R1_MASKED_SHIFT_WARNING_ON

class IfmaRows final : public spectral::BlockRows {
 public:
  // The rows keep M's entries as 32-bit raws (every M raw is at most 2^32 since M_ij <= 1, and
  // below it on any graph the solver iterates on), half the operator's 64-bit copy, which the
  // solver then releases while the rows live (R1-SPEC-076), and each row's sum_k M_ik, fixed for
  // the operator, formed once in 64 bits (a row of M sums to far below 2^31 on any graph that
  // fits in memory). Where an entry reaches 2^32 or a row sum 2^64 the vector path is off and the
  // rows read the operator's entries product by product.
  IfmaRows(const SpectralOperator<fx::Q32>& op, bool parallel, std::size_t fuse_from)
      : op_(op), parallel_(parallel), fuse_from_(fuse_from) {
    std::uint64_t mbits = 0;
    for (const fx::Q32 v : op_.m) mbits |= spectral::magnitude_bits(v.raw);
    if ((mbits >> 32) != 0) return;  // m_fits_ stays false
    m32_.resize(op_.m.size());
    msum_.assign(op_.n, 0);
    const Graph& gr = *op_.graph;
    std::atomic<bool> wide{false};
    spectral::for_row_blocks(op_.n, parallel_, [&](std::size_t lo, std::size_t hi) {
      for (std::size_t i = lo; i < hi; ++i) {
        u128 sum = 0;
        for (std::uint64_t k = gr.row_ptr[i]; k < gr.row_ptr[i + 1]; ++k) {
          m32_[k] = static_cast<std::uint32_t>(op_.m[k].raw);
          sum += m32_[k];
        }
        if ((sum >> 64) != 0) wide = true;
        msum_[i] = static_cast<std::uint64_t>(sum);
      }
    });
    m_fits_ = !wide;
    if (!m_fits_) {
      std::vector<std::uint32_t>().swap(m32_);
      std::vector<std::uint64_t>().swap(msum_);
    }
  }

  bool holds_entries() const override { return m_fits_; }
  void restore_entries(std::vector<fx::Q32>& m) const override {
    m.resize(m32_.size());
    for (std::size_t k = 0; k < m32_.size(); ++k) m[k] = fx::Q32::from_raw(static_cast<std::int64_t>(m32_[k]));
  }

  void apply(const fx::Q32* x_in, std::span<const std::int64_t> coef, fx::Q32* y, std::size_t count) override {
    run(x_in, count, coef, y, count);
  }
  bool apply_strided(const fx::Q32* x, std::size_t ld, std::span<const std::int64_t> coef, fx::Q32* y,
                     std::size_t count) override {
    run(x, ld, coef, y, count);
    return true;
  }
  // The filter's step (R1-SPEC-075): each task forms its rows of L~ x a piece at a time into a
  // block of its own (zero past count, as the solver's blocks are), then runs the recurrence on
  // those rows of x and p while they are in cache. Taken on the solver's line-wide blocks from
  // fuse_from_ rows.
  bool apply_three_term(const fx::Q32* x, std::size_t ld, std::span<const std::int64_t> coef, fx::Q32* p,
                        std::size_t count, double alpha, double beta, double gamma) override {
    if (ld != kLanes || reinterpret_cast<std::uintptr_t>(x) % 64 != 0 || count > kLanes || op_.n < fuse_from_) return false;
    const std::size_t n = op_.n;
    tbb::enumerable_thread_specific<std::vector<fx::Q32>> scratch;
    // Pieces of kFuse rows: the recurrence reads and writes 3 x 16 KB beside the gathers' lines.
    constexpr std::size_t kFuse = 256;
    spectral::for_row_blocks(n, parallel_, [&](std::size_t lo, std::size_t hi) {
      std::vector<fx::Q32>& s = scratch.local();
      if (s.size() != kFuse * ld) s.assign(kFuse * ld, fx::Q32{});  // entries past count: zero, never written
      for (std::size_t a = lo; a < hi; a += kFuse) {
        const std::size_t b = std::min(hi, a + kFuse);
        for (std::size_t i = a; i < b; ++i) row(x, ld, coef, count, i, s.data() + (i - a) * ld);
        three_term_ifma((b - a) * ld, s.data(), x + a * ld, p + a * ld, alpha, beta, gamma, false);
      }
    });
    return true;
  }

 private:
  // Rows of x and y ld entries apart (ld >= count).
  void run(const fx::Q32* x_in, std::size_t ldx, std::span<const std::int64_t> coef, fx::Q32* y, std::size_t count) {
    const std::size_t n = op_.n;
    // The gathers read x from a copy whose rows are 8 entries (one 64-byte line) apart and
    // line-aligned when a row would straddle lines: 7 entries 56 bytes apart straddle two lines
    // 7 times in 8, and on large graphs each line of a gather comes from memory (1, 2 and 4
    // entries never straddle). Same values, same sums. A block whose rows are whole aligned
    // lines already (the solver's, R1-SPEC-074) is read in place.
    const fx::Q32* x = x_in;
    std::size_t ld = ldx;
    const bool lines = ldx == kLanes && reinterpret_cast<std::uintptr_t>(x_in) % 64 == 0;
    if (m_fits_ && count < kLanes && kLanes % ldx != 0 && !lines && n >= kPadFrom) {
      ld = kLanes;
      padded_.resize(n * kLanes + kLanes);
      fx::Q32* base = padded_.data();
      base += (64 - reinterpret_cast<std::uintptr_t>(base) % 64) % 64 / sizeof(fx::Q32);
      spectral::for_row_blocks(n, parallel_, [&](std::size_t lo, std::size_t hi) { pad_rows(x_in, ldx, count, base, lo, hi); });
      x = base;
    }
    spectral::for_row_blocks(n, parallel_, [&](std::size_t lo, std::size_t hi) {
      for (std::size_t i = lo; i < hi; ++i) row(x, ld, coef, count, i, y + i * ldx);
    });
  }

  // Row i of L~ x (x's rows ld apart) into out[0 .. count).
  void row(const fx::Q32* x, std::size_t ld, std::span<const std::int64_t> coef, std::size_t count, std::size_t i,
           fx::Q32* out) const {
    const Graph& gr = *op_.graph;
    const std::uint64_t nnz = gr.row_ptr[op_.n];
    const bool rank_one = !op_.g.empty();
    const i128 one = i128{1} << 32;
    const std::uint64_t b = gr.row_ptr[i], e = gr.row_ptr[i + 1];
    if (m_fits_ && !rank_one && count <= kLanes && e - b <= kFlush &&
        ifma_row_rounded(gr.col.data(), m32_.data(), b, e, nnz, x, ld, i, static_cast<__mmask8>((1u << count) - 1),
                         msum_[i], out))
      return;
    for (std::size_t c0 = 0; c0 < count; c0 += kLanes) {
      const std::size_t lanes = std::min(kLanes, count - c0);
      RowSums s{};
      if (m_fits_) ifma_row(gr.col.data(), m32_.data(), b, e, nnz, x, ld, c0, static_cast<__mmask8>((1u << lanes) - 1), s);
      for (std::size_t c = 0; c < lanes; ++c) {
        const std::size_t col = c0 + c;
        const std::int64_t xi = x[i * ld + col].raw;
        if (m_fits_ && (s.bits[c] >> kOffsetBits) == 0) {
          const u128 mx = s.lo[c] + (s.hi[c] << 52) - (static_cast<u128>(msum_[i]) << kOffsetBits);  // sum_k M_ik x_k mod 2^128
          u128 total = static_cast<u128>(static_cast<i128>(xi) * one) - mx;
          if (rank_one) total -= static_cast<u128>(static_cast<i128>(op_.g[i].raw) * coef[col]);
          const i128 r = fx::detail::rne_shift(static_cast<i128>(total), 32);
          if (!fx::detail::fits_i64(r)) fx::detail::throw_overflow("spectral round");
          out[col] = fx::Q32::from_raw(static_cast<std::int64_t>(r));
          continue;
        }
        spectral::FastExact acc;  // an entry beyond the offset range: product by product
        acc.add(static_cast<i128>(xi) * one);
        for (std::uint64_t k = b; k < e; ++k)
          acc.add(-(static_cast<i128>(m_fits_ ? static_cast<std::int64_t>(m32_[k]) : op_.m[k].raw) *
                    x[static_cast<std::size_t>(gr.col[k]) * ld + col].raw));
        if (rank_one) acc.add(-(static_cast<i128>(op_.g[i].raw) * coef[col]));
        out[col] = fx::Q32::from_raw(acc.round_shift(32));
      }
    }
  }

  const SpectralOperator<fx::Q32>& op_;
  bool parallel_;
  std::size_t fuse_from_;
  std::vector<std::uint32_t> m32_;  // M's raws, when m_fits_
  std::vector<std::uint64_t> msum_;
  bool m_fits_ = false;
  std::vector<fx::Q32> padded_;  // x with rows of 8 entries, kept across applications
};

}  // namespace

Q32RowsFactory rows_factory(Simd level, bool parallel, std::size_t fuse_from) {
  if (level != Simd::kAvx512Ifma) return {};
  return [parallel, fuse_from](const SpectralOperator<fx::Q32>& op) -> std::unique_ptr<spectral::BlockRows> {
    if (static_cast<int>(detect_simd()) < static_cast<int>(Simd::kAvx512Ifma)) return nullptr;
    return std::make_unique<IfmaRows>(op, parallel, fuse_from);
  };
}

#else  // not x86-64: no IFMA, so the solver's own rows (R1-BKD-045)

Q32RowsFactory rows_factory(Simd, bool, std::size_t) { return {}; }

#endif

}  // namespace r1::accel::cpu
