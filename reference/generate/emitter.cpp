// The generators' link emitter: first-appearance particle numbering and text-style links
// (R1-GEN-005, R1-GEN-006).
#include "gen_internal.hpp"

namespace r1::gen {

Emitter::Emitter(std::string source, std::uint32_t nodes, Namer name)
    : b_(std::move(source)), name_(std::move(name)), particle_of_(nodes, kNone) {}

std::uint32_t Emitter::particle(std::uint32_t node) {
  std::uint32_t& p = particle_of_[node];
  if (p == kNone) {
    p = b_.particle_by_name(name_(node));
    node_of_.push_back(node);
  }
  return p;
}

void Emitter::link(std::uint32_t from, std::uint32_t to, u128 amount, std::int8_t valence) {
  Link l;
  l.amount = amount;
  // Text-style snapshots live in block 1 (text_input_config) with the all-zero neuron.
  l.height = 1;
  l.neuron = 0;
  l.token = 0;
  l.valence = valence;
  // Two statements: the source must be numbered before the target (decision 2).
  l.from = particle(from);
  l.to = particle(to);
  b_.add_link(l);
}

Result<Snapshot> Emitter::finish(std::string card, const ProgressFn& progress) {
  b_.snapshot().config = text_input_config();
  b_.snapshot().card = std::move(card);
  std::vector<std::uint32_t>().swap(particle_of_);
  return b_.finish(progress);
}

Emitter::Namer indexed_names(std::string prefix) {
  prefix += '/';
  return [prefix](std::uint32_t node) { return prefix + std::to_string(node); };
}

}  // namespace r1::gen
