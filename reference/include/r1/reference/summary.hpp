// What `r1 info` reports about a snapshot and its layout graph (R1-IN-060).
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "r1/spec/graph.hpp"
#include "r1/spec/snapshot.hpp"

namespace r1 {

struct DegreeStats {
  double min = 0, max = 0, mean = 0, median = 0;
};

struct SnapshotSummary {
  std::string chain_id;
  std::uint64_t block = 0;
  std::uint64_t particles = 0;
  std::uint64_t links = 0;
  std::uint64_t neurons = 0;
  std::uint64_t self_loops_dropped = 0;
  std::uint64_t pairs = 0;  // distinct unordered particle pairs with a link (nnz of A_sym / 2)
  std::uint64_t components = 0;
  std::uint64_t largest_component = 0;
  std::uint64_t isolated = 0;  // particles without a neighbour (only self-loops)
  std::uint64_t anchor = 0;    // min(1024, particles)
  std::uint64_t titles = 0;    // particles with a title
  std::uint64_t crystal = 0;   // particles with crystal metadata
  DegreeStats degree;           // neighbour counts in A_sym
  DegreeStats weighted_degree;  // sum of Q32 weights, as reals
  std::optional<std::string> digest;  // 64 hex digits; absent when not computed
};

SnapshotSummary summarize(const Snapshot& s, const Graph& g);

}  // namespace r1
