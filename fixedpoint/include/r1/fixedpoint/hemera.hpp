// Hemera v2, 32-byte digests (R1-HASH-001..024, spec/hemera.md): Poseidon2 over Goldilocks,
// plain/keyed/derive-key sponge, tree hash, and the lane-batched bulk paths.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "r1/fixedpoint/goldilocks.hpp"

namespace r1::hemera {

inline constexpr std::size_t WIDTH = 16;
inline constexpr std::size_t RATE = 8;
inline constexpr std::size_t RATE_BYTES = 56;      // 8 elements x 7 bytes
inline constexpr std::size_t DIGEST_BYTES = 32;    // elements 0..3, 8 bytes little-endian each
inline constexpr std::size_t CHUNK_BYTES = 4096;   // tree-mode leaf size
// States permuted in lockstep by the batched paths: they fill the pipeline with independent
// multiplications and share field inversions per partial round. Measured per state on x86-64
// with AVX-512 (element-major rounds, R1-HASH-023): 8 lanes 1.10 us, 64 lanes 0.76 us; scalar
// rounds 1.96 and 1.56 us (R1-HASH-020).
inline constexpr std::size_t LANES = 64;

using State = std::array<std::uint64_t, WIDTH>;
using Digest = std::array<std::uint8_t, DIGEST_BYTES>;

// The Hemera permutation. Inputs may be any 64-bit words (each stands for its residue mod p);
// outputs are canonical field elements.
void permute(State& s);

// Permutes each state independently, LANES at a time in lockstep; equal to permute() on each.
void permute_many(std::span<State> states);

// The fast-path switch: with batching off, every batched entry point (permute_many, hash_many,
// the tree hash) permutes one state at a time. Results are identical either way; process-wide.
void set_lane_batching(bool on);
bool lane_batching();
// The rounds on AVX-512 (eight elements of a state per vector) where the CPU has it, else the
// scalar rounds. The same values either way; process-wide. vector_rounds(): whether they run.
void set_vector_rounds(bool on);
bool vector_rounds();

// Streaming sponge. Domain tags (state[11]): 0 plain, 1 keyed, 2 derive-key context,
// 3 derive-key material.
class Hasher {
 public:
  Hasher();                                   // plain hash
  static Hasher keyed(const Digest& key);     // keyed hash: the key is absorbed first
  static Hasher derive_key_context();  // absorbs the context string
  static Hasher derive_key_material(const Digest& context_hash);

  Hasher& update(std::span<const std::uint8_t> data);
  Hasher& update(std::string_view s) {
    return update(std::span(reinterpret_cast<const std::uint8_t*>(s.data()), s.size()));
  }
  Digest finalize() const;

 private:
  explicit Hasher(std::uint64_t domain);
  void absorb_block(const std::uint8_t* block);

  State state_{};
  std::array<std::uint8_t, RATE_BYTES> buf_{};
  std::size_t buf_len_ = 0;
  std::uint64_t absorbed_ = 0;
};

Digest hash(std::span<const std::uint8_t> data);
inline Digest hash(std::string_view s) {
  return hash(std::span(reinterpret_cast<const std::uint8_t*>(s.data()), s.size()));
}
Digest keyed_hash(const Digest& key, std::span<const std::uint8_t> data);
Digest derive_key(std::string_view context, std::span<const std::uint8_t> material);

// Plain hash of many independent inputs: out[i] = hash(inputs[i]) (out.size() must equal
// inputs.size()). Inputs of one block count (floor(len / 56) + 1 permutations) run in lanes;
// groups and batches are spread over TBB workers when `parallel` is set. Used for particle ids.
void hash_many(std::span<const std::span<const std::uint8_t>> inputs, std::span<Digest> out,
               bool parallel = true);
void hash_many(std::span<const std::string> inputs, std::span<Digest> out, bool parallel = true);

// Tree mode: a left-balanced binary tree over 4096-byte chunks (one leaf when the input is at
// most one chunk, the empty input included). Leaves and parent nodes are hashed in lanes and,
// when `parallel` is set, on TBB workers; the digest depends on neither.
Digest hash_leaf(std::span<const std::uint8_t> chunk, std::uint64_t counter, bool is_root);
Digest hash_node(const Digest& left, const Digest& right, bool is_root);
Digest root_hash(std::span<const std::uint8_t> data, bool parallel = true);

// The tree by its leaves, for inputs that change in place between versions (epoch files, R1-HASH-024):
// root_hash(data) == root_of_leaves(tree_leaves(data)). tree_leaves_reusing gives the same leaves,
// taking leaf i from previous_leaves (the leaves of `previous`) when chunk i of data equals chunk
// i of previous byte for byte and both have more than one leaf; it hashes only the others.
std::vector<Digest> tree_leaves(std::span<const std::uint8_t> data, bool parallel = true);
std::vector<Digest> tree_leaves_reusing(std::span<const std::uint8_t> data, std::span<const std::uint8_t> previous,
                                        std::span<const Digest> previous_leaves, bool parallel = true);
// leaves.size() >= 1.
Digest root_of_leaves(std::vector<Digest> leaves, bool parallel = true);
// The number of leaves of the tree over total_bytes: ceil(total_bytes / 4096), at least 1.
std::uint64_t leaf_count(std::uint64_t total_bytes);

// Tree hash of a stream whose chunks are produced on demand: chunk(i, out) fills `out` (4096
// bytes, or fewer for the last chunk) and returns the byte count. Used to hash large record
// streams without materialising them. `chunk` may be called concurrently for different i.
template <class ChunkFn>
Digest root_hash_chunks(std::uint64_t total_bytes, ChunkFn&& chunk, bool parallel = true);
// Leaves todo[k] of that tree (leaves.size() == leaf_count(total_bytes)): leaves[todo[k]] is
// written and every other entry left as it is. For streams whose unchanged chunks are known by
// other means (the snapshot digest of a chain's next epoch, R1-EPO-017).
template <class ChunkFn>
void chunk_leaves(std::uint64_t total_bytes, std::span<const std::uint64_t> todo, ChunkFn&& chunk,
                  std::span<Digest> leaves, bool parallel = true);

std::string to_hex(std::span<const std::uint8_t> bytes);
inline std::string to_hex(const Digest& d) { return to_hex(std::span<const std::uint8_t>(d)); }
// Parses exactly 64 hex digits (either case); false on anything else.
bool from_hex(std::string_view hex, Digest& out);

namespace detail {
// Combines leaf digests into the left-balanced root recursively (leaves.size() >= 1): the
// definition the batched level-by-level merge is tested against.
Digest merge_leaves(std::span<const Digest> leaves, bool is_root);
// Fills `out` with chunk `index` and returns its length (see root_hash_chunks).
using ChunkFill = std::size_t (*)(const void* ctx, std::uint64_t index, std::span<std::uint8_t> out);
Digest tree_hash(std::uint64_t total_bytes, const void* ctx, ChunkFill fill, bool parallel);
void tree_leaves_of(std::uint64_t total_bytes, std::span<const std::uint64_t> todo, const void* ctx, ChunkFill fill,
                    std::span<Digest> leaves, bool parallel);
template <class Fn>
ChunkFill chunk_fill() {
  return [](const void* ctx, std::uint64_t i, std::span<std::uint8_t> out) -> std::size_t {
    return (*const_cast<Fn*>(static_cast<const Fn*>(ctx)))(i, out);
  };
}
}  // namespace detail

template <class ChunkFn>
Digest root_hash_chunks(std::uint64_t total_bytes, ChunkFn&& chunk, bool parallel) {
  using Fn = std::remove_reference_t<ChunkFn>;
  return detail::tree_hash(total_bytes, static_cast<const void*>(&chunk), detail::chunk_fill<Fn>(), parallel);
}
template <class ChunkFn>
void chunk_leaves(std::uint64_t total_bytes, std::span<const std::uint64_t> todo, ChunkFn&& chunk,
                  std::span<Digest> leaves, bool parallel) {
  using Fn = std::remove_reference_t<ChunkFn>;
  detail::tree_leaves_of(total_bytes, todo, static_cast<const void*>(&chunk), detail::chunk_fill<Fn>(), leaves, parallel);
}

}  // namespace r1::hemera
