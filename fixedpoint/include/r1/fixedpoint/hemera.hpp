// Hemera v2 (Poseidon2 over Goldilocks): permutation, plain/keyed/derive-key sponge and tree
// hash with 32-byte digests (R1-HASH-001..012, spec/hemera.md).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "r1/fixedpoint/goldilocks.hpp"

namespace r1::hemera {

inline constexpr std::size_t WIDTH = 16;
inline constexpr std::size_t RATE = 8;
inline constexpr std::size_t RATE_BYTES = 56;      // 8 elements x 7 bytes
inline constexpr std::size_t DIGEST_BYTES = 32;    // elements 0..3, 8 bytes little-endian each
inline constexpr std::size_t CHUNK_BYTES = 4096;   // tree-mode leaf size

using State = std::array<std::uint64_t, WIDTH>;
using Digest = std::array<std::uint8_t, DIGEST_BYTES>;

// The Hemera permutation on 16 canonical field elements.
void permute(State& s);

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

// Tree mode: a left-balanced binary tree over 4096-byte chunks (one leaf when the input is at
// most one chunk, the empty input included). Leaves are hashed in parallel when `parallel` is
// set; the digest does not depend on it.
Digest hash_leaf(std::span<const std::uint8_t> chunk, std::uint64_t counter, bool is_root);
Digest hash_node(const Digest& left, const Digest& right, bool is_root);
Digest root_hash(std::span<const std::uint8_t> data, bool parallel = true);

// Tree hash of a stream whose chunks are produced on demand: chunk(i, out) fills `out` (4096
// bytes, or fewer for the last chunk) and returns the byte count. Used to hash large record
// streams without materialising them.
template <class ChunkFn>
Digest root_hash_chunks(std::uint64_t total_bytes, ChunkFn&& chunk, bool parallel = true);

std::string to_hex(std::span<const std::uint8_t> bytes);
inline std::string to_hex(const Digest& d) { return to_hex(std::span<const std::uint8_t>(d)); }
// Parses exactly 64 hex digits (either case); false on anything else.
bool from_hex(std::string_view hex, Digest& out);

namespace detail {
// Combines precomputed leaf digests into the left-balanced root (leaves.size() >= 1).
Digest merge_leaves(std::span<const Digest> leaves, bool is_root);
void parallel_for(std::size_t n, const void* ctx, void (*body)(const void*, std::size_t));
}  // namespace detail

template <class ChunkFn>
Digest root_hash_chunks(std::uint64_t total_bytes, ChunkFn&& chunk, bool parallel) {
  const std::uint64_t n = total_bytes == 0 ? 1 : (total_bytes + CHUNK_BYTES - 1) / CHUNK_BYTES;
  std::vector<Digest> leaves(static_cast<std::size_t>(n));
  struct Ctx {
    ChunkFn* fn;
    std::vector<Digest>* leaves;
    std::uint64_t n;
  } ctx{&chunk, &leaves, n};
  auto body = [](const void* c, std::size_t i) {
    const Ctx& x = *static_cast<const Ctx*>(c);
    std::array<std::uint8_t, CHUNK_BYTES> buf;
    const std::size_t len = (*x.fn)(static_cast<std::uint64_t>(i), std::span<std::uint8_t>(buf));
    (*x.leaves)[i] = hash_leaf(std::span<const std::uint8_t>(buf.data(), len), i, x.n == 1);
  };
  if (parallel) {
    detail::parallel_for(leaves.size(), &ctx, body);
  } else {
    for (std::size_t i = 0; i < leaves.size(); ++i) body(&ctx, i);
  }
  return n == 1 ? leaves[0] : detail::merge_leaves(leaves, true);
}

}  // namespace r1::hemera
