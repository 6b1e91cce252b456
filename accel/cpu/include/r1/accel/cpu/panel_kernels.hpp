// The cpu backend's kernels for the spectral solver (spec/backends.md R1-BKD-040..044): the
// solver's Q32 vector-space operations on all cores (TBB) with the exact inner products
// vectorised, the SIMD level chosen at run time from what the CPU has, a portable path beside it.
// Every level gives the bits of the portable spectral::PanelOps (R1-SPEC-011): exact sums do not
// depend on how the products are grouped.
#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <string_view>

#include "r1/solvers/panel.hpp"
#include "r1/solvers/spectral.hpp"

namespace r1::accel::cpu {

// The instruction sets the exact dot-product kernel has a path for, lowest first.
enum class Simd { kPortable, kAvx2, kAvx512Ifma };
std::string_view simd_name(Simd s);
std::optional<Simd> simd_from_name(std::string_view name);

// The highest level this CPU runs.
Simd detect_simd();
// The level the kernels use: $R1_CPU_SIMD (portable, avx2, avx512ifma) when set and supported,
// else detect_simd(). An unknown or unsupported name is an error string in *error (and the
// detected level is returned).
Simd chosen_simd(std::string* error = nullptr);

// The solver's Q32 kernels at `level` (which this CPU must support): dots vectorised, every
// kernel split over TBB tasks at fixed row blocks when `parallel`.
std::unique_ptr<spectral::PanelOps<fx::Q32>> make_panel_kernels(std::size_t n, int e, bool parallel, int frac, Simd level);

// The factory the solver takes (SpectralOptions::q32_kernels) for `level`.
Q32KernelFactory kernel_factory(Simd level);

// The operator's rows the solver takes (SpectralOptions::q32_rows, R1-SPEC-073) for `level`:
// with AVX-512 IFMA, a block application's exact row sums vectorised over the block's columns
// (block_rows.cpp), on TBB tasks when `parallel`; below IFMA none (an empty factory: the
// solver's own rows run).
// The filter's step is fused into the rows (R1-SPEC-075) from `fuse_from` rows: what it saves is
// a block of 32 MB or more, and below, where the blocks stay in cache, the separate recurrence
// was measured faster (BA 10^5: 5.4-6.8 s against 6.0-8.8 s a solve; BA 10^6 fused 214 s against
// 218 s). Tests pass 0.
inline constexpr std::size_t kFuseFrom = std::size_t{1} << 19;
Q32RowsFactory rows_factory(Simd level, bool parallel, std::size_t fuse_from = kFuseFrom);

// spectral::three_term's values on AVX-512 IFMA (which the CPU must have), on TBB tasks when
// `parallel`: the filter's recurrence of the cpu kernels and of the rows' fused filter step.
void three_term_ifma(std::size_t len, const fx::Q32* s, const fx::Q32* y, fx::Q32* p, double alpha, double beta,
                     double gamma, bool parallel);

}  // namespace r1::accel::cpu
