// Open-addressing indexes that number keys by first appearance: particle and neuron ids (32-byte
// Hemera digests) and particle names. The keys live in the caller's table (a vector); the index
// holds only (hash tag, number) slots. Hand-written because std::unordered_map spends most of a
// 10^7-link load allocating nodes and chasing pointers, and Debian's Boost 1.74 predates
// boost::unordered_flat_map.
#pragma once

#include <array>
#include <cstdint>
#include <cstring>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "r1/fixedpoint/prefetch.hpp"

namespace r1 {

// Ids are uniform hash outputs: their first 8 bytes are already a good hash.
struct DigestKeyHash {
  std::uint64_t operator()(const std::array<std::uint8_t, 32>& id) const noexcept {
    std::uint64_t h;
    std::memcpy(&h, id.data(), sizeof h);
    return h;
  }
};

// Digest equality as four word compares: std::array's operator== goes through an out-of-line
// memcmp, which dominated the lookup profile.
struct DigestKeyEq {
  bool operator()(const std::array<std::uint8_t, 32>& a, const std::array<std::uint8_t, 32>& b) const noexcept {
    std::uint64_t x[4], y[4];
    std::memcpy(x, a.data(), 32);
    std::memcpy(y, b.data(), 32);
    return ((x[0] ^ y[0]) | (x[1] ^ y[1]) | (x[2] ^ y[2]) | (x[3] ^ y[3])) == 0;
  }
};

struct NameKeyHash {
  std::uint64_t operator()(std::string_view s) const noexcept { return std::hash<std::string_view>{}(s); }
};

template <class Key, class Hash, class View = const Key&, class Eq = std::equal_to<>>
class InternIndex {
 public:
  using key_type = Key;
  // The number of `key` in `table`, appending it first when it is new.
  std::uint32_t intern(View key, std::vector<Key>& table) {
    if ((table.size() + 1) * 2 > slots_.size()) grow(table);
    const std::uint64_t h = Hash{}(key);
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t s = static_cast<std::size_t>(h) & mask;; s = (s + 1) & mask) {  // linear probing
      const std::uint64_t v = slots_[s];
      if (v == kEmpty) {
        const auto n = static_cast<std::uint32_t>(table.size());
        table.emplace_back(key);
        slots_[s] = pack(h, n);
        return n;
      }
      if (tag(v) == tag_of(h) && Eq{}(View(table[index(v)]), key)) return index(v);
    }
  }

  // An index over an existing table of distinct keys.
  static InternIndex over(const std::vector<Key>& table) {
    InternIndex x;
    x.grow(table);
    return x;
  }

  // The number of `key` in the table this index covers, or -1 when absent.
  std::int64_t find(View key, const std::vector<Key>& table) const {
    if (slots_.empty()) return -1;
    const std::uint64_t h = Hash{}(key);
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t s = static_cast<std::size_t>(h) & mask;; s = (s + 1) & mask) {
      const std::uint64_t v = slots_[s];
      if (v == kEmpty) return -1;
      if (tag(v) == tag_of(h) && Eq{}(View(table[index(v)]), key)) return index(v);
    }
  }

  // A hint for a lookup of `key` soon (no effect on any result), for an index that is not empty:
  // fetch the key's home slot. Unconditional: with an emptiness test here, and likewise for a
  // fetch of the table entry the slot names, GCC 12 left no prefetch instruction in the reader's
  // loop (seen in its object code).
  void prefetch_slot(View key) const {
    fx::gather_hint(slots_.data() + (static_cast<std::size_t>(Hash{}(key)) & (slots_.size() - 1)));
  }

  void clear() { std::vector<std::uint64_t>().swap(slots_); }

 private:
  // A slot packs the key's upper hash bits (a tag that settles most mismatches without touching
  // the table) and its number; all ones is empty (number 2^32 - 1 is never used, R1-IN-010).
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};
  static std::uint32_t tag_of(std::uint64_t h) { return static_cast<std::uint32_t>(h >> 32); }
  static std::uint64_t pack(std::uint64_t h, std::uint32_t n) { return (std::uint64_t{tag_of(h)} << 32) | n; }
  static std::uint32_t tag(std::uint64_t v) { return static_cast<std::uint32_t>(v >> 32); }
  static std::uint32_t index(std::uint64_t v) { return static_cast<std::uint32_t>(v); }

  // Load factor at most 1/2; rebuilding keeps every number.
  void grow(const std::vector<Key>& table) {
    std::size_t cap = slots_.empty() ? 1024 : slots_.size() * 2;
    while (cap < (table.size() + 1) * 2) cap *= 2;
    slots_.assign(cap, kEmpty);
    const std::size_t mask = cap - 1;
    for (std::uint32_t i = 0; i < table.size(); ++i) {
      const std::uint64_t h = Hash{}(View(table[i]));
      std::size_t s = static_cast<std::size_t>(h) & mask;
      while (slots_[s] != kEmpty) s = (s + 1) & mask;
      slots_[s] = pack(h, i);
    }
  }
  std::vector<std::uint64_t> slots_;
};

using IdIndex = InternIndex<std::array<std::uint8_t, 32>, DigestKeyHash, const std::array<std::uint8_t, 32>&, DigestKeyEq>;
using NameIndex = InternIndex<std::string, NameKeyHash, std::string_view>;

}  // namespace r1
