// Hemera sponge modes one input at a time (R1-HASH-004..012): plain, keyed, derive-key, the tree's
// leaf and parent nodes and its recursive definition, hex.
#include <algorithm>
#include <cstring>

#include "hemera_internal.hpp"

namespace r1::hemera {

using namespace detail;

Hasher::Hasher() : Hasher(DOMAIN_HASH) {}

Hasher::Hasher(std::uint64_t domain) { state_[CAP_DOMAIN] = domain; }

Hasher Hasher::keyed(const Digest& key) {
  Hasher h(DOMAIN_KEYED);
  h.update(std::span<const std::uint8_t>(key));
  return h;
}

Hasher Hasher::derive_key_context() { return Hasher(DOMAIN_DERIVE_CONTEXT); }

Hasher Hasher::derive_key_material(const Digest& context_hash) {
  Hasher h(DOMAIN_DERIVE_MATERIAL);
  std::uint64_t w[4];
  digest_words(context_hash, w);
  for (std::size_t i = 0; i < 4; ++i) h.state_[i] = w[i];
  permute(h.state_);
  return h;
}

void Hasher::absorb_block(const std::uint8_t* block) {
  absorb_rate(state_, block);
  permute(state_);
}

Hasher& Hasher::update(std::span<const std::uint8_t> data) {
  absorbed_ += data.size();
  std::size_t pos = 0;
  if (buf_len_ > 0) {
    const std::size_t take = std::min(RATE_BYTES - buf_len_, data.size());
    std::memcpy(buf_.data() + buf_len_, data.data(), take);
    buf_len_ += take;
    pos = take;
    if (buf_len_ < RATE_BYTES) return *this;
    absorb_block(buf_.data());
    buf_len_ = 0;
  }
  while (data.size() - pos >= RATE_BYTES) {
    absorb_block(data.data() + pos);
    pos += RATE_BYTES;
  }
  buf_len_ = data.size() - pos;
  if (buf_len_ > 0) std::memcpy(buf_.data(), data.data() + pos, buf_len_);
  return *this;
}

Digest Hasher::finalize() const {
  // Always one padded block, even after a whole number of blocks.
  State s = state_;
  absorb_final(s, buf_.data(), buf_len_, absorbed_);
  permute(s);
  return digest_of(s);
}

Digest hash(std::span<const std::uint8_t> data) { return Hasher().update(data).finalize(); }

Digest keyed_hash(const Digest& key, std::span<const std::uint8_t> data) {
  return Hasher::keyed(key).update(data).finalize();
}

Digest derive_key(std::string_view context, std::span<const std::uint8_t> material) {
  const Digest ctx = Hasher::derive_key_context().update(context).finalize();
  return Hasher::derive_key_material(ctx).update(material).finalize();
}

Digest hash_leaf(std::span<const std::uint8_t> chunk, std::uint64_t counter, bool is_root) {
  // Content first through the plain sponge, then one permutation binds position and flags.
  State s = leaf_state(hash(chunk), counter, is_root);
  permute(s);
  return digest_of(s);
}

Digest hash_node(const Digest& left, const Digest& right, bool is_root) {
  State s = node_state(left, right, is_root);
  permute(s);
  return digest_of(s);
}

namespace detail {

Digest merge_leaves(std::span<const Digest> leaves, bool is_root) {
  if (leaves.size() == 1) return leaves[0];
  // Left subtree: the largest power of two strictly below the leaf count.
  std::size_t split = 1;
  while (split * 2 < leaves.size()) split *= 2;
  const Digest l = merge_leaves(leaves.subspan(0, split), false);
  const Digest r = merge_leaves(leaves.subspan(split), false);
  return hash_node(l, r, is_root);
}

}  // namespace detail

std::string to_hex(std::span<const std::uint8_t> bytes) {
  static constexpr char digits[] = "0123456789abcdef";
  std::string s(bytes.size() * 2, '0');
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    s[2 * i] = digits[bytes[i] >> 4];
    s[2 * i + 1] = digits[bytes[i] & 15];
  }
  return s;
}

bool from_hex(std::string_view hex, Digest& out) {
  if (hex.size() != 2 * DIGEST_BYTES) return false;
  auto nib = [](char c) -> int {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
  };
  for (std::size_t i = 0; i < DIGEST_BYTES; ++i) {
    const int hi = nib(hex[2 * i]), lo = nib(hex[2 * i + 1]);
    if (hi < 0 || lo < 0) return false;
    out[i] = static_cast<std::uint8_t>(hi * 16 + lo);
  }
  return true;
}

}  // namespace r1::hemera
