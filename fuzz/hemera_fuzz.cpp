// Fuzz target `hemera` (R1-HASH-004..012, R1-HASH-020..022): streaming == one-shot at chosen cuts,
// hash_many == hash, tree hash parallel == serial == unbatched == its recursive definition.
#include <algorithm>
#include <span>
#include <vector>

#include "fuzz_target.hpp"
#include "r1/fixedpoint/hemera.hpp"

namespace {

namespace hm = r1::hemera;
using Bytes = std::span<const std::uint8_t>;

// Input layout: byte 0 = flags (bits 0-2 cut count, bits 3-5 tree repeat count - 1, bit 6 parallel
// hash_many, bit 7 streaming through the keyed mode as well); then two bytes (little-endian) per
// cut, taken modulo message length + 1; the rest is the message.
struct Plan {
  bool parallel = false;
  bool keyed = false;
  std::size_t repeat = 1;
  std::vector<std::size_t> cuts;  // sorted, within [0, message.size()]
  Bytes message;
};

Plan parse(const std::uint8_t* data, std::size_t size) {
  Plan p;
  if (size == 0) return p;
  const std::uint8_t flags = data[0];
  const std::size_t ncuts = std::min<std::size_t>(flags & 7u, (size - 1) / 2);
  p.repeat = 1 + ((flags >> 3) & 7u);
  p.parallel = (flags & 0x40u) != 0;
  p.keyed = (flags & 0x80u) != 0;
  const std::size_t head = 1 + 2 * ncuts;
  p.message = Bytes(data + head, size - head);
  for (std::size_t i = 0; i < ncuts; ++i) {
    const std::size_t v = data[1 + 2 * i] | (static_cast<std::size_t>(data[2 + 2 * i]) << 8);
    p.cuts.push_back(v % (p.message.size() + 1));
  }
  std::sort(p.cuts.begin(), p.cuts.end());
  return p;
}

// Feeds the message to `h` in the pieces the cuts delimit (empty pieces included).
hm::Digest streamed(hm::Hasher h, const Plan& p) {
  std::size_t at = 0;
  for (const std::size_t c : p.cuts) {
    h.update(p.message.subspan(at, c - at));
    at = c;
  }
  h.update(p.message.subspan(at));
  return h.finalize();
}

// The tree by its definition: every leaf through hash_leaf, then the recursive merge.
hm::Digest tree_by_definition(Bytes data) {
  const std::size_t n = data.empty() ? 1 : (data.size() + hm::CHUNK_BYTES - 1) / hm::CHUNK_BYTES;
  std::vector<hm::Digest> leaves;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t off = i * hm::CHUNK_BYTES;
    leaves.push_back(hm::hash_leaf(data.subspan(off, std::min(hm::CHUNK_BYTES, data.size() - off)), i, n == 1));
  }
  return n == 1 ? leaves[0] : hm::detail::merge_leaves(leaves, true);
}

// Restores the process-wide batching switch on every exit path.
struct BatchingOff {
  bool was = hm::lane_batching();
  BatchingOff() { hm::set_lane_batching(false); }
  ~BatchingOff() { hm::set_lane_batching(was); }
  BatchingOff(const BatchingOff&) = delete;
  BatchingOff& operator=(const BatchingOff&) = delete;
};

}  // namespace

R1_FUZZ_TARGET(hemera) {
  const Plan p = parse(data, size);
  const hm::Digest one_shot = hm::hash(p.message);
  R1_FUZZ_CHECK(streamed(hm::Hasher(), p) == one_shot);
  if (p.keyed) R1_FUZZ_CHECK(streamed(hm::Hasher::keyed(one_shot), p) == hm::keyed_hash(one_shot, p.message));

  // hash_many over the pieces, the whole message and each prefix ending at a cut: lengths mix
  // block counts, and equal pieces share lanes.
  std::vector<Bytes> inputs{p.message};
  std::size_t at = 0;
  for (const std::size_t c : p.cuts) {
    inputs.push_back(p.message.subspan(at, c - at));
    inputs.push_back(p.message.subspan(0, c));
    at = c;
  }
  inputs.push_back(p.message.subspan(at));
  std::vector<hm::Digest> many(inputs.size());
  hm::hash_many(inputs, many, p.parallel);
  for (std::size_t i = 0; i < inputs.size(); ++i) R1_FUZZ_CHECK(many[i] == hm::hash(inputs[i]));

  // The tree over the message repeated, so that a few KiB of input reach several chunks.
  std::vector<std::uint8_t> tree_input;
  for (std::size_t r = 0; r < p.repeat; ++r) tree_input.insert(tree_input.end(), p.message.begin(), p.message.end());
  const hm::Digest serial = hm::root_hash(tree_input, false);
  R1_FUZZ_CHECK(hm::root_hash(tree_input, true) == serial);
  R1_FUZZ_CHECK(tree_by_definition(tree_input) == serial);
  {
    const BatchingOff off;
    R1_FUZZ_CHECK(hm::root_hash(tree_input, true) == serial);
  }
  return 0;
}
