// The hint every random gather of r1 gives ahead of itself (R1-NUM-070): fetch the line holding
// p into the second-level cache. It changes no value anywhere, only when a line arrives.
#pragma once

namespace r1::fx {

// Why the second level: a first-level prefetch (prefetcht0) holds one of the core's few
// first-level miss buffers until its line arrives, so on arrays past the caches it caps the
// misses in flight; a second-level one (prefetcht1) waits in the second level's larger queue, and
// the gather's own load then finds its line a few cycles away. Measured on the build machine
// (AMD EPYC, 2 cores), gathering 64-byte rows of a 64 MB block by the 2 x 10^7 columns of BA 10^6:
// 72-117 ms with first-level hints, 52-73 ms with second-level ones, 97-162 ms with none (32 to
// 128 entries ahead; spec/numerics.md R1-NUM-070 and the README have the rest). On aarch64 the
// hint is PRFM PLDL2KEEP, the same request (checked in Clang's output for that target).
inline void gather_hint(const void* p) noexcept {
#if defined(__GNUC__) || defined(__clang__)
  __builtin_prefetch(p, 0, 2);
#else
  (void)p;
#endif
}

}  // namespace r1::fx
