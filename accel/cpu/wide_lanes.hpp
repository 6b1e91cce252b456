// Eight signed 128-bit integers in AVX-512 lanes, each as two 64-bit halves (the low half read
// unsigned, the high half signed), and their one rounding: the exact totals that the cpu
// backend's combinations (panel_kernels.cpp) and operator rows (block_rows.cpp) form modulo 2^128
// and round as fx::detail::rne_shift does. Carries and borrows come from unsigned compares.
#pragma once

#include <immintrin.h>

#include <cstdint>

// GCC 12 reports the shift and masked builtins' undefined pass-through operand as
// (maybe-)uninitialized (a false positive inside avx512fintrin.h; every lane is defined). Clang
// has no such warning group.
#if defined(__GNUC__) && !defined(__clang__)
#define R1_MASKED_SHIFT_WARNING_OFF                                                               \
  _Pragma("GCC diagnostic push") _Pragma("GCC diagnostic ignored \"-Wmaybe-uninitialized\"") \
      _Pragma("GCC diagnostic ignored \"-Wuninitialized\"")
#define R1_MASKED_SHIFT_WARNING_ON _Pragma("GCC diagnostic pop")
#else
#define R1_MASKED_SHIFT_WARNING_OFF
#define R1_MASKED_SHIFT_WARNING_ON
#endif

#define R1_WIDE_LANES __attribute__((target("avx512f"), always_inline)) inline

namespace r1::accel::cpu {

struct Wide {
  __m512i lo, hi;
};

R1_MASKED_SHIFT_WARNING_OFF

// a + (hi 2^64 + lo), per lane, modulo 2^128.
R1_WIDE_LANES Wide wide_add(Wide a, __m512i lo, __m512i hi) {
  const __m512i s = _mm512_add_epi64(a.lo, lo);
  __m512i h = _mm512_add_epi64(a.hi, hi);
  h = _mm512_mask_add_epi64(h, _mm512_cmplt_epu64_mask(s, a.lo), h, _mm512_set1_epi64(1));
  return Wide{s, h};
}

// a - (hi 2^64 + lo), per lane, modulo 2^128.
R1_WIDE_LANES Wide wide_sub(Wide a, __m512i lo, __m512i hi) {
  const __m512i d = _mm512_sub_epi64(a.lo, lo);
  __m512i h = _mm512_sub_epi64(a.hi, hi);
  h = _mm512_mask_sub_epi64(h, _mm512_cmplt_epu64_mask(a.lo, lo), h, _mm512_set1_epi64(1));
  return Wide{d, h};
}

// RNE(v / 2^S) per lane (0 < S < 64), ties to the even quotient; `ok` receives the lanes whose
// result lies in int64: v / 2^S fits when hi lies in [-2^(S-1), 2^(S-1)), and the quotient then
// overflows only when 2^63 - 1 rounds up.
template <int S>
R1_WIDE_LANES __m512i wide_rne_shift(Wide v, __mmask8& ok) {
  const __m512i one = _mm512_set1_epi64(1);
  const __m512i q = _mm512_or_si512(_mm512_srli_epi64(v.lo, S), _mm512_slli_epi64(v.hi, 64 - S));
  const __m512i rem = _mm512_and_si512(v.lo, _mm512_set1_epi64((std::int64_t{1} << S) - 1));
  const __m512i half = _mm512_set1_epi64(std::int64_t{1} << (S - 1));
  const __mmask8 up = _mm512_cmpgt_epu64_mask(rem, half) | (_mm512_cmpeq_epu64_mask(rem, half) & _mm512_test_epi64_mask(q, one));
  const __mmask8 fits = _mm512_cmpeq_epu64_mask(_mm512_srli_epi64(_mm512_add_epi64(v.hi, half), S), _mm512_setzero_si512());
  const __mmask8 wraps = _mm512_cmpeq_epu64_mask(q, _mm512_set1_epi64(INT64_MAX)) & up;
  ok = fits & static_cast<__mmask8>(~wraps);
  return _mm512_mask_add_epi64(q, up, q, one);
}

R1_MASKED_SHIFT_WARNING_ON

}  // namespace r1::accel::cpu
