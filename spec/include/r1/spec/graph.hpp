// The layout graph of a snapshot (decision 3, R1-IN-050..058): CSR of A_sym = A0 + A0^T with Q32
// weights in (0, 1], the bivector A2 on the same pattern, directed A0 for diffusion, weighted
// degrees and connected components.
#pragma once

#include <cstdint>
#include <vector>

#include "r1/fixedpoint/int128.hpp"

namespace r1 {

struct Graph {
  std::uint32_t n = 0;  // particles (canonical order)

  // A_sym, symmetric, self-loops dropped, parallel links summed. Row i holds columns in
  // ascending order. Weights are Q32 raw (2^32 = 1.0): round(A_sym * 2^32 / max A_sym), ties to
  // even, at least 1 so every stored link stays positive.
  std::vector<std::uint64_t> row_ptr;  // n + 1
  std::vector<std::uint32_t> col;
  std::vector<std::int64_t> w;
  // A2 on the A_sym pattern, Q32 raw, antisymmetric: a2 of (i, j) = -a2 of (j, i), |a2| <= w.
  std::vector<std::int64_t> a2;

  // Directed A0 (out-links), same scale as w: out_w of (p, q) = round(A0(p, q) * 2^32 / max A_sym).
  std::vector<std::uint64_t> out_ptr;  // n + 1
  std::vector<std::uint32_t> out_col;
  std::vector<std::int64_t> out_w;

  // Weighted degree d_i = sum_j w(i, j), exact (Q32 raw, unsigned: up to (n - 1) * 2^32).
  std::vector<std::uint64_t> degree;

  // What the focus reads of the whole graph (R1-IN-059), so that a local update (R1-INC-050)
  // passes over no array of n: filled by build_graph. A graph made otherwise leaves `prior` empty
  // and the focus computes all three from the arrays above.
  std::vector<std::int64_t> prior;      // the prior apportion(2^32, degree), raws (R1-FOC-011)
  std::vector<std::uint32_t> dangling;  // particles without out-links, ascending (R1-FOC-021)
  std::uint64_t max_degree = 0;         // max degree, for ||L|| (R1-FOC-060)
  bool summarised() const { return n > 0 && prior.size() == n; }

  // Connected components of A_sym: ids numbered by their lowest particle index.
  std::vector<std::uint32_t> component;
  std::vector<std::uint32_t> component_size;  // by id

  u128 weight_scale = 0;  // max A_sym entry in exact units (amount x token per-mille weight)
  std::uint64_t links = 0;              // links in the snapshot
  std::uint64_t self_loops_dropped = 0;

  std::uint64_t nnz() const { return col.size(); }
  std::uint32_t neighbours(std::uint32_t i) const { return static_cast<std::uint32_t>(row_ptr[i + 1] - row_ptr[i]); }
};

}  // namespace r1
