// The cpu backend's spectral kernels (R1-BKD-040..044): exact Q32 inner products vectorised with
// AVX-512 IFMA or AVX2 and combinations with AVX-512 IFMA, chosen at run time, beside the portable
// path; the other kernels are the solver's own on TBB tasks.
//
// The vector paths compute the same exact sum as the portable one by another grouping. A row
// block's entries are offset to x' = x + 2^51, which lies in [0, 2^52) whenever |x| < 2^51 (the
// block's magnitude bits say so; otherwise the pair falls back to the exact product-by-product
// sum). Then sum x w = sum x' w' - 2^51 (sum x + sum w) - rows 2^102, every term an integer:
//   * AVX-512 IFMA multiplies 52-bit lanes and adds the low and the high 52 bits of each product
//     into separate 64-bit lanes: sum x' w' = LO + 2^52 HI. A lane takes at most 4096 / 8 = 512
//     terms below 2^52, so it stays below 2^61 and never wraps.
//   * AVX2 splits x' = a 2^26 + b (a, b < 2^26) and multiplies 32-bit halves:
//     x' w' = ac 2^52 + (ad + bc) 2^26 + bd. A lane takes at most 4096 / 4 = 1024 rows, so the
//     middle sum stays below 2^63 and the others below 2^62.
// The totals then enter the same spectral::FastExact as the portable kernel's, so the rounded
// double of every inner product is the portable one's bit for bit (tests: panel_kernels_test).
#include "r1/accel/cpu/panel_kernels.hpp"

#include <immintrin.h>
#include <tbb/enumerable_thread_specific.h>

#include <algorithm>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

#include "r1/solvers/exact_round.hpp"

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
#if defined(__x86_64__) || defined(__i386__)
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

namespace {

constexpr std::size_t kTile = 64;                        // rows per transposed tile (a multiple of 8)
constexpr int kOffsetBits = 51;                          // |x| < 2^51 takes the vector path
constexpr std::uint64_t kOffset = std::uint64_t{1} << kOffsetBits;
static_assert(spectral::kBlock <= 4096, "the lane bounds above assume row blocks of at most 4096");

// The scratch of one row block: the tile's offset columns and, per pair, the lane sums.
struct Scratch {
  std::vector<std::uint64_t> x, w;  // column-major tiles: column q at x + q * kTile (AVX2: two halves)
  std::vector<std::uint64_t> lanes; // per pair: 8 (IFMA: LO, HI x 8 lanes ... see kernels) u64
  std::vector<i128> sx, sw;         // sum of the raw entries per column over the block
  std::vector<std::uint64_t> qbits, wbits;
};

// ---- AVX-512 IFMA ----------------------------------------------------------------------------

// lanes per pair: LO[8], HI[8].
__attribute__((target("avx512f,avx512ifma"))) void ifma_tile(const std::uint64_t* x, std::size_t nq,
                                                                const std::uint64_t* w, std::size_t nw,
                                                                std::uint64_t* lanes) {
  for (std::size_t q = 0; q < nq; ++q) {
    const std::uint64_t* xq = x + q * kTile;
    __m512i xv[kTile / 8];
    for (std::size_t v = 0; v < kTile / 8; ++v) xv[v] = _mm512_loadu_si512(xq + v * 8);
    std::size_t c = 0;
    for (; c + 2 <= nw; c += 2) {
      std::uint64_t* l0 = lanes + (q * nw + c) * 16;
      std::uint64_t* l1 = l0 + 16;
      __m512i lo0 = _mm512_loadu_si512(l0), hi0 = _mm512_loadu_si512(l0 + 8);
      __m512i lo1 = _mm512_loadu_si512(l1), hi1 = _mm512_loadu_si512(l1 + 8);
      const std::uint64_t* w0 = w + c * kTile;
      const std::uint64_t* w1 = w0 + kTile;
      for (std::size_t v = 0; v < kTile / 8; ++v) {
        const __m512i a = _mm512_loadu_si512(w0 + v * 8), b = _mm512_loadu_si512(w1 + v * 8);
        lo0 = _mm512_madd52lo_epu64(lo0, xv[v], a);
        hi0 = _mm512_madd52hi_epu64(hi0, xv[v], a);
        lo1 = _mm512_madd52lo_epu64(lo1, xv[v], b);
        hi1 = _mm512_madd52hi_epu64(hi1, xv[v], b);
      }
      _mm512_storeu_si512(l0, lo0);
      _mm512_storeu_si512(l0 + 8, hi0);
      _mm512_storeu_si512(l1, lo1);
      _mm512_storeu_si512(l1 + 8, hi1);
    }
    for (; c < nw; ++c) {
      std::uint64_t* l0 = lanes + (q * nw + c) * 16;
      __m512i lo0 = _mm512_loadu_si512(l0), hi0 = _mm512_loadu_si512(l0 + 8);
      const std::uint64_t* w0 = w + c * kTile;
      for (std::size_t v = 0; v < kTile / 8; ++v) {
        const __m512i a = _mm512_loadu_si512(w0 + v * 8);
        lo0 = _mm512_madd52lo_epu64(lo0, xv[v], a);
        hi0 = _mm512_madd52hi_epu64(hi0, xv[v], a);
      }
      _mm512_storeu_si512(l0, lo0);
      _mm512_storeu_si512(l0 + 8, hi0);
    }
  }
}

// sum x' w' of one pair from its lanes: LO + 2^52 HI.
u128 ifma_total(const std::uint64_t* l) {
  u128 lo = 0, hi = 0;
  for (int k = 0; k < 8; ++k) {
    lo += l[k];
    hi += l[8 + k];
  }
  return lo + (hi << 52);
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

struct CombinePlan {
  std::size_t no = 0, nt = 0;
  std::vector<std::uint64_t> c0, c1;  // [t * no + o]
  std::vector<u128> csum;             // sum_t c'_t per output
  std::vector<std::int64_t> coef;     // the multiples of 2^-60, for the exact scalar rows
};

// Outputs o0 .. o0 + W - 1 of 8 rows: lanes l of acc[] hold row l's sums.
template <std::size_t W>
__attribute__((target("avx512f,avx512ifma"))) void ifma_combine_group(const CombinePlan& plan, const std::uint64_t* xt,
                                                                         std::size_t o0, std::uint64_t* sums) {
  __m512i l0[W], h0[W], l1[W], h1[W];
  for (std::size_t j = 0; j < W; ++j) l0[j] = h0[j] = l1[j] = h1[j] = _mm512_setzero_si512();
  for (std::size_t t = 0; t < plan.nt; ++t) {
    const __m512i x = _mm512_loadu_si512(xt + t * 8);
    const std::uint64_t* a = plan.c0.data() + t * plan.no + o0;
    const std::uint64_t* b = plan.c1.data() + t * plan.no + o0;
    for (std::size_t j = 0; j < W; ++j) {
      const __m512i ca = _mm512_set1_epi64(static_cast<long long>(a[j]));
      const __m512i cb = _mm512_set1_epi64(static_cast<long long>(b[j]));
      l0[j] = _mm512_madd52lo_epu64(l0[j], x, ca);
      h0[j] = _mm512_madd52hi_epu64(h0[j], x, ca);
      l1[j] = _mm512_madd52lo_epu64(l1[j], x, cb);
      h1[j] = _mm512_madd52hi_epu64(h1[j], x, cb);
    }
  }
  for (std::size_t j = 0; j < W; ++j) {
    std::uint64_t* out = sums + (o0 + j) * 32;
    _mm512_storeu_si512(out, l0[j]);
    _mm512_storeu_si512(out + 8, h0[j]);
    _mm512_storeu_si512(out + 16, l1[j]);
    _mm512_storeu_si512(out + 24, h1[j]);
  }
}

__attribute__((target("avx512f,avx512ifma"))) void ifma_combine_rows(const CombinePlan& plan, const std::uint64_t* xt,
                                                                        std::uint64_t* sums) {
  std::size_t o = 0;
  for (; o + 4 <= plan.no; o += 4) ifma_combine_group<4>(plan, xt, o, sums);
  for (; o + 2 <= plan.no; o += 2) ifma_combine_group<2>(plan, xt, o, sums);
  for (; o < plan.no; ++o) ifma_combine_group<1>(plan, xt, o, sums);
}

// Columns `cols` of rows t0 .. t0 + rows - 1, offset by 2^51, into a column-major tile (IFMA: one
// kTile run per column; AVX2: the high and the low 26 bits in two runs), adding each column's raw
// entries to sum[] and its magnitude bits to bits[]. An entry of 2^51 or more wraps here; the bits
// then send its pair to the exact fall-back, which never reads the tile. The tile's sum is formed
// in 64 bits: below 2^57 whenever the bits allow the vector path (64 entries below 2^51).
template <bool kIfma>
void transpose(const Panel<fx::Q32>& p, Cols cols, std::size_t t0, std::size_t rows, std::uint64_t* tile, i128* sum,
               std::uint64_t* bits) {
  constexpr std::size_t per_col = kIfma ? kTile : 2 * kTile;
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
        if constexpr (kIfma) {
          col[i] = o;
        } else {
          col[i] = (o >> 26) & low26;
          col[kTile + i] = o & low26;
        }
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

// The kernels: the solver's, with dots() on the vector paths.
class CpuPanelOps final : public PanelOps<fx::Q32> {
 public:
  CpuPanelOps(std::size_t n, int e, bool parallel, int frac, Simd level)
      : PanelOps<fx::Q32>(n, e, parallel, frac), level_(level) {}

  void dots(const Panel<fx::Q32>& p, Cols qs, Cols ws, std::span<double> out) const override;
  void combine(Panel<fx::Q32>& p, Cols outs, Cols bases, Cols terms, std::span<const double> coef) const override;

 private:
  void block_sum(const Panel<fx::Q32>& p, Cols qs, Cols ws, std::size_t lo, std::size_t hi, Scratch& s,
                 std::vector<FastExact>& acc) const;
  Simd level_;
};

void CpuPanelOps::block_sum(const Panel<fx::Q32>& p, Cols qs, Cols ws, std::size_t lo, std::size_t hi, Scratch& s,
                            std::vector<FastExact>& acc) const {
  const std::size_t nq = qs.size(), nw = ws.size(), pairs = nq * nw;
  const bool ifma = level_ == Simd::kAvx512Ifma;
  const std::size_t per_col = ifma ? kTile : 2 * kTile, per_pair = ifma ? 16 : 12;
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
    if (ifma) {
      transpose<true>(p, ws, t0, rows, s.w.data(), s.sw.data(), s.wbits.data());
      transpose<true>(p, qs, t0, rows, s.x.data(), s.sx.data(), s.qbits.data());
      ifma_tile(s.x.data(), nq, s.w.data(), nw, s.lanes.data());
    } else {
      transpose<false>(p, ws, t0, rows, s.w.data(), s.sw.data(), s.wbits.data());
      transpose<false>(p, qs, t0, rows, s.x.data(), s.sx.data(), s.qbits.data());
      avx2_tile(s.x.data(), nq, s.w.data(), nw, s.lanes.data());
    }
  }
  const i128 rows = static_cast<i128>(hi - lo);
  for (std::size_t q = 0; q < nq; ++q)
    for (std::size_t c = 0; c < nw; ++c) {
      const std::size_t k = q * nw + c;
      if (((s.qbits[q] | s.wbits[c]) >> kOffsetBits) == 0) {
        const u128 t = ifma ? ifma_total(s.lanes.data() + k * per_pair) : avx2_total(s.lanes.data() + k * per_pair);
        // sum x' w' < 2^116; the corrections are below 2^115: all exact in i128.
        acc[k].add(static_cast<i128>(t) - (s.sx[q] + s.sw[c]) * static_cast<i128>(kOffset) - rows * (i128{1} << 102));
      } else {
        for (std::size_t i = lo; i < hi; ++i)
          acc[k].add(static_cast<i128>(p.at(i, qs[q]).raw) * p.at(i, ws[c]).raw);
      }
    }
}

void CpuPanelOps::dots(const Panel<fx::Q32>& p, Cols qs, Cols ws, std::span<double> out) const {
  if (level_ == Simd::kPortable) return PanelOps<fx::Q32>::dots(p, qs, ws, out);
  const std::size_t nq = qs.size(), nw = ws.size(), pairs = nq * nw;
  if (out.size() != pairs || p.rows() != size()) throw std::invalid_argument("spectral dots: sizes");
  for (const std::uint32_t c : qs)
    if (c >= p.cols()) throw std::invalid_argument("panel: column out of range");
  for (const std::uint32_t c : ws)
    if (c >= p.cols()) throw std::invalid_argument("panel: column out of range");
  std::vector<FastExact> total(pairs);
  if (!parallel() || size() < spectral::kParallelMin) {
    Scratch s;
    spectral::for_row_blocks(size(), false, [&](std::size_t lo, std::size_t hi) { block_sum(p, qs, ws, lo, hi, s, total); });
  } else {
    struct Part {
      Scratch s;
      std::vector<FastExact> acc;
    };
    tbb::enumerable_thread_specific<Part> parts([pairs] { return Part{Scratch{}, std::vector<FastExact>(pairs)}; });
    spectral::for_row_blocks(size(), true, [&](std::size_t lo, std::size_t hi) {
      Part& part = parts.local();
      block_sum(p, qs, ws, lo, hi, part.s, part.acc);
    });
    for (const auto& part : parts)  // exact: the merge order plays no part
      for (std::size_t k = 0; k < pairs; ++k) total[k].merge(part.acc[k]);
  }
  for (std::size_t k = 0; k < pairs; ++k) out[k] = spectral::to_double_scaled(total[k].total(), 2 * frac_bits() + scale_exponent());
}

void CpuPanelOps::combine(Panel<fx::Q32>& p, Cols outs, Cols bases, Cols terms, std::span<const double> c) const {
  const std::size_t no = outs.size(), nt = terms.size();
  if (level_ != Simd::kAvx512Ifma || nt == 0 || nt > kMaxIfmaTerms || no == 0)
    return PanelOps<fx::Q32>::combine(p, outs, bases, terms, c);
  if (c.size() != nt * no || (!bases.empty() && bases.size() != no) || p.rows() != size())
    throw std::invalid_argument("spectral combine: sizes");
  for (Cols cols : {outs, bases, terms})
    for (const std::uint32_t k : cols)
      if (k >= p.cols()) throw std::invalid_argument("panel: column out of range");
  CombinePlan plan;
  plan.no = no;
  plan.nt = nt;
  plan.c0.resize(nt * no);
  plan.c1.resize(nt * no);
  plan.coef.resize(nt * no);
  plan.csum.assign(no, 0);
  for (std::size_t k = 0; k < nt * no; ++k) {
    plan.coef[k] = spectral::coef60(c[k]);  // throws on a NaN or |c| >= 8, as the portable kernel does
    const std::uint64_t cp = static_cast<std::uint64_t>(plan.coef[k]) ^ (std::uint64_t{1} << 63);  // c + 2^63
    plan.c0[k] = cp & ((std::uint64_t{1} << 52) - 1);
    plan.c1[k] = cp >> 52;
    plan.csum[k % no] += cp;
  }
  const u128 nt_ck = static_cast<u128>(nt) << 114;
  const i128 one = i128{1} << 60;
  auto finish = [](i128 total) {
    const i128 r = fx::detail::rne_shift(total, 60);
    if (!fx::detail::fits_i64(r)) fx::detail::throw_overflow("spectral round");
    return static_cast<std::int64_t>(r);
  };
  spectral::for_row_blocks(size(), parallel(), [&](std::size_t lo, std::size_t hi) {
    std::vector<std::uint64_t> xt(nt * 8), sums(no * 32);
    std::vector<std::int64_t> base(no * 8), result(no * 8);
    for (std::size_t g0 = lo; g0 < hi; g0 += 8) {
      const std::size_t rows = std::min<std::size_t>(8, hi - g0);
      std::uint64_t xsum[8] = {}, bits[8] = {};
      for (std::size_t r = 0; r < 8; ++r) {
        if (r >= rows) {  // lanes past the block's end: zeros, never written back
          for (std::size_t t = 0; t < nt; ++t) xt[t * 8 + r] = 0;
          continue;
        }
        const fx::Q32* row = p.row(g0 + r);
        for (std::size_t t = 0; t < nt; ++t) {
          const std::int64_t v = row[terms[t]].raw;
          const std::uint64_t xo = static_cast<std::uint64_t>(v) + kOffset;
          xt[t * 8 + r] = xo;
          xsum[r] += xo;  // below nt 2^52 < 2^63 whenever the bits allow the row
          bits[r] |= spectral::magnitude_bits(v);
        }
        for (std::size_t o = 0; o < no; ++o) base[o * 8 + r] = bases.empty() ? 0 : row[bases[o]].raw;
      }
      ifma_combine_rows(plan, xt.data(), sums.data());
      for (std::size_t r = 0; r < rows; ++r) {
        if ((bits[r] >> kOffsetBits) != 0) {  // an entry beyond the offset range: the exact scalar sum
          const fx::Q32* row = p.row(g0 + r);
          for (std::size_t o = 0; o < no; ++o) {
            FastExact acc;
            acc.add(static_cast<i128>(base[o * 8 + r]) * one);
            for (std::size_t t = 0; t < nt; ++t) acc.add(static_cast<i128>(plan.coef[t * no + o]) * row[terms[t]].raw);
            result[o * 8 + r] = acc.round_shift(60);
          }
          continue;
        }
        for (std::size_t o = 0; o < no; ++o) {
          const std::uint64_t* l = sums.data() + o * 32;
          const u128 cx = static_cast<u128>(l[r]) + ((static_cast<u128>(l[8 + r]) + l[16 + r]) << 52) +
                          (static_cast<u128>(l[24 + r]) << 104);
          const u128 total = cx - (plan.csum[o] << kOffsetBits) - (static_cast<u128>(xsum[r]) << 63) + nt_ck +
                             static_cast<u128>(static_cast<i128>(base[o * 8 + r]) * one);
          result[o * 8 + r] = finish(static_cast<i128>(total));
        }
      }
      for (std::size_t r = 0; r < rows; ++r) {
        fx::Q32* row = p.row(g0 + r);
        for (std::size_t o = 0; o < no; ++o) row[outs[o]] = fx::Q32::from_raw(result[o * 8 + r]);
      }
    }
  });
}

}  // namespace

std::unique_ptr<PanelOps<fx::Q32>> make_panel_kernels(std::size_t n, int e, bool parallel, int frac, Simd level) {
  if (static_cast<int>(level) > static_cast<int>(detect_simd()))
    throw std::invalid_argument("cpu kernels: this CPU does not run " + std::string(simd_name(level)));
  return std::make_unique<CpuPanelOps>(n, e, parallel, frac, level);
}

Q32KernelFactory kernel_factory(Simd level) {
  return [level](std::size_t n, int e, bool parallel, int frac) { return make_panel_kernels(n, e, parallel, frac, level); };
}

}  // namespace r1::accel::cpu
