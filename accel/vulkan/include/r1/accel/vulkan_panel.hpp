// The spectral solver's exact Q32 kernels on a Vulkan device (spec/backends.md R1-BKD-069): the
// inner products and the combinations of spectral::PanelOps as compute shaders in exact integer
// arithmetic (128-bit products, 192-bit sums in three 64-bit limbs, one rounding), so the solver
// gives the portable kernels' bits. Scaling, random columns and copies stay on the host. The
// operator's rows likewise (rows_factory).
#pragma once

#include <memory>

#include "r1/accel/vulkan.hpp"
#include "r1/solvers/panel.hpp"
#include "r1/solvers/spectral.hpp"

namespace r1::vk {

// The solver's Q32 kernels on `ctx` (the context must outlive them). Input error when a shader
// does not compile on the device.
Result<Q32KernelFactory> panel_kernel_factory(std::shared_ptr<Context> ctx);

// The spectral operator's rows for the solver's block applications on `ctx` (R1-SPEC-073,
// R1-BKD-071): x_i 2^32 - sum_k M_ik x_k - g_i coef in 192 bits, rounded once, the host's bits.
// Each operator's matrix is uploaded once and released with its rows. Input error when the
// shader does not compile on the device.
Result<Q32RowsFactory> rows_factory(std::shared_ptr<Context> ctx);

}  // namespace r1::vk
