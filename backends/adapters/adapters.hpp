// The adapters built into r1 (R1-BKD-020..023, R1-BKD-040): reference, fp64, cpu, null and the
// self-test backends that break one contract each. Internal to backends/.
#pragma once

#include <memory>
#include <string_view>

#include "r1/backends/backend.hpp"

namespace r1::backends {

// The reference stages; `fp64` runs the spectral and focus stages in IEEE doubles (R1-EPO-003),
// the second numeric domain: within the bounds, not the same bits.
std::unique_ptr<Backend> make_reference_backend(bool fp64 = false);

// The cpu backend (R1-BKD-040): the reference's bytes on every core with vectorised kernels.
// Throws std::invalid_argument when $R1_CPU_SIMD names a level this CPU lacks.
std::unique_ptr<Backend> make_cpu_backend();

// The vulkan backend (R1-BKD-065): frame passes on a Vulkan device, epoch stages on the host.
// Throws std::invalid_argument saying why when no usable Vulkan device exists.
std::unique_ptr<Backend> make_vulkan_backend();

// Well-formed, deliberately wrong results at every stage (R1-BKD-021).
std::unique_ptr<Backend> make_null_backend();

// The reference with one fault injected (R1-BKD-022): each must fail exactly the check it names.
enum class SelfTestFault { kPosition, kTopology, kHue };
std::string_view self_test_name(SelfTestFault f);
std::string_view self_test_summary(SelfTestFault f);
std::unique_ptr<Backend> make_self_test_backend(SelfTestFault f);

}  // namespace r1::backends
