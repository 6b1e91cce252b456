// Builds a Snapshot from links in chain order: particles are numbered by first appearance,
// source before target (decision 2, R1-IN-010). Text inputs name particles (id = Hemera(name),
// R1-IN-011); .graph inputs give ids directly.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "r1/reference/intern_index.hpp"
#include "r1/spec/progress.hpp"
#include "r1/spec/snapshot.hpp"
#include "r1/spec/status.hpp"

namespace r1 {

// The config every text input gets (R1-IN-012): chain "local", block 1, one token of weight 1.0.
SnapshotConfig text_input_config();

class SnapshotBuilder {
 public:
  explicit SnapshotBuilder(std::string source);

  // Index of the particle with this name, numbering a new one on first sight. Do not mix with
  // particle_by_id in one snapshot.
  std::uint32_t particle_by_name(std::string_view name);
  std::uint32_t particle_by_id(const ParticleId& id);
  std::uint32_t neuron_by_id(const NeuronId& id);
  std::size_t particle_count() const;
  // A hint for particle_by_id(id) a few records ahead (speed only): fetches its index slot. Only
  // once a particle has been numbered (the index is not empty).
  void prefetch_particle(const ParticleId& id) const { by_id_.prefetch_slot(id); }

  // Appends a link; its from/to/neuron are indices returned above. Text inputs leave neuron 0
  // (the all-zero neuron id) and height 1.
  void add_link(const Link& l);
  void reserve_links(std::size_t n) { s_.links.reserve(n); }

  Snapshot& snapshot() { return s_; }  // config, card, titles, crystal may be set directly

  // Computes the ids of named particles (Hemera of the name bytes, in bulk) and hands over the
  // snapshot. Fails on more than 2^32 - 2 particles or an id shared by two names.
  Result<Snapshot> finish(const ProgressFn& progress = {});

 private:
  Snapshot s_;
  bool named_ = false;
  NameIndex by_name_;
  IdIndex by_id_;
  IdIndex neuron_by_id_;
};

}  // namespace r1
