// The cpu backend's spectral kernels (R1-BKD-040..044): exact Q32 inner products vectorised with
// AVX-512 IFMA or AVX2 and combinations with AVX-512 IFMA, chosen at run time, beside the portable
// path; the other kernels are the solver's own on TBB tasks.
//
// The vector paths compute the same exact sums as the portable kernels by another grouping.
// Entries are offset to x' = x + 2^51, which lies in [0, 2^52) whenever |x| < 2^51 (magnitude
// bits say so; otherwise the pair, or the row of a combination, takes the exact product-by-product
// sum). Then sum x w = sum x' w' - 2^51 (sum x' + sum w') + rows 2^102, every term an integer,
// formed modulo 2^128 and read as i128 (the true value is far inside its range):
//   * IFMA inner products: a lane per (list column, block column) pair accumulates the low and
//     the high 52 bits of x' w' (sum x' w' = LO + 2^52 HI) over a chunk of at most 2048 rows, so
//     no lane passes 2^63.
//   * AVX2 inner products: x' = a 2^26 + b (a, b < 2^26), x' w' = ac 2^52 + (ad + bc) 2^26 + bd,
//     lanes over rows of transposed tiles; a lane takes at most 4096 / 4 = 1024 rows, so the
//     middle sum stays below 2^63 and the others below 2^62.
//   * IFMA combinations: see CombinePlan below (coefficients offset by 2^63, two limbs).
// The totals enter the same spectral::FastExact and the same one rounding as the portable
// kernels', so every inner product and every combined entry is the portable one's bit for bit
// (tests: panel_kernels_test).
#include "r1/accel/cpu/panel_kernels.hpp"

// The vector kernels are x86-64's (R1-BKD-045): elsewhere (aarch64) the level is always portable,
// and the kernels are the solver's own on TBB tasks.
#if defined(__x86_64__)
#define R1_CPU_X86 1
#include <immintrin.h>
#else
#define R1_CPU_X86 0
#endif

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include "r1/solvers/exact_round.hpp"
#if R1_CPU_X86
#include "wide_lanes.hpp"
#endif


namespace r1::accel::cpu {

using spectral::Cols;
using spectral::FastExact;
using spectral::Panel;
using spectral::PanelOps;

std::string_view simd_name(Simd s) {
  switch (s) {
    case Simd::kPortable: return "portable";
    case Simd::kAvx2: return "avx2";
    case Simd::kAvx512Ifma: return "avx512ifma";
  }
  return "?";
}

std::optional<Simd> simd_from_name(std::string_view name) {
  for (Simd s : {Simd::kPortable, Simd::kAvx2, Simd::kAvx512Ifma})
    if (simd_name(s) == name) return s;
  return std::nullopt;
}

Simd detect_simd() {
#if R1_CPU_X86
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512ifma")) return Simd::kAvx512Ifma;
  if (__builtin_cpu_supports("avx2")) return Simd::kAvx2;
#endif
  return Simd::kPortable;
}

Simd chosen_simd(std::string* error) {
  const Simd best = detect_simd();
  const char* env = std::getenv("R1_CPU_SIMD");
  if (env == nullptr || *env == '\0') return best;
  const auto s = simd_from_name(env);
  if (!s) {
    if (error) *error = "R1_CPU_SIMD: unknown level '" + std::string(env) + "' (portable, avx2, avx512ifma)";
    return best;
  }
  if (static_cast<int>(*s) > static_cast<int>(best)) {
    if (error) *error = "R1_CPU_SIMD: this CPU does not run " + std::string(env) + " (best: " + std::string(simd_name(best)) + ")";
    return best;
  }
  return *s;
}

#if R1_CPU_X86

namespace {

constexpr std::size_t kTile = 64;                        // rows per tile (a multiple of 8)
constexpr int kOffsetBits = 51;                          // |x| < 2^51 takes the vector path
constexpr std::uint64_t kOffset = std::uint64_t{1} << kOffsetBits;
static_assert(spectral::kBlock <= 4096, "the lane bounds above assume row blocks of at most 4096");

// The AVX2 scratch of one row block: the tile's offset columns and, per pair, the lane sums.
struct Scratch {
  std::vector<std::uint64_t> x, w;  // column-major tiles, two halves per column: column q at x + 2 q kTile
  std::vector<std::uint64_t> lanes; // per pair: AC[4], MID[4], BD[4]
  std::vector<i128> sx, sw;         // sum of the raw entries per column over the block
  std::vector<std::uint64_t> qbits, wbits;
};

// A run of `count` consecutive panel columns from `col`, list entries (or terms) at .. at + count - 1.
struct TermRun {
  std::size_t at = 0, col = 0, count = 0;
};

std::vector<TermRun> term_runs(Cols terms) {
  std::vector<TermRun> runs;
  for (std::size_t t = 0; t < terms.size(); ++t) {
    if (!runs.empty() && terms[t] == runs.back().col + runs.back().count) {
      ++runs.back().count;
    } else {
      runs.push_back(TermRun{t, terms[t], 1});
    }
  }
  return runs;
}

// ---- AVX-512 IFMA inner products ---------------------------------------------------------------
//
// Row-major, no transposition: each tile's list entries are copied compact (one contiguous copy
// per run of consecutive columns), a vector holds 8 list columns of one row, each lane
// one pair's sums against a broadcast entry of a block column. Chunks of at most 2048 rows keep
// every lane below 2^63 (terms below 2^52), and the block columns' offset entries of a chunk
// (2048 x nw) stay in L2.
constexpr std::size_t kChunk = 2048;
constexpr std::size_t kMaxGroup = 8;  // block columns per pass over the chunk: 16 accumulators

// A list in panel order, so that its runs are as long as they can be: a step's list is the
// trivial column, the locked columns in eigenvalue order and the basis, which in panel order is
// one run (the near list two). order[k] is the list position of cols[k], the k-th column in that
// order. Formed once per call of dots(), not per row block.
struct PanelOrder {
  std::vector<std::uint32_t> order, cols;
  std::vector<TermRun> runs;  // cols as runs of consecutive columns
};

PanelOrder panel_order(Cols qs) {
  PanelOrder o;
  o.order.resize(qs.size());
  std::iota(o.order.begin(), o.order.end(), 0u);
  std::stable_sort(o.order.begin(), o.order.end(), [&qs](std::uint32_t a, std::uint32_t b) { return qs[a] < qs[b]; });
  o.cols.resize(qs.size());
  for (std::size_t k = 0; k < qs.size(); ++k) o.cols[k] = qs[o.order[k]];
  o.runs = term_runs(o.cols);
  return o;
}

struct IfmaDots {
  std::size_t nq = 0, nq_pad = 0, nw = 0;
  const std::vector<TermRun>* runs = nullptr;  // the list as runs of consecutive columns
  std::vector<std::int64_t> xt;       // the tile's list entries, row-major (kTile x nq_pad)
  std::vector<std::uint64_t> wt;      // chunk rows x nw: w + 2^51
  std::vector<std::uint64_t> lo, hi;  // [c * nq_pad + q]: the pair's lane sums
  std::vector<std::uint64_t> xsum, xbits;  // per q: sum of x + 2^51, magnitude bits
  std::vector<std::uint64_t> wsum, wbits;  // per c
};

// The lanes of a vector of 8 that hold one of `left` remaining entries.
inline __mmask8 tail_mask(std::size_t left) {
  return left >= 8 ? __mmask8{0xFF} : static_cast<__mmask8>((1u << left) - 1);
}

R1_MASKED_SHIFT_WARNING_OFF
template <std::size_t G>
__attribute__((target("avx512f,avx512ifma"))) void ifma_dots_group(std::size_t rows, IfmaDots& d, std::size_t wr0,
                                                                      std::size_t q0, std::size_t c0, bool first) {
  const __mmask8 mask = tail_mask(d.nq - q0);
  const __m512i off = _mm512_set1_epi64(static_cast<long long>(kOffset));
  __m512i lo[G], hi[G];
#pragma GCC unroll 8
  for (std::size_t j = 0; j < G; ++j) {
    lo[j] = _mm512_loadu_si512(d.lo.data() + (c0 + j) * d.nq_pad + q0);
    hi[j] = _mm512_loadu_si512(d.hi.data() + (c0 + j) * d.nq_pad + q0);
  }
  __m512i sx = _mm512_loadu_si512(d.xsum.data() + q0), bx = _mm512_loadu_si512(d.xbits.data() + q0);
  for (std::size_t r = 0; r < rows; ++r) {
    const __m512i x = _mm512_maskz_loadu_epi64(mask, d.xt.data() + r * d.nq_pad + q0);
    const __m512i xo = _mm512_add_epi64(x, off);
    if (first) {
      bx = _mm512_or_si512(bx, _mm512_xor_si512(x, _mm512_srai_epi64(x, 63)));
      sx = _mm512_add_epi64(sx, xo);
    }
    const std::uint64_t* wr = d.wt.data() + wr0 + r * d.nw + c0;
#pragma GCC unroll 8  // unrolled, the accumulators stay in registers (else a store and a load per IFMA)
    for (std::size_t j = 0; j < G; ++j) {
      const __m512i b = _mm512_set1_epi64(static_cast<long long>(wr[j]));
      lo[j] = _mm512_madd52lo_epu64(lo[j], xo, b);
      hi[j] = _mm512_madd52hi_epu64(hi[j], xo, b);
    }
  }
#pragma GCC unroll 8
  for (std::size_t j = 0; j < G; ++j) {
    _mm512_storeu_si512(d.lo.data() + (c0 + j) * d.nq_pad + q0, lo[j]);
    _mm512_storeu_si512(d.hi.data() + (c0 + j) * d.nq_pad + q0, hi[j]);
  }
  if (first) {
    _mm512_storeu_si512(d.xsum.data() + q0, sx);
    _mm512_storeu_si512(d.xbits.data() + q0, bx);
  }
}

R1_MASKED_SHIFT_WARNING_ON

// Tiles of kTile rows (about 100 KB of the widest panels, kept in L2 while every group of list
// columns passes over them), the accumulators carried in memory between tiles. A tile's list
// entries are copied compact, a run of columns at a time (the solver's lists are the trivial and
// locked columns, then one run of basis columns), and its rows' block-column entries are
// offset beside them while those rows are in the cache.
void ifma_dots_chunk(const Panel<fx::Q32>& p, Cols ws, std::size_t r0, std::size_t rows, IfmaDots& d) {
  d.xt.resize(kTile * d.nq_pad);
  for (std::size_t t0 = 0; t0 < rows; t0 += kTile) {
    const std::size_t tr = std::min(kTile, rows - t0);
    for (std::size_t r = 0; r < tr; ++r) {
      const fx::Q32* row = p.row(r0 + t0 + r);
      std::int64_t* dst = d.xt.data() + r * d.nq_pad;
      for (const TermRun& run : *d.runs) std::memcpy(dst + run.at, &row[run.col].raw, run.count * sizeof(std::int64_t));
      std::uint64_t* wr = d.wt.data() + (t0 + r) * d.nw;
      for (std::size_t c = 0; c < d.nw; ++c) {
        const std::int64_t v = row[ws[c]].raw;
        const std::uint64_t o = static_cast<std::uint64_t>(v) + kOffset;  // wraps only when the bits refuse it
        wr[c] = o;
        d.wsum[c] += o;  // below 2048 2^52 = 2^63 whenever the bits allow the pair
        d.wbits[c] |= spectral::magnitude_bits(v);
      }
    }
    const std::size_t wr = t0 * d.nw;  // the tile's first row of the block columns' entries
    for (std::size_t q0 = 0; q0 < d.nq; q0 += 8)
      for (std::size_t c0 = 0; c0 < d.nw; c0 += kMaxGroup) {
        const bool first = c0 == 0;
        switch (std::min(kMaxGroup, d.nw - c0)) {
          case 1: ifma_dots_group<1>(tr, d, wr, q0, c0, first); break;
          case 2: ifma_dots_group<2>(tr, d, wr, q0, c0, first); break;
          case 3: ifma_dots_group<3>(tr, d, wr, q0, c0, first); break;
          case 4: ifma_dots_group<4>(tr, d, wr, q0, c0, first); break;
          case 5: ifma_dots_group<5>(tr, d, wr, q0, c0, first); break;
          case 6: ifma_dots_group<6>(tr, d, wr, q0, c0, first); break;
          case 7: ifma_dots_group<7>(tr, d, wr, q0, c0, first); break;
          default: ifma_dots_group<8>(tr, d, wr, q0, c0, first); break;
        }
      }
  }
}

// ---- AVX2 ------------------------------------------------------------------------------------

__attribute__((target("avx2"))) inline __m256i ld(const std::uint64_t* p) {
  return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
}

// Tiles hold a = x' >> 26 in the first kTile entries of a column and b = x' mod 2^26 in the next
// kTile; lanes per pair: AC[4], MID[4], BD[4].
__attribute__((target("avx2"))) void avx2_tile(const std::uint64_t* x, std::size_t nq, const std::uint64_t* w,
                                               std::size_t nw, std::uint64_t* lanes) {
  for (std::size_t q = 0; q < nq; ++q) {
    const std::uint64_t* xa = x + q * 2 * kTile;
    const std::uint64_t* xb = xa + kTile;
    for (std::size_t c = 0; c < nw; ++c) {
      std::uint64_t* l = lanes + (q * nw + c) * 12;
      __m256i ac = ld(l), mid = ld(l + 4), bd = ld(l + 8);
      const std::uint64_t* wc = w + c * 2 * kTile;
      const std::uint64_t* wd = wc + kTile;
      for (std::size_t v = 0; v < kTile / 4; ++v) {
        const __m256i a = ld(xa + v * 4), b = ld(xb + v * 4), cc = ld(wc + v * 4), d = ld(wd + v * 4);
        ac = _mm256_add_epi64(ac, _mm256_mul_epu32(a, cc));
        mid = _mm256_add_epi64(mid, _mm256_add_epi64(_mm256_mul_epu32(a, d), _mm256_mul_epu32(b, cc)));
        bd = _mm256_add_epi64(bd, _mm256_mul_epu32(b, d));
      }
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(l), ac);
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(l + 4), mid);
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(l + 8), bd);
    }
  }
}

u128 avx2_total(const std::uint64_t* l) {
  u128 ac = 0, mid = 0, bd = 0;
  for (int k = 0; k < 4; ++k) {
    ac += l[k];
    mid += l[4 + k];
    bd += l[8 + k];
  }
  return (ac << 52) + (mid << 26) + bd;
}

// ---- combinations on AVX-512 IFMA --------------------------------------------------------------
//
// A combination's output entry is RNE((base 2^60 + sum_t c_t x_t) / 2^60) with c_t the
// coefficients as multiples of 2^-60 (spectral::coef60, |c_t| < 2^63) and x_t the row's term
// entries. With c' = c + 2^63 in [0, 2^64) split as c0 + 2^52 c1 (c0 < 2^52, c1 < 2^12) and
// x' = x + 2^51 in [0, 2^52) (|x| < 2^51; a row with a larger entry takes the exact scalar sum):
//   sum c x = sum c' x' - 2^51 sum c' - 2^63 sum x' + nt 2^114,
//   sum c' x' = L0 + 2^52 (H0 + L1) + 2^104 H1,
// where L0/H0 and L1/H1 are the low and high 52-bit halves of c0 x' and c1 x' summed per lane
// (nt < 2^11 terms below 2^52 each: no lane wraps). Every quantity is formed modulo 2^128; the
// true total is below 2^125 + 2^123 in magnitude, so its i128 reading is exact, and the rounding
// is the portable kernel's.
constexpr std::size_t kMaxIfmaTerms = 2047;
constexpr std::size_t kCombineRows = 4;  // rows a combination takes together

struct CombinePlan {
  std::size_t no = 0, nt = 0, no_pad = 0;
  std::vector<std::uint64_t> c0, c1;  // [t * no_pad + o], zero past no
  std::vector<u128> csum;             // sum_t c'_t per output
  std::vector<std::uint64_t> k_lo, k_hi;  // nt 2^114 - 2^51 csum per output, mod 2^128, zero past no
  std::vector<std::int64_t> coef;     // the multiples of 2^-60 [t * no + o], for the exact scalar rows
};

// R rows, outputs og .. og + 7: a lane per output, each row's offset term entry broadcast against
// the term's coefficients, which are loaded once for the R rows (a thick restart's coefficients
// are 200 KB, far beyond the first-level cache). sums[r][k * no_pad + o] receives row r's L0, H0,
// L1, H1 (k = 0..3).
template <std::size_t R>
__attribute__((target("avx512f,avx512ifma"))) void ifma_combine_rows(const CombinePlan& plan,
                                                                        const std::uint64_t* const* xo, std::size_t og,
                                                                        std::uint64_t* const* sums) {
  __m512i l0[R], h0[R], l1[R], h1[R];
  for (std::size_t r = 0; r < R; ++r) l0[r] = h0[r] = l1[r] = h1[r] = _mm512_setzero_si512();
  const std::uint64_t* a = plan.c0.data() + og;
  const std::uint64_t* b = plan.c1.data() + og;
  for (std::size_t t = 0; t < plan.nt; ++t, a += plan.no_pad, b += plan.no_pad) {
    const __m512i ca = _mm512_loadu_si512(a), cb = _mm512_loadu_si512(b);
#pragma GCC unroll 8  // the accumulators stay in registers only when the rows are unrolled
    for (std::size_t r = 0; r < R; ++r) {
      const __m512i x = _mm512_set1_epi64(static_cast<long long>(xo[r][t]));
      l0[r] = _mm512_madd52lo_epu64(l0[r], x, ca);
      h0[r] = _mm512_madd52hi_epu64(h0[r], x, ca);
      l1[r] = _mm512_madd52lo_epu64(l1[r], x, cb);
      h1[r] = _mm512_madd52hi_epu64(h1[r], x, cb);
    }
  }
  const std::size_t np = plan.no_pad;
  for (std::size_t r = 0; r < R; ++r) {
    _mm512_storeu_si512(sums[r] + og, l0[r]);
    _mm512_storeu_si512(sums[r] + np + og, h0[r]);
    _mm512_storeu_si512(sums[r] + 2 * np + og, l1[r]);
    _mm512_storeu_si512(sums[r] + 3 * np + og, h1[r]);
  }
}

// A row's term entries, run by run: xo = x + 2^51, their sum and the OR of their magnitude bits,
// 8 at a time (a run's last vector masked), reduced once for the row.
R1_MASKED_SHIFT_WARNING_OFF
__attribute__((target("avx512f,avx512ifma"))) void ifma_offset_row(const std::int64_t* row, const std::vector<TermRun>& runs,
                                                                      std::uint64_t* xo, std::uint64_t& sum, std::uint64_t& bits) {
  const __m512i off = _mm512_set1_epi64(static_cast<long long>(kOffset));
  __m512i vs = _mm512_setzero_si512(), vb = _mm512_setzero_si512();
  for (const TermRun& run : runs) {
    const std::int64_t* x = row + run.col;
    std::uint64_t* out = xo + run.at;
    for (std::size_t t = 0; t < run.count; t += 8) {
      const __mmask8 mask = tail_mask(run.count - t);
      const __m512i v = _mm512_maskz_loadu_epi64(mask, x + t);
      const __m512i o = _mm512_maskz_add_epi64(mask, v, off);
      _mm512_mask_storeu_epi64(out + t, mask, o);
      vs = _mm512_add_epi64(vs, o);
      vb = _mm512_or_si512(vb, _mm512_xor_si512(v, _mm512_srai_epi64(v, 63)));
    }
  }
  alignas(64) std::uint64_t ls[8], lb[8];
  _mm512_store_si512(ls, vs);
  _mm512_store_si512(lb, vb);
  sum = bits = 0;
  for (int k = 0; k < 8; ++k) {
    sum += ls[k];
    bits |= lb[k];
  }
}
R1_MASKED_SHIFT_WARNING_ON

// The one rounding of outputs og .. og + 7 of a row whose entries all took the vector path: per
// lane the total of the scalar epilogue in CpuPanelOps::combine,
//   L0 + 2^52 (H0 + L1) + 2^104 H1 + (nt 2^114 - 2^51 sum c') - 2^63 sum x' + base 2^60,
// formed modulo 2^128 as two 64-bit halves (H0 + L1 < 2^64: both below 2^63), then RNE(. / 2^60)
// as fx::detail::rne_shift does it. `k_lo`/`k_hi` hold the per-output constant, `base` the
// row's base entries (or null). Writes 8 results to out + og; false when a lane below `no`
// does not fit 64 bits (the caller's scalar epilogue then reports it).
R1_MASKED_SHIFT_WARNING_OFF
__attribute__((target("avx512f"))) bool ifma_round8(const std::uint64_t* sums, std::size_t np, std::size_t og, std::size_t no,
                                                    const std::uint64_t* k_lo, const std::uint64_t* k_hi, std::uint64_t xsum,
                                                    const std::int64_t* base, std::int64_t* out) {
  const __m512i l0 = _mm512_loadu_si512(sums + og), h0 = _mm512_loadu_si512(sums + np + og);
  const __m512i l1 = _mm512_loadu_si512(sums + 2 * np + og), h1 = _mm512_loadu_si512(sums + 3 * np + og);
  const __m512i b = _mm512_add_epi64(h0, l1);
  Wide t{l0, _mm512_slli_epi64(h1, 40)};  // L0 + 2^104 H1
  t = wide_add(t, _mm512_slli_epi64(b, 52), _mm512_srli_epi64(b, 12));   // + 2^52 (H0 + L1)
  t = wide_add(t, _mm512_loadu_si512(k_lo + og), _mm512_loadu_si512(k_hi + og));  // + nt 2^114 - 2^51 sum c'
  t = wide_sub(t, _mm512_set1_epi64(static_cast<long long>(xsum << 63)), _mm512_set1_epi64(static_cast<long long>(xsum >> 1)));  // - 2^63 sum x'
  if (base != nullptr) {  // + base 2^60, sign-extended
    const __m512i bv = _mm512_loadu_si512(base + og);
    t = wide_add(t, _mm512_slli_epi64(bv, 60), _mm512_srai_epi64(bv, 4));
  }
  __mmask8 ok = 0;
  _mm512_storeu_si512(out + og, wide_rne_shift<60>(t, ok));
  return (static_cast<__mmask8>(~ok) & tail_mask(no - og)) == 0;
}
R1_MASKED_SHIFT_WARNING_ON

// ---- the Chebyshev filter's recurrence on AVX-512 IFMA ------------------------------------------
//
// p[k] <- RNE((a s[k] + b y[k] + g p[k]) / 2^60) (spectral::three_term) is a combination of nt = 2
// or 3 terms with the same coefficients for every entry, so here a lane is an entry and the
// coefficients are broadcast: the identity of the combinations above, with the per-entry sum of
// the offset terms in place of the per-row one. The constant nt 2^114 - 2^51 sum c' is the same
// for every lane.
struct ThreeTermPlan {
  std::size_t nt = 0;
  std::uint64_t c0[3] = {}, c1[3] = {};
  std::uint64_t k_lo = 0, k_hi = 0;
};

// Entries k .. k + 7 under `mask`; false, with p untouched, when a term lies beyond the offset
// range or a result does not fit 64 bits (the caller then takes the portable path, which rounds
// the first and reports the second).
R1_MASKED_SHIFT_WARNING_OFF
__attribute__((target("avx512f,avx512ifma"))) bool ifma_three_term8(const ThreeTermPlan& plan, const std::int64_t* s,
                                                                       const std::int64_t* y, std::int64_t* p,
                                                                       __mmask8 mask) {
  const __m512i off = _mm512_set1_epi64(static_cast<long long>(kOffset));
  const __m512i x[3] = {_mm512_maskz_loadu_epi64(mask, s), _mm512_maskz_loadu_epi64(mask, y),
                        plan.nt == 3 ? _mm512_maskz_loadu_epi64(mask, p) : _mm512_setzero_si512()};
  __m512i l0 = _mm512_setzero_si512(), h0 = l0, l1 = l0, h1 = l0, xsum = l0, bits = l0;
  for (std::size_t t = 0; t < plan.nt; ++t) {
    bits = _mm512_or_si512(bits, _mm512_xor_si512(x[t], _mm512_srai_epi64(x[t], 63)));
    const __m512i xo = _mm512_add_epi64(x[t], off);
    xsum = _mm512_add_epi64(xsum, xo);
    const __m512i ca = _mm512_set1_epi64(static_cast<long long>(plan.c0[t]));
    const __m512i cb = _mm512_set1_epi64(static_cast<long long>(plan.c1[t]));
    l0 = _mm512_madd52lo_epu64(l0, xo, ca);
    h0 = _mm512_madd52hi_epu64(h0, xo, ca);
    l1 = _mm512_madd52lo_epu64(l1, xo, cb);
    h1 = _mm512_madd52hi_epu64(h1, xo, cb);
  }
  if (_mm512_test_epi64_mask(bits, _mm512_set1_epi64(static_cast<long long>(~((std::uint64_t{1} << kOffsetBits) - 1)))) != 0)
    return false;
  const __m512i b = _mm512_add_epi64(h0, l1);
  Wide t{l0, _mm512_slli_epi64(h1, 40)};                                  // L0 + 2^104 H1
  t = wide_add(t, _mm512_slli_epi64(b, 52), _mm512_srli_epi64(b, 12));  // + 2^52 (H0 + L1)
  t = wide_add(t, _mm512_set1_epi64(static_cast<long long>(plan.k_lo)), _mm512_set1_epi64(static_cast<long long>(plan.k_hi)));
  t = wide_sub(t, _mm512_slli_epi64(xsum, 63), _mm512_srli_epi64(xsum, 1));  // - 2^63 sum x'
  __mmask8 ok = 0;
  const __m512i r = wide_rne_shift<60>(t, ok);
  if ((static_cast<__mmask8>(~ok) & mask) != 0) return false;
  _mm512_mask_storeu_epi64(p, mask, r);
  return true;
}
R1_MASKED_SHIFT_WARNING_ON

// Columns `cols` of rows t0 .. t0 + rows - 1, offset by 2^51,  and split into the high and the low
// 26 bits, into a column-major tile (two kTile runs per column), adding each column's raw
// entries to sum[] and its magnitude bits to bits[]. An entry of 2^51 or more wraps here; the bits
// then send its pair to the exact fall-back, which never reads the tile. The tile's sum is formed
// in 64 bits: below 2^57 whenever the bits allow the vector path (64 entries below 2^51).
void transpose(const Panel<fx::Q32>& p, Cols cols, std::size_t t0, std::size_t rows, std::uint64_t* tile, i128* sum,
               std::uint64_t* bits) {
  constexpr std::size_t per_col = 2 * kTile;
  constexpr std::uint64_t low26 = (std::uint64_t{1} << 26) - 1;
  const std::size_t nc = cols.size();
  std::uint64_t tile_sum[64], tile_bits[64];
  for (std::size_t c0 = 0; c0 < nc; c0 += 64) {
    const std::size_t nb = std::min<std::size_t>(64, nc - c0);
    for (std::size_t k = 0; k < nb; ++k) tile_sum[k] = tile_bits[k] = 0;
    for (std::size_t i = 0; i < rows; ++i) {
      const fx::Q32* row = p.row(t0 + i);
      for (std::size_t k = 0; k < nb; ++k) {
        const std::int64_t v = row[cols[c0 + k]].raw;
        const std::uint64_t o = static_cast<std::uint64_t>(v) + kOffset;
        std::uint64_t* col = tile + (c0 + k) * per_col;
        col[i] = (o >> 26) & low26;
        col[kTile + i] = o & low26;
        tile_sum[k] += static_cast<std::uint64_t>(v);  // wraps only when the bits refuse the pair
        tile_bits[k] |= spectral::magnitude_bits(v);
      }
    }
    for (std::size_t k = 0; k < nb; ++k) {
      sum[c0 + k] += static_cast<std::int64_t>(tile_sum[k]);
      bits[c0 + k] |= tile_bits[k];
    }
  }
}

// The exact fall-back for one pair over rows [lo, hi): product by product.
void exact_pair(const Panel<fx::Q32>& p, std::uint32_t a, std::uint32_t b, std::size_t lo, std::size_t hi, FastExact& acc) {
  for (std::size_t i = lo; i < hi; ++i) acc.add(static_cast<i128>(p.at(i, a).raw) * p.at(i, b).raw);
}

// The kernels: the solver's, with dots() on the vector paths.
class CpuPanelOps final : public PanelOps<fx::Q32> {
 public:
  CpuPanelOps(std::size_t n, int e, bool parallel, int frac, Simd level)
      : PanelOps<fx::Q32>(n, e, parallel, frac), level_(level) {}

  void dots(const Panel<fx::Q32>& p, Cols qs, Cols ws, std::span<double> out) const override;
  void combine(Panel<fx::Q32>& p, Cols outs, Cols bases, Cols terms, std::span<const double> coef) const override;
  void three_term(std::size_t len, const fx::Q32* s, const fx::Q32* y, fx::Q32* p, double alpha, double beta,
                  double gamma) const override;

 private:
  void avx2_block_sum(const Panel<fx::Q32>& p, Cols qs, Cols ws, std::size_t lo, std::size_t hi, Scratch& s,
                      std::vector<FastExact>& acc) const;
  void ifma_block_sum(const Panel<fx::Q32>& p, const PanelOrder& qs, Cols ws, std::size_t lo, std::size_t hi, IfmaDots& d,
                      std::vector<FastExact>& acc) const;
  Simd level_;
};

void CpuPanelOps::avx2_block_sum(const Panel<fx::Q32>& p, Cols qs, Cols ws, std::size_t lo, std::size_t hi, Scratch& s,
                                 std::vector<FastExact>& acc) const {
  const std::size_t nq = qs.size(), nw = ws.size(), pairs = nq * nw, per_col = 2 * kTile, per_pair = 12;
  s.x.assign(nq * per_col, 0);
  s.w.assign(nw * per_col, 0);
  s.lanes.assign(pairs * per_pair, 0);
  s.sx.assign(nq, 0);
  s.sw.assign(nw, 0);
  s.qbits.assign(nq, 0);
  s.wbits.assign(nw, 0);
  for (std::size_t t0 = lo; t0 < hi; t0 += kTile) {
    const std::size_t rows = std::min(kTile, hi - t0);
    if (rows < kTile) {  // a short last tile: the rows past the end stay 0 and add nothing
      std::fill(s.x.begin(), s.x.end(), 0);
      std::fill(s.w.begin(), s.w.end(), 0);
    }
    transpose(p, ws, t0, rows, s.w.data(), s.sw.data(), s.wbits.data());
    transpose(p, qs, t0, rows, s.x.data(), s.sx.data(), s.qbits.data());
    avx2_tile(s.x.data(), nq, s.w.data(), nw, s.lanes.data());
  }
  const i128 rows = static_cast<i128>(hi - lo);
  for (std::size_t q = 0; q < nq; ++q)
    for (std::size_t c = 0; c < nw; ++c) {
      const std::size_t k = q * nw + c;
      if (((s.qbits[q] | s.wbits[c]) >> kOffsetBits) == 0) {
        const u128 t = avx2_total(s.lanes.data() + k * per_pair);
        // sum x' w' < 2^116; the corrections are below 2^115: all exact in i128.
        acc[k].add(static_cast<i128>(t) - (s.sx[q] + s.sw[c]) * static_cast<i128>(kOffset) - rows * (i128{1} << 102));
      } else {
        exact_pair(p, qs[q], ws[c], lo, hi, acc[k]);
      }
    }
}

void CpuPanelOps::ifma_block_sum(const Panel<fx::Q32>& p, const PanelOrder& qs, Cols ws, std::size_t lo, std::size_t hi,
                                 IfmaDots& d, std::vector<FastExact>& acc) const {
  const std::size_t nq = qs.cols.size(), nw = ws.size();
  d.nq = nq;
  d.nw = nw;
  d.nq_pad = (nq + 7) / 8 * 8;
  d.runs = &qs.runs;
  for (std::size_t r0 = lo; r0 < hi; r0 += kChunk) {
    const std::size_t rows = std::min(kChunk, hi - r0);
    d.wt.resize(rows * nw);
    d.wsum.assign(nw, 0);
    d.wbits.assign(nw, 0);
    d.lo.assign(nw * d.nq_pad, 0);
    d.hi.assign(nw * d.nq_pad, 0);
    d.xsum.assign(d.nq_pad, 0);
    d.xbits.assign(d.nq_pad, 0);
    ifma_dots_chunk(p, ws, r0, rows, d);
    // sum x w = sum x' w' - 2^51 (sum x' + sum w') + rows 2^102, formed modulo 2^128: the true
    // value is below 2^11 2^102 in magnitude, so its i128 reading is exact.
    const u128 rows_kk = static_cast<u128>(rows) << 102;
    for (std::size_t q = 0; q < nq; ++q)
      for (std::size_t c = 0; c < nw; ++c) {
        const std::size_t k = qs.order[q] * nw + c;
        if (((d.xbits[q] | d.wbits[c]) >> kOffsetBits) == 0) {
          const std::size_t l = c * d.nq_pad + q;
          const u128 t = static_cast<u128>(d.lo[l]) + (static_cast<u128>(d.hi[l]) << 52) -
                         ((static_cast<u128>(d.xsum[q]) + d.wsum[c]) << kOffsetBits) + rows_kk;
          acc[k].add(static_cast<i128>(t));
        } else {
          exact_pair(p, qs.cols[q], ws[c], r0, r0 + rows, acc[k]);
        }
      }
  }
}

void CpuPanelOps::dots(const Panel<fx::Q32>& p, Cols qs, Cols ws, std::span<double> out) const {
  if (level_ == Simd::kPortable) return PanelOps<fx::Q32>::dots(p, qs, ws, out);
  spectral::check_dots(p.rows(), size(), p.cols(), qs, ws, out.size());
  if (out.empty()) return;
  // The scratch lives per row block (a few KB against 4096 rows of products).
  const PanelOrder order = level_ == Simd::kAvx512Ifma ? panel_order(qs) : PanelOrder{};
  spectral::exact_dots(size(), parallel(), 2 * frac_bits() + scale_exponent(), out,
                       [&](std::size_t lo, std::size_t hi, std::vector<FastExact>& acc) {
                         if (level_ == Simd::kAvx512Ifma) {
                           IfmaDots d;
                           ifma_block_sum(p, order, ws, lo, hi, d, acc);
                         } else {
                           Scratch s;
                           avx2_block_sum(p, qs, ws, lo, hi, s, acc);
                         }
                       });
}

void CpuPanelOps::combine(Panel<fx::Q32>& p, Cols outs, Cols bases, Cols terms, std::span<const double> c) const {
  const std::size_t no = outs.size(), nt = terms.size();
  if (level_ != Simd::kAvx512Ifma || nt == 0 || nt > kMaxIfmaTerms || no == 0)
    return PanelOps<fx::Q32>::combine(p, outs, bases, terms, c);
  spectral::check_combine(p.rows(), size(), p.cols(), outs, bases, terms, c.size());
  CombinePlan plan;
  plan.no = no;
  plan.nt = nt;
  plan.no_pad = (no + 7) / 8 * 8;
  plan.c0.assign(nt * plan.no_pad, 0);
  plan.c1.assign(nt * plan.no_pad, 0);
  plan.coef.resize(nt * no);
  plan.csum.assign(no, 0);
  for (std::size_t t = 0; t < nt; ++t)
    for (std::size_t o = 0; o < no; ++o) {
      const std::int64_t k = spectral::coef60(c[t * no + o]);  // throws on a NaN or |c| >= 8, as the portable kernel does
      plan.coef[t * no + o] = k;
      const std::uint64_t cp = static_cast<std::uint64_t>(k) ^ (std::uint64_t{1} << 63);  // c + 2^63
      plan.c0[t * plan.no_pad + o] = cp & ((std::uint64_t{1} << 52) - 1);
      plan.c1[t * plan.no_pad + o] = cp >> 52;
      plan.csum[o] += cp;
    }
  const u128 nt_ck = static_cast<u128>(nt) << 114;
  const i128 one = i128{1} << 60;
  plan.k_lo.assign(plan.no_pad, 0);
  plan.k_hi.assign(plan.no_pad, 0);
  for (std::size_t o = 0; o < no; ++o) {
    const u128 k = nt_ck - (plan.csum[o] << kOffsetBits);
    plan.k_lo[o] = static_cast<std::uint64_t>(k);
    plan.k_hi[o] = static_cast<std::uint64_t>(k >> 64);
  }
  // The terms as runs of consecutive columns (a pass's terms are two: the block, then the list),
  // each offset 8 entries at a time; a list of scattered columns is many runs of one.
  const std::vector<TermRun> runs = term_runs(terms);
  // The byte spans of a row the combination reads or writes (the term runs, the bases, the
  // outputs), merged: what is prefetched of the rows ahead. A pass's combination reads a tenth of
  // a 209-column row, and at 10^6 rows prefetching whole rows streamed the whole panel.
  std::vector<std::pair<std::size_t, std::size_t>> spans;
  {
    for (const TermRun& run : runs) spans.emplace_back(run.col * sizeof(fx::Q32), (run.col + run.count) * sizeof(fx::Q32));
    for (const Cols cols : {bases, outs})
      for (const std::uint32_t col : cols) spans.emplace_back(col * sizeof(fx::Q32), (col + 1) * sizeof(fx::Q32));
    std::sort(spans.begin(), spans.end());
    std::vector<std::pair<std::size_t, std::size_t>> merged;
    for (const auto& sp : spans) {
      if (!merged.empty() && sp.first <= merged.back().second + 64) merged.back().second = std::max(merged.back().second, sp.second);
      else merged.push_back(sp);
    }
    spans.swap(merged);
  }
  spectral::for_row_blocks(size(), parallel(), [&](std::size_t lo, std::size_t hi) {
    std::vector<std::uint64_t> xo(kCombineRows * nt), sums(kCombineRows * 4 * plan.no_pad);
    std::uint64_t xsum[kCombineRows], bits[kCombineRows];
    const std::uint64_t* xr[kCombineRows];
    std::uint64_t* sr[kCombineRows];
    for (std::size_t r = 0; r < kCombineRows; ++r) {
      xr[r] = xo.data() + r * nt;
      sr[r] = sums.data() + r * 4 * plan.no_pad;
    }
    std::vector<std::int64_t> result(plan.no_pad), base_raw(bases.empty() ? 0 : plan.no_pad, 0);
    // The vector epilogue of row r of the current group into result[]; false when an output
    // does not fit (the scalar epilogue then throws as the portable kernel does).
    const auto vector_round = [&](const fx::Q32* row, std::size_t r) {
      if (!bases.empty())
        for (std::size_t o = 0; o < no; ++o) base_raw[o] = row[bases[o]].raw;
      for (std::size_t og = 0; og < plan.no_pad; og += 8)
        if (!ifma_round8(sr[r], plan.no_pad, og, no, plan.k_lo.data(), plan.k_hi.data(), xsum[r],
                         bases.empty() ? nullptr : base_raw.data(), result.data()))
          return false;
      return true;
    };
    for (std::size_t i0 = lo; i0 < hi; i0 += kCombineRows) {
      const std::size_t rows = std::min(kCombineRows, hi - i0);
      // The next rows' spans on their way to the cache while these are combined (every line a
      // span touches: its first byte, then every 64 bytes, and its last byte).
      for (std::size_t i = i0 + kCombineRows; i < std::min(hi, i0 + 2 * kCombineRows); ++i) {
        const char* ahead = reinterpret_cast<const char*>(p.row(i));
        for (const auto& [b, e] : spans) {
          for (std::size_t at = b; at < e; at += 64) _mm_prefetch(ahead + at, _MM_HINT_T0);
          _mm_prefetch(ahead + e - 1, _MM_HINT_T0);
        }
      }
      // Each row's terms offset by 2^51, their sum (below nt 2^52 < 2^63 whenever the bits allow
      // the row) and the OR of their magnitude bits.
      for (std::size_t r = 0; r < rows; ++r)
        ifma_offset_row(&p.row(i0 + r)->raw, runs, xo.data() + r * nt, xsum[r], bits[r]);
      for (std::size_t og = 0; og < plan.no_pad; og += 8) {
        if (rows == kCombineRows) {
          ifma_combine_rows<kCombineRows>(plan, xr, og, sr);
        } else {
          for (std::size_t r = 0; r < rows; ++r) ifma_combine_rows<1>(plan, xr + r, og, sr + r);
        }
      }
      for (std::size_t r = 0; r < rows; ++r) {
        fx::Q32* row = p.row(i0 + r);
        if ((bits[r] >> kOffsetBits) != 0) {  // an entry beyond the offset range: the exact scalar sum
          for (std::size_t o = 0; o < no; ++o) {
            FastExact acc;
            if (!bases.empty()) acc.add(static_cast<i128>(row[bases[o]].raw) * one);
            for (std::size_t t = 0; t < nt; ++t) acc.add(static_cast<i128>(plan.coef[t * no + o]) * row[terms[t]].raw);
            result[o] = acc.round_shift(60);
          }
        } else if (vector_round(row, r)) {
          // result[] holds the row's outputs
        } else {
          const u128 xs = static_cast<u128>(xsum[r]) << 63;
          const std::size_t np = plan.no_pad;
          for (std::size_t o = 0; o < no; ++o) {
            const std::uint64_t* l = sr[r] + o;
            const u128 cx = static_cast<u128>(l[0]) + ((static_cast<u128>(l[np]) + l[2 * np]) << 52) +
                            (static_cast<u128>(l[3 * np]) << 104);
            const i128 base = bases.empty() ? 0 : static_cast<i128>(row[bases[o]].raw) * one;
            const u128 total = cx - (plan.csum[o] << kOffsetBits) - xs + nt_ck + static_cast<u128>(base);
            const i128 rr = fx::detail::rne_shift(static_cast<i128>(total), 60);
            if (!fx::detail::fits_i64(rr)) fx::detail::throw_overflow("spectral round");
            result[o] = static_cast<std::int64_t>(rr);
          }
        }
        for (std::size_t o = 0; o < no; ++o) row[outs[o]] = fx::Q32::from_raw(result[o]);
      }
    }
  });
}

void CpuPanelOps::three_term(std::size_t len, const fx::Q32* s, const fx::Q32* y, fx::Q32* p, double alpha, double beta,
                             double gamma) const {
  if (level_ != Simd::kAvx512Ifma) return PanelOps<fx::Q32>::three_term(len, s, y, p, alpha, beta, gamma);
  three_term_ifma(len, s, y, p, alpha, beta, gamma, parallel());
}

}  // namespace

void three_term_ifma(std::size_t len, const fx::Q32* s, const fx::Q32* y, fx::Q32* p, double alpha, double beta,
                     double gamma, bool parallel) {
  ThreeTermPlan plan;
  plan.nt = gamma == 0 ? 2 : 3;  // gamma = 0: p is not read, as in the portable kernel
  const double coef[3] = {alpha, beta, gamma};
  u128 csum = 0;
  for (std::size_t t = 0; t < plan.nt; ++t) {
    const std::uint64_t cp = static_cast<std::uint64_t>(spectral::coef60(coef[t])) ^ (std::uint64_t{1} << 63);  // c + 2^63
    plan.c0[t] = cp & ((std::uint64_t{1} << 52) - 1);
    plan.c1[t] = cp >> 52;
    csum += cp;
  }
  const u128 k = (static_cast<u128>(plan.nt) << 114) - (csum << kOffsetBits);
  plan.k_lo = static_cast<std::uint64_t>(k);
  plan.k_hi = static_cast<std::uint64_t>(k >> 64);
  // Row blocks split at multiples of 8, so groups of 8 entries never straddle two tasks.
  spectral::for_row_blocks(len, parallel, [&](std::size_t lo, std::size_t hi) {
    for (std::size_t k0 = lo; k0 < hi; k0 += 8) {
      const std::size_t count = std::min<std::size_t>(8, hi - k0);
      if (!ifma_three_term8(plan, &s[k0].raw, &y[k0].raw, &p[k0].raw, tail_mask(count)))
        spectral::three_term(count, s + k0, y + k0, p + k0, alpha, beta, gamma, false);
    }
  });
}

#else  // R1_CPU_X86

void three_term_ifma(std::size_t len, const fx::Q32* s, const fx::Q32* y, fx::Q32* p, double alpha, double beta,
                     double gamma, bool parallel) {
  spectral::three_term(len, s, y, p, alpha, beta, gamma, parallel);  // never asked for: no IFMA here
}

#endif  // R1_CPU_X86

std::unique_ptr<PanelOps<fx::Q32>> make_panel_kernels(std::size_t n, int e, bool parallel, int frac, Simd level) {
  if (static_cast<int>(level) > static_cast<int>(detect_simd()))
    throw std::invalid_argument("cpu kernels: this CPU does not run " + std::string(simd_name(level)));
#if R1_CPU_X86
  return std::make_unique<CpuPanelOps>(n, e, parallel, frac, level);
#else
  return std::make_unique<PanelOps<fx::Q32>>(n, e, parallel, frac);  // the level is portable here
#endif
}

Q32KernelFactory kernel_factory(Simd level) {
  return [level](std::size_t n, int e, bool parallel, int frac) { return make_panel_kernels(n, e, parallel, frac, level); };
}

}  // namespace r1::accel::cpu
