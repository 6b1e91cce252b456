// The epoch's chunk table (R1-EPO-018, `files.chunks`): per 4096-byte chunk of each listed file,
// its SHA-256 and its leaf in the file's Hemera tree, so that the next epoch of a chain checks
// PREV's files at SHA-256 speed and takes PREV's leaves for the chunks that did not change.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "r1/fixedpoint/hemera.hpp"
#include "r1/spec/snapshot.hpp"
#include "r1/spec/status.hpp"

namespace r1::epoch_chunks {

inline constexpr std::size_t kRowBytes = 64;  // SHA-256, then the Hemera leaf

// One file's chunks: sha[i] and leaves[i] for chunk i (leaf_count(bytes) of each).
struct FileChunks {
  std::vector<Sha256> sha;
  std::vector<hemera::Digest> leaves;
};

// Every chunk's SHA-256 of `bytes`, on TBB workers.
std::vector<Sha256> chunk_sha(std::span<const std::uint8_t> bytes);

// The chunks of `bytes` with their leaves: where the same file in the epoch before (its chunks'
// SHA-256s and leaves, empty when there is none) has the same SHA-256 at index i and both files
// have more than one chunk, leaf i is the earlier one (a leaf binds its chunk, its index and the
// ROOT flag alone, R1-HASH-024); the other leaves are hashed. The leaves are tree_leaves(bytes)
// either way.
FileChunks chunk_file(std::span<const std::uint8_t> bytes, std::span<const Sha256> previous_sha = {},
                      std::span<const hemera::Digest> previous_leaves = {});

// The table's rows for `files` in order.
std::string table_bytes(std::span<const FileChunks> files);

// Checks `bytes` (the file `path`) against `rows`, its rows of the table, and its manifest digest:
// each chunk's SHA-256 must be the row's, and the rows' leaves must merge to `digest`. Gives the
// chunks, or a one-line input error naming the file.
Result<FileChunks> check_file(std::span<const std::uint8_t> bytes, std::string_view rows, const hemera::Digest& digest,
                              const std::string& path);

}  // namespace r1::epoch_chunks
