// The reference adapters (R1-BKD-020): every stage is the cpu-reference's own function
// (r1::ReferenceStages and the reference renderer): `reference` single-threaded, `fp64` with
// spectral and focus in IEEE doubles.
#include "adapters.hpp"
#include "stage_backend.hpp"

namespace r1::backends {

std::unique_ptr<Backend> make_reference_backend(bool fp64) {
  if (fp64)
    return std::make_unique<StageBackend>("fp64", "reference stages with spectral and focus in IEEE doubles (R1-EPO-003)",
                                          ReferenceStages(false, true), Domain::kFp64);
  return std::make_unique<StageBackend>("reference", "the single-threaded cpu-reference", ReferenceStages(), Domain::kFixedQ32);
}

}  // namespace r1::backends
