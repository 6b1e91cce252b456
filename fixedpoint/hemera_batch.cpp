// Hemera bulk paths (R1-HASH-010..012, R1-HASH-020..022): hash_many and the tree hash, in lanes and
// on TBB workers, bit-identical to the one-at-a-time definitions.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cassert>
#include <memory>
#include <utility>
#include <vector>

#include "hemera_internal.hpp"

namespace r1::hemera {

using namespace detail;

namespace {

struct Input {
  const std::uint8_t* data;
  std::size_t len;
};

// Full 56-byte blocks before the finalisation block: the sponge's control flow depends on this
// alone, so inputs that share it can run in lockstep.
std::size_t full_blocks(std::size_t len) { return len / RATE_BYTES; }

// Plain-hash digests of L inputs with `blocks` full blocks each: every block is absorbed into all
// lanes, then the lanes are permuted together; each lane sees exactly the one-input sponge.
template <std::size_t L>
void sponge_lanes(const Input* in, std::size_t blocks, Digest* out) {
  State st[L] = {};  // domain tag 0 (plain hash): the all-zero state
  const std::uint8_t* data[L];
  for (std::size_t k = 0; k < L; ++k) data[k] = in[k].data;
  absorb_blocks<L>(st, data, blocks);
  for (std::size_t k = 0; k < L; ++k) {
    const std::size_t done = blocks * RATE_BYTES;
    absorb_final(st[k], in[k].data + done, in[k].len - done, in[k].len);
  }
  permute_lanes<L>(st);
  for (std::size_t k = 0; k < L; ++k) out[k] = digest_of(st[k]);
}

// Plain-hash digests of n inputs that share one block count, in lockstep groups (split_lanes).
void sponge_group(const Input* in, std::size_t n, Digest* out) {
  if (n == 0) return;
  const std::size_t blocks = full_blocks(in[0].len);
  split_lanes(n, lane_batching(), [&](auto lanes, std::size_t first) {
    sponge_lanes<decltype(lanes)::value>(in + first, blocks, out + first);
  });
}

// Runs body(i) for i in [0, n): on TBB workers when `parallel`, in order otherwise. Every i
// writes only its own outputs, so the results cannot depend on the schedule.
template <class Body>
void for_each_index(std::size_t n, bool parallel, const Body& body) {
  if (parallel && n > 1) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i) body(i);
    });
  } else {
    for (std::size_t i = 0; i < n; ++i) body(i);
  }
}

// Input indices ordered by block count, cut into batches of at most LANES inputs of one block
// count: counting sort while the counts are small (names, records), a comparison sort otherwise.
struct Batches {
  std::vector<std::size_t> order;
  std::vector<std::size_t> starts;  // batch b is order[starts[b], starts[b + 1])
};

template <class Get>
Batches make_batches(std::size_t n, const Get& get) {
  Batches bt;
  std::vector<std::size_t> key(n);
  std::size_t max_key = 0;
  for (std::size_t i = 0; i < n; ++i) max_key = std::max(max_key, key[i] = full_blocks(get(i).len));
  bt.order.resize(n);
  // 2^16 buckets cost nothing next to hashing inputs that long; beyond that sort pairs.
  if (max_key < (std::size_t{1} << 16)) {
    std::vector<std::size_t> pos(max_key + 2, 0);
    for (std::size_t i = 0; i < n; ++i) ++pos[key[i] + 1];
    for (std::size_t k = 1; k < pos.size(); ++k) pos[k] += pos[k - 1];
    for (std::size_t i = 0; i < n; ++i) bt.order[pos[key[i]]++] = i;
  } else {
    std::vector<std::pair<std::size_t, std::size_t>> kv(n);
    for (std::size_t i = 0; i < n; ++i) kv[i] = {key[i], i};
    std::sort(kv.begin(), kv.end());
    for (std::size_t i = 0; i < n; ++i) bt.order[i] = kv[i].second;
  }
  for (std::size_t i = 0; i < n;) {
    bt.starts.push_back(i);
    const std::size_t k = key[bt.order[i]];
    std::size_t j = i + 1;
    while (j < n && j - i < LANES && key[bt.order[j]] == k) ++j;
    i = j;
  }
  bt.starts.push_back(n);
  return bt;
}

template <class Get>
void hash_many_impl(std::size_t n, const Get& get, std::span<Digest> out, bool parallel) {
  assert(out.size() == n);
  const Batches bt = make_batches(n, get);
  for_each_index(bt.starts.size() - 1, parallel, [&](std::size_t b) {
    Input in[LANES];
    Digest d[LANES];
    const std::size_t first = bt.starts[b], m = bt.starts[b + 1] - first;
    for (std::size_t j = 0; j < m; ++j) in[j] = get(bt.order[first + j]);
    sponge_group(in, m, d);
    for (std::size_t j = 0; j < m; ++j) out[bt.order[first + j]] = d[j];
  });
}

// Leaves counter[0..m) (m <= LANES) of an n-leaf tree: plain digests of their chunks in lanes,
// then the binding permutations in lanes. Chunks are grouped by block count: all full chunks share
// one, and a short chunk (the stream's last) runs in a group of its own.
void leaf_batch(const Input* chunks, std::size_t m, const std::uint64_t* counter, std::uint64_t n, Digest* out) {
  std::size_t order[LANES];
  for (std::size_t j = 0; j < m; ++j) order[j] = j;
  std::stable_sort(order, order + m, [&](std::size_t x, std::size_t y) {
    return full_blocks(chunks[x].len) < full_blocks(chunks[y].len);
  });
  Input sorted[LANES];
  Digest digests[LANES], plain[LANES];
  for (std::size_t j = 0; j < m; ++j) sorted[j] = chunks[order[j]];
  for (std::size_t a = 0; a < m;) {
    std::size_t b = a + 1;
    while (b < m && full_blocks(sorted[b].len) == full_blocks(sorted[a].len)) ++b;
    sponge_group(sorted + a, b - a, digests + a);
    a = b;
  }
  for (std::size_t j = 0; j < m; ++j) plain[order[j]] = digests[j];
  State st[LANES];
  for (std::size_t j = 0; j < m; ++j) st[j] = leaf_state(plain[j], counter[j], n == 1);
  permute_states(st, m);
  for (std::size_t j = 0; j < m; ++j) out[j] = digest_of(st[j]);
}

// Left-balanced merge, level by level: pair neighbours from the left and carry an odd last node
// up unchanged. The left subtree of n leaves is the perfect tree over the largest power of two
// below n, whose levels always hold an even number of nodes, so no pair straddles it: this is
// merge_leaves' recursion, with each level's parents independent and hashed in lanes.
Digest merge_levels(std::vector<Digest> level, bool parallel) {
  while (level.size() > 1) {
    const std::size_t pairs = level.size() / 2;
    const bool top = level.size() == 2;
    std::vector<Digest> next(pairs + level.size() % 2);
    const std::size_t batches = (pairs + LANES - 1) / LANES;
    // Parents are 1/75 of the work of their leaves: spread a level only when it is wide.
    for_each_index(batches, parallel && pairs >= 64, [&](std::size_t b) {
      const std::size_t first = b * LANES, m = std::min(LANES, pairs - first);
      State st[LANES];
      for (std::size_t j = 0; j < m; ++j) st[j] = node_state(level[2 * (first + j)], level[2 * (first + j) + 1], top);
      permute_states(st, m);
      for (std::size_t j = 0; j < m; ++j) next[first + j] = digest_of(st[j]);
    });
    if (level.size() % 2 == 1) next.back() = level.back();
    level = std::move(next);
  }
  return level[0];
}

// Leaves todo[0..count) of an n-leaf tree over a chunk source (get(i, scratch) returns chunk i,
// either pointing into memory it already has or filling the 4096-byte scratch buffer), written
// to leaves[todo[k]], in batches of LANES.
template <class Source>
void hash_leaves(std::uint64_t n, const std::uint64_t* todo, std::size_t count, const Source& get, Digest* leaves,
                 bool parallel) {
  const std::size_t batches = (count + LANES - 1) / LANES;
  for_each_index(batches, parallel, [&](std::size_t b) {
    const std::unique_ptr<std::uint8_t[]> scratch(new std::uint8_t[LANES * CHUNK_BYTES]);
    const std::uint64_t* counter = todo + b * LANES;
    const std::size_t m = std::min(LANES, count - b * LANES);
    Input in[LANES];
    Digest out[LANES];
    for (std::size_t j = 0; j < m; ++j) {
      const std::span<const std::uint8_t> c = get(counter[j], scratch.get() + j * CHUNK_BYTES);
      in[j] = {c.data(), c.size()};
    }
    leaf_batch(in, m, counter, n, out);
    for (std::size_t j = 0; j < m; ++j) leaves[counter[j]] = out[j];
  });
}

// Every leaf of the tree over a chunk source (see hash_leaves).
template <class Source>
std::vector<Digest> all_leaves(std::uint64_t total_bytes, const Source& get, bool parallel) {
  const std::uint64_t n = leaf_count(total_bytes);
  std::vector<Digest> leaves(static_cast<std::size_t>(n));
  std::vector<std::uint64_t> todo(static_cast<std::size_t>(n));
  for (std::uint64_t i = 0; i < n; ++i) todo[static_cast<std::size_t>(i)] = i;
  hash_leaves(n, todo.data(), todo.size(), get, leaves.data(), parallel);
  return leaves;
}

template <class Source>
Digest tree_hash_impl(std::uint64_t total_bytes, const Source& get, bool parallel) {
  return merge_levels(all_leaves(total_bytes, get, parallel), parallel);
}

// Chunk i of a byte span.
struct SpanChunks {
  std::span<const std::uint8_t> data;
  std::span<const std::uint8_t> operator()(std::uint64_t i, std::uint8_t*) const {
    const std::size_t off = static_cast<std::size_t>(i) * CHUNK_BYTES;
    return data.subspan(off, std::min(CHUNK_BYTES, data.size() - off));
  }
};

}  // namespace

void hash_many(std::span<const std::span<const std::uint8_t>> inputs, std::span<Digest> out, bool parallel) {
  hash_many_impl(
      inputs.size(), [&](std::size_t i) { return Input{inputs[i].data(), inputs[i].size()}; }, out, parallel);
}

void hash_many(std::span<const std::string> inputs, std::span<Digest> out, bool parallel) {
  hash_many_impl(
      inputs.size(),
      [&](std::size_t i) { return Input{reinterpret_cast<const std::uint8_t*>(inputs[i].data()), inputs[i].size()}; },
      out, parallel);
}

Digest root_hash(std::span<const std::uint8_t> data, bool parallel) {
  return tree_hash_impl(data.size(), SpanChunks{data}, parallel);
}

std::vector<Digest> tree_leaves(std::span<const std::uint8_t> data, bool parallel) {
  return all_leaves(data.size(), SpanChunks{data}, parallel);
}

std::vector<Digest> tree_leaves_reusing(std::span<const std::uint8_t> data, std::span<const std::uint8_t> previous,
                                        std::span<const Digest> previous_leaves, bool parallel) {
  const std::uint64_t n = leaf_count(data.size());
  std::vector<Digest> leaves(static_cast<std::size_t>(n));
  std::vector<std::uint64_t> todo;
  // A leaf digest binds its chunk, its index and whether it is the root (one leaf in all): with
  // more than one leaf on both sides, equal chunks at one index have equal digests.
  const bool reuse = n > 1 && previous_leaves.size() > 1 && previous_leaves.size() == leaf_count(previous.size());
  const SpanChunks now{data}, before{previous};
  for (std::uint64_t i = 0; i < n; ++i) {
    if (reuse && i < previous_leaves.size()) {
      const auto a = now(i, nullptr), b = before(i, nullptr);
      if (a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin())) {
        leaves[static_cast<std::size_t>(i)] = previous_leaves[static_cast<std::size_t>(i)];
        continue;
      }
    }
    todo.push_back(i);
  }
  hash_leaves(n, todo.data(), todo.size(), now, leaves.data(), parallel);
  return leaves;
}

std::uint64_t leaf_count(std::uint64_t total_bytes) {
  return total_bytes == 0 ? 1 : (total_bytes + CHUNK_BYTES - 1) / CHUNK_BYTES;
}

Digest root_of_leaves(std::vector<Digest> leaves, bool parallel) {
  assert(!leaves.empty());
  return merge_levels(std::move(leaves), parallel);
}

namespace detail {

namespace {
// Chunk i of a ChunkFill source, filled into the caller's scratch.
struct FilledChunks {
  const void* ctx;
  ChunkFill fill;
  std::span<const std::uint8_t> operator()(std::uint64_t i, std::uint8_t* scratch) const {
    const std::size_t len = std::min(CHUNK_BYTES, fill(ctx, i, std::span<std::uint8_t>(scratch, CHUNK_BYTES)));
    return std::span<const std::uint8_t>(scratch, len);
  }
};
}  // namespace

Digest tree_hash(std::uint64_t total_bytes, const void* ctx, ChunkFill fill, bool parallel) {
  return tree_hash_impl(total_bytes, FilledChunks{ctx, fill}, parallel);
}

void tree_leaves_of(std::uint64_t total_bytes, std::span<const std::uint64_t> todo, const void* ctx, ChunkFill fill,
                    std::span<Digest> leaves, bool parallel) {
  const std::uint64_t n = leaf_count(total_bytes);
  assert(leaves.size() == n);
  for ([[maybe_unused]] const std::uint64_t i : todo) assert(i < n);
  hash_leaves(n, todo.data(), todo.size(), FilledChunks{ctx, fill}, leaves.data(), parallel);
}

}  // namespace detail

}  // namespace r1::hemera
