// Snapshot assembly: first-appearance particle numbering and bulk particle ids (R1-IN-010..012).
#include "r1/reference/snapshot_builder.hpp"

#include <algorithm>
#include <cstring>
#include <limits>

namespace r1 {

SnapshotConfig text_input_config() {
  SnapshotConfig c;
  c.chain_id = "local";
  // Records need 1 <= height <= block; text inputs have no chain, so everything is block 1.
  c.block = 1;
  c.captured_at = 0;  // no clock: the same input must give the same bytes
  c.format_version = 1;
  c.tokens[0] = Token{"weight", 1000};
  return c;
}

SnapshotBuilder::SnapshotBuilder(std::string source) { s_.source = std::move(source); }

std::uint32_t SnapshotBuilder::particle_by_name(std::string_view name) {
  named_ = true;
  return by_name_.intern(name, s_.names);
}

std::uint32_t SnapshotBuilder::particle_by_id(const ParticleId& id) { return by_id_.intern(id, s_.particles); }

std::uint32_t SnapshotBuilder::neuron_by_id(const NeuronId& id) { return neuron_by_id_.intern(id, s_.neurons); }

std::size_t SnapshotBuilder::particle_count() const { return named_ ? s_.names.size() : s_.particles.size(); }

void SnapshotBuilder::add_link(const Link& l) { s_.links.push_back(l); }

Result<Snapshot> SnapshotBuilder::finish(const ProgressFn& progress) {
  // Index 2^32 - 1 stays free as a "none" marker for later stages.
  if (particle_count() >= std::numeric_limits<std::uint32_t>::max())
    return Status::input(s_.source + ": more than 2^32 - 2 particles");
  if (named_) {
    by_name_.clear();
    const std::size_t n = s_.names.size();
    s_.particles.assign(n, ParticleId{});
    // Bulk hashing in lanes (R1-HASH-020); blocks only to report progress between them.
    constexpr std::size_t kBlock = std::size_t{1} << 16;
    for (std::size_t first = 0; first < n; first += kBlock) {
      const std::size_t count = std::min(kBlock, n - first);
      hemera::hash_many(std::span<const std::string>(s_.names).subspan(first, count),
                        std::span<hemera::Digest>(s_.particles).subspan(first, count));
      report(progress, "hashing particle names", first + count, n);
    }
    // Two names with one id would make two particles one: impossible short of a Hemera collision,
    // but checked because everything downstream assumes distinct ids.
    IdIndex seen;
    std::vector<ParticleId> distinct;
    distinct.reserve(n);
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t first = seen.intern(s_.particles[i], distinct);
      if (first != i)
        return Status::input(s_.source + ": particles '" + s_.names[first] + "' and '" + s_.names[i] +
                             "' have the same Hemera id");
    }
  }
  if (s_.neurons.empty()) s_.neurons.push_back(NeuronId{});  // text inputs: the all-zero neuron
  by_id_.clear();
  neuron_by_id_.clear();
  return std::move(s_);
}

}  // namespace r1
