// The cpu backend's spectral kernels against the solver's portable ones (R1-BKD-041): every SIMD
// level this CPU runs, serial and on TBB tasks, gives the portable inner products bit for bit,
// on entries of every magnitude (the vector paths' range, its edge, and the fall-back beyond).
#include "r1/accel/cpu/panel_kernels.hpp"

#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cstdint>
#include <limits>
#include <numeric>
#include <vector>

#include "r1/fixedpoint/counter_rng.hpp"
#include "panel_cases.hpp"
#include "test_support.hpp"

namespace r1::accel::cpu {
namespace {

using spectral::Panel;
using spectral::PanelOps;

// A panel whose column c has entries of about `bits[c]` bits (random signs), with the extremes
// of the vector path's range planted in a few rows.
Panel<fx::Q32> make_panel(std::size_t n, const std::vector<int>& bits, std::uint64_t seed) {
  Panel<fx::Q32> p = test::random_panel(n, bits, seed);
  // The edges of the offset range: -2^51 is inside, 2^51 - 1 inside, 2^51 outside.
  if (n > 300) {
    p.at(7, 0) = fx::Q32::from_raw(-(std::int64_t{1} << 51));
    p.at(8, 1 % bits.size()) = fx::Q32::from_raw((std::int64_t{1} << 51) - 1);
  }
  return p;
}

std::vector<std::uint64_t> dots_bits(const PanelOps<fx::Q32>& ops, const Panel<fx::Q32>& p, std::vector<std::uint32_t> qs,
                                     std::vector<std::uint32_t> ws) {
  std::vector<double> out(qs.size() * ws.size());
  ops.dots(p, qs, ws, out);
  std::vector<std::uint64_t> b;
  for (double d : out) b.push_back(std::bit_cast<std::uint64_t>(d));
  return b;
}

std::vector<Simd> levels() {
  std::vector<Simd> v;
  for (Simd s : {Simd::kPortable, Simd::kAvx2, Simd::kAvx512Ifma})
    if (static_cast<int>(s) <= static_cast<int>(detect_simd())) v.push_back(s);
  return v;
}

TEST(CpuPanelKernels, EveryLevelGivesThePortableDotsBitForBit) {
  // Sizes: one short block, several blocks with a ragged tail, and enough rows for TBB tasks.
  for (const std::size_t n : {std::size_t{100}, std::size_t{3 * 4096 + 37}, std::size_t{(1u << 15) + 4096 + 5}}) {
    // Column magnitudes: typical basis entries (48-50 bits), the vector path's edge (51), beyond
    // it (52, 57) and the portable kernel's own fall-back range (60, 63).
    const std::vector<int> bits = {48, 49, 50, 51, 52, 57, 60, 63, 30, 48, 48};
    const Panel<fx::Q32> p = make_panel(n, bits, 0x5eed + n);
    std::vector<std::uint32_t> all(bits.size());
    std::iota(all.begin(), all.end(), 0u);
    const std::vector<std::uint32_t> block = {0, 1, 2, 9, 10, 4, 3};  // the width of a solver block
    const PanelOps<fx::Q32> portable(n, 20, false, 48);
    const auto want_all = dots_bits(portable, p, all, block);
    const auto want_one = dots_bits(portable, p, {2}, {9});
    const auto want_gather = dots_bits(portable, p, block, all);  // a list that is not a run of columns
    for (const Simd s : levels())
      for (const bool parallel : {false, true}) {
        SCOPED_TRACE(std::string(simd_name(s)) + (parallel ? " parallel" : " serial") + " n=" + std::to_string(n));
        const auto ops = make_panel_kernels(n, 20, parallel, 48, s);
        EXPECT_EQ(dots_bits(*ops, p, all, block), want_all);
        EXPECT_EQ(dots_bits(*ops, p, {2}, {9}), want_one);
        EXPECT_EQ(dots_bits(*ops, p, block, all), want_gather);
      }
  }
}

// Combinations: every level, serial and parallel, writes the portable kernel's raws, with and
// without bases, with outputs that are also bases or terms, up to the thick restart's width, on
// rows inside and beyond the vector path's range.
TEST(CpuPanelKernels, EveryLevelGivesThePortableCombinationsBitForBit) {
  for (const std::size_t n : {std::size_t{203}, std::size_t{(1u << 15) + 4096 + 5}}) {
    std::vector<int> bits(200, 48);
    bits[3] = 51;
    bits[4] = 50;
    bits[5] = 52;   // beyond the vector path: its rows take the exact scalar sum when a term
    bits[6] = 30;
    const Panel<fx::Q32> start = make_panel(n, bits, 0xc0ffee + n);
    struct Case {
      std::vector<std::uint32_t> outs, bases, terms;
    };
    std::vector<std::uint32_t> many(189);
    std::iota(many.begin(), many.end(), 7u);
    std::vector<std::uint32_t> seventy(70);
    std::iota(seventy.begin(), seventy.end(), 0u);
    // A fused pass as the solver makes it: the block's own columns, then the list (a long run
    // through a column beyond the vector range), then list columns in short runs.
    std::vector<std::uint32_t> block = {190, 191, 192, 193, 194, 195, 196}, pass = block;
    for (std::uint32_t c = 0; c < 150; ++c) pass.push_back(c);
    for (const std::uint32_t c : {160u, 162u, 163u, 164u, 170u, 171u, 172u, 173u, 174u}) pass.push_back(c);
    const std::vector<Case> cases = {
        {{0, 1, 2, 3, 4, 5, 6}, {0, 1, 2, 3, 4, 5, 6}, {7, 8, 9, 10, 11, 12, 13, 14, 15, 16}},  // a Gram-Schmidt pass
        {{190, 191, 192}, {}, {0, 1, 2, 3, 4}},                                                  // no bases
        {seventy, {}, many},                                                                     // a thick restart
        {block, {}, pass},                                                                       // a fused pass's runs
        {{7}, {7}, {3}},                                                                         // one term, in range
        {{8}, {8}, {5, 4}},                                                                      // a term beyond it
        {{9, 10}, {11, 12}, {9, 10, 5}},                                                         // outputs are terms
        {{20, 21, 22}, {20, 21, 22}, {2, 3, 4, 5, 6}},  // a run of terms holding entries beyond the range
    };
    for (std::size_t ci = 0; ci < cases.size(); ++ci) {
      const Case& k = cases[ci];
      // Coefficients over the whole allowed range (-8, 8), tiny ones and exact extremes.
      const std::vector<double> coef = test::combine_coefficients(ci, k.terms.size() * k.outs.size());
      Panel<fx::Q32> want = start;
      PanelOps<fx::Q32>(n, 20, false, 48).combine(want, k.outs, k.bases, k.terms, coef);
      for (const Simd s : levels())
        for (const bool parallel : {false, true}) {
          SCOPED_TRACE(std::string(simd_name(s)) + (parallel ? " parallel" : " serial") + " n=" + std::to_string(n) +
                       " case " + std::to_string(ci));
          Panel<fx::Q32> got = start;
          make_panel_kernels(n, 20, parallel, 48, s)->combine(got, k.outs, k.bases, k.terms, coef);
          bool same = true;
          for (std::size_t i = 0; i < n && same; ++i)
            for (std::size_t c = 0; c < got.cols(); ++c)
              if (got.at(i, c).raw != want.at(i, c).raw) {
                ADD_FAILURE() << "row " << i << " column " << c << ": " << got.at(i, c).raw << " != " << want.at(i, c).raw;
                same = false;
                break;
              }
        }
    }
  }
}

// A coefficient the solver cannot take (NaN, |c| >= 8) is refused as the portable kernel refuses it.
TEST(CpuPanelKernels, ABadCoefficientIsRefusedAtEveryLevel) {
  Panel<fx::Q32> p = make_panel(64, {48, 48}, 3);
  const std::vector<std::uint32_t> out = {0}, term = {1};
  for (const Simd s : levels()) {
    const auto ops = make_panel_kernels(64, 6, false, 48, s);
    EXPECT_THROW(ops->combine(p, out, out, term, std::vector<double>{8.0}), fx::OverflowError) << simd_name(s);
  }
}

// Halves of integers are ties: with coefficients of +-1/2 every output whose terms sum to an odd
// number rounds a tie (to even), about half the rows, in both of a 9-output combination's groups
// of 8 lanes, with and without bases.
TEST(CpuPanelKernels, TiesRoundToEvenAtEveryLevel) {
  constexpr std::size_t n = 512;
  const Panel<fx::Q32> start = make_panel(n, std::vector<int>(16, 40), 11);
  std::vector<std::uint32_t> outs(9), terms = {10, 11, 12};
  std::iota(outs.begin(), outs.end(), 0u);
  std::vector<double> coef(terms.size() * outs.size());
  for (std::size_t k = 0; k < coef.size(); ++k) coef[k] = (k % 3 == 1) ? -0.5 : 0.5;
  for (const bool with_bases : {false, true}) {
    const std::vector<std::uint32_t> bases = with_bases ? outs : std::vector<std::uint32_t>{};
    Panel<fx::Q32> want = start;
    PanelOps<fx::Q32>(n, 9, false, 48).combine(want, outs, bases, terms, coef);
    std::size_t ties = 0;
    for (std::size_t i = 0; i < n; ++i) {
      std::int64_t s = 0;
      for (const std::uint32_t t : terms) s += start.at(i, t).raw;
      ties += (s & 1) != 0;
    }
    EXPECT_GT(ties, n / 4);
    for (const Simd lv : levels()) {
      Panel<fx::Q32> got = start;
      make_panel_kernels(n, 9, false, 48, lv)->combine(got, outs, bases, terms, coef);
      for (std::size_t i = 0; i < n; ++i)
        for (const std::uint32_t c : outs) ASSERT_EQ(got.at(i, c).raw, want.at(i, c).raw) << simd_name(lv) << " row " << i << " output " << c;
    }
  }
}

// A combined entry beyond 64 bits is refused at every level, as the portable kernel refuses it:
// 520 terms of 2^51 - 1 (the vector path's largest entry) with coefficients just below 8 sum to
// about 2^63.02. One output (one lane) and nine (a second vector of lanes) overflow in row 5 only.
TEST(CpuPanelKernels, ACombinedEntryBeyond64BitsIsRefusedAtEveryLevel) {
  constexpr std::size_t n = 16, nt = 520;
  Panel<fx::Q32> p(n, nt + 9);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t c = 0; c < nt; ++c) p.at(i, c) = fx::Q32::from_raw(i == 5 ? (std::int64_t{1} << 51) - 1 : 1000);
  std::vector<std::uint32_t> terms(nt);
  std::iota(terms.begin(), terms.end(), 0u);
  for (const std::size_t no : {std::size_t{1}, std::size_t{9}}) {
    std::vector<std::uint32_t> outs(no);
    std::iota(outs.begin(), outs.end(), static_cast<std::uint32_t>(nt));
    const std::vector<double> coef(nt * no, 7.99);
    Panel<fx::Q32> want = p;
    EXPECT_THROW(PanelOps<fx::Q32>(n, 4, false, 48).combine(want, outs, {}, terms, coef), fx::OverflowError);
    for (const Simd s : levels()) {
      Panel<fx::Q32> got = p;
      EXPECT_THROW(make_panel_kernels(n, 4, false, 48, s)->combine(got, outs, {}, terms, coef), fx::OverflowError)
          << simd_name(s) << " outputs " << no;
    }
    // One step below the edge every level agrees with the portable kernel: 1000-raw rows only.
    Panel<fx::Q32> small(n, nt + 9);
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t c = 0; c < nt; ++c) small.at(i, c) = fx::Q32::from_raw(i == 5 ? -(std::int64_t{1} << 51) + 1 : 1000);
    const std::vector<double> fits(nt * no, 1.0);  // 520 (2^51 - 1) < 2^63: fits
    Panel<fx::Q32> w2 = small;
    PanelOps<fx::Q32>(n, 4, false, 48).combine(w2, outs, {}, terms, fits);
    for (const Simd s : levels()) {
      Panel<fx::Q32> g2 = small;
      make_panel_kernels(n, 4, false, 48, s)->combine(g2, outs, {}, terms, fits);
      for (std::size_t i = 0; i < n; ++i)
        for (const std::uint32_t c : outs) ASSERT_EQ(g2.at(i, c).raw, w2.at(i, c).raw) << simd_name(s) << " row " << i;
    }
  }
}

// The Chebyshev filter's recurrence (spectral::three_term): every level, serial and parallel,
// writes the portable raws, with two terms (gamma = 0: p not read) and three, on entries inside
// the vector path's range, at its edges and beyond it, with ties and with the extreme
// coefficients; an entry that cannot fit is refused at every level.
TEST(CpuPanelKernels, EveryLevelGivesThePortableRecurrenceBitForBit) {
  for (const std::size_t len : {std::size_t{13}, std::size_t{3 * 4096 + 37}, std::size_t{(1u << 15) + 4096 + 5}}) {
    const Panel<fx::Q32> src = make_panel(len, {48, 50, 49}, 0x7e11 + len);
    std::vector<fx::Q32> s = src.copy_column(0), y = src.copy_column(1), p0 = src.copy_column(2);
    // The offset range's edges (-2^51 in, 2^51 - 1 in, 2^51 out), far beyond it, and odd raws
    // that make halves (ties) under coefficients of +-1/2.
    const std::int64_t edge = std::int64_t{1} << 51;
    const std::vector<std::pair<std::size_t, std::int64_t>> plant = {
        {0, -edge}, {1, edge - 1}, {2, edge}, {3, -edge - 1}, {4, std::int64_t{1} << 57}, {5, 1}, {6, -3}, {7, 5}};
    for (const auto& [k, v] : plant)
      if (k < len) {
        s[k] = fx::Q32::from_raw(v);
        y[len - 1 - k] = fx::Q32::from_raw(k % 2 == 0 ? v : 7);
        p0[(k * 977) % len] = fx::Q32::from_raw(v);
      }
    const std::vector<std::array<double, 3>> coefs = {
        {-1.25, 0.75, 0.0}, {0.5, -0.5, 0.5}, {7.999999999, -7.999999999, 7.5}, {0x1p-60, -0x1p-59, 3.0}, {1.0, 0.0, -1.0}};
    for (std::size_t ci = 0; ci < coefs.size(); ++ci) {
      const auto [a, b, g] = coefs[ci];
      std::vector<fx::Q32> want = p0;
      spectral::three_term(len, s.data(), y.data(), want.data(), a, b, g, false);
      for (const Simd lv : levels())
        for (const bool parallel : {false, true}) {
          SCOPED_TRACE(std::string(simd_name(lv)) + (parallel ? " parallel" : " serial") + " len=" + std::to_string(len) +
                       " case " + std::to_string(ci));
          std::vector<fx::Q32> got = p0;
          make_panel_kernels(len, 20, parallel, 48, lv)->three_term(len, s.data(), y.data(), got.data(), a, b, g);
          for (std::size_t k = 0; k < len; ++k) ASSERT_EQ(got[k].raw, want[k].raw) << "entry " << k;
        }
    }
  }
  // 7.99 (2^61) + 7.99 (2^61) is about 2^65: refused by the portable kernel and at every level.
  std::vector<fx::Q32> big(16, fx::Q32::from_raw(std::int64_t{1} << 61)), out(16, fx::Q32::from_raw(0));
  EXPECT_THROW(spectral::three_term(16, big.data(), big.data(), out.data(), 7.99, 7.99, 0.0, false), fx::OverflowError);
  for (const Simd lv : levels())
    EXPECT_THROW(make_panel_kernels(16, 4, false, 48, lv)->three_term(16, big.data(), big.data(), out.data(), 7.99, 7.99, 0.0),
                 fx::OverflowError)
        << simd_name(lv);
}

TEST(CpuPanelKernels, TheChosenLevelFollowsTheEnvironmentAndRefusesWhatTheCpuLacks) {
  {
    test::ScopedEnv env("R1_CPU_SIMD", "portable");
    std::string error;
    EXPECT_EQ(chosen_simd(&error), Simd::kPortable);
    EXPECT_TRUE(error.empty());
  }
  {
    test::ScopedEnv env("R1_CPU_SIMD", "sse9");
    std::string error;
    EXPECT_EQ(chosen_simd(&error), detect_simd());
    EXPECT_NE(error.find("unknown level 'sse9'"), std::string::npos) << error;
  }
  if (detect_simd() != Simd::kAvx512Ifma) {
    test::ScopedEnv env("R1_CPU_SIMD", "avx512ifma");
    std::string error;
    EXPECT_EQ(chosen_simd(&error), detect_simd());
    EXPECT_NE(error.find("does not run"), std::string::npos) << error;
    EXPECT_THROW(make_panel_kernels(10, 4, false, 48, Simd::kAvx512Ifma), std::invalid_argument);
  }
}

}  // namespace
}  // namespace r1::accel::cpu
