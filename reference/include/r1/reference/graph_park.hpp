// The layout graph's arrays that the spectral solve does not read, held compressed while it runs
// (spec/epoch.md R1-EPO-006): the solve is the epoch's peak of memory, and beside its basis it
// needs only the graph's pattern and degrees.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "r1/spec/graph.hpp"
#include "r1/spec/status.hpp"

namespace r1 {

// Releases the arrays ParkedGraph::park compresses, for a caller that needs only what the
// spectral solve reads from here on (`r1 spectrum`, R1-SPEC-077).
void release_unread_by_spectral(Graph& g);

class ParkedGraph {
 public:
  // Compresses w, a2, out_ptr, out_col, out_w, prior, dangling and component of `g` (zstd over
  // byte planes, in chunks; `parallel`: the chunks on TBB workers) and releases them. `g` keeps n,
  // row_ptr, col, degree, component_size and its scalars. An error (zstd failed: out of memory)
  // leaves `g` whole.
  static Result<ParkedGraph> park(Graph& g, bool parallel);
  // Puts the arrays back into `g`, bit for bit, and empties this. Restoring an empty ParkedGraph
  // changes nothing.
  Status restore(Graph& g, bool parallel);

  bool empty() const { return arrays_.empty(); }
  std::uint64_t raw_bytes() const;     // the arrays' bytes as they were in `g`
  std::uint64_t packed_bytes() const;  // their compressed chunks' bytes

  // One array: `elements` entries of `width` bytes, compressed chunk by chunk.
  struct Packed {
    std::size_t elements = 0;
    std::size_t width = 0;
    std::vector<std::vector<unsigned char>> chunks;
  };

 private:
  std::vector<Packed> arrays_;  // in the order park() lists them
};

}  // namespace r1
