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

std::size_t SnapshotBuilder::IdHash::operator()(const ParticleId& id) const noexcept {
  // Ids are Hemera digests, already uniform: any 8 bytes make a good hash.
  std::size_t h;
  std::memcpy(&h, id.data(), sizeof h);
  return h;
}

SnapshotBuilder::SnapshotBuilder(std::string source) { s_.source = std::move(source); }

std::uint32_t SnapshotBuilder::particle_by_name(std::string_view name) {
  named_ = true;
  auto [it, inserted] = by_name_.try_emplace(std::string(name), static_cast<std::uint32_t>(s_.names.size()));
  if (inserted) s_.names.emplace_back(name);
  return it->second;
}

std::uint32_t SnapshotBuilder::particle_by_id(const ParticleId& id) {
  auto [it, inserted] = by_id_.try_emplace(id, static_cast<std::uint32_t>(s_.particles.size()));
  if (inserted) s_.particles.push_back(id);
  return it->second;
}

std::uint32_t SnapshotBuilder::neuron_by_id(const NeuronId& id) {
  auto [it, inserted] = neuron_by_id_.try_emplace(id, static_cast<std::uint32_t>(s_.neurons.size()));
  if (inserted) s_.neurons.push_back(id);
  return it->second;
}

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
    std::unordered_map<ParticleId, std::uint32_t, IdHash> seen;
    seen.reserve(n);
    for (std::size_t i = 0; i < n; ++i) {
      auto [it, inserted] = seen.try_emplace(s_.particles[i], static_cast<std::uint32_t>(i));
      if (!inserted)
        return Status::input(s_.source + ": particles '" + s_.names[it->second] + "' and '" + s_.names[i] +
                             "' have the same Hemera id");
    }
  }
  if (s_.neurons.empty()) s_.neurons.push_back(NeuronId{});  // text inputs: the all-zero neuron
  by_id_.clear();
  neuron_by_id_.clear();
  return std::move(s_);
}

}  // namespace r1
