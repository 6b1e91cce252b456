// The cpu backend (spec/backends.md R1-BKD-040..044): the canonical stages on every core, the
// spectral solver on accel/cpu's kernels (exact inner products vectorised at the SIMD level the
// CPU runs, chosen at run time or by $R1_CPU_SIMD), focus, encoding and hierarchy with their TBB
// switches on; the bytes are the reference's. R1-BKD-043 says which stage runs where; the frame
// renderer is the reference's.
#include <stdexcept>
#include <string>

#include "adapters.hpp"
#include "r1/accel/cpu/panel_kernels.hpp"
#include "stage_backend.hpp"

namespace r1::backends {

std::unique_ptr<Backend> make_cpu_backend() {
  std::string error;
  const accel::cpu::Simd level = accel::cpu::chosen_simd(&error);
  if (!error.empty()) throw std::invalid_argument(error);
  std::string summary = "spectral on accel/cpu kernels (TBB, exact SIMD ";
  summary += accel::cpu::simd_name(level);
  summary += level == accel::cpu::Simd::kAvx512Ifma ? " dots, combinations and operator rows" : level == accel::cpu::Simd::kAvx2 ? " dots" : " none";
  summary += "), focus on TBB row loops, encoding's batched betweenness and hierarchy with their TBB switches; "
             "frame and render the reference's (same bits)";
  StageKernels kernels;
  kernels.panel = accel::cpu::kernel_factory(level);
  kernels.rows = accel::cpu::rows_factory(level, true);
  return std::make_unique<StageBackend>("cpu", summary, ReferenceStages(true, false, std::move(kernels)),
                                        Domain::kFixedQ32);
}

}  // namespace r1::backends
