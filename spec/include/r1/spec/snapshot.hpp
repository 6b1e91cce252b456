// The snapshot data model: config, particles in canonical order, links, the 128-byte record and
// the snapshot digest (R1-IN-001..006, R1-IN-020..024, R1-IN-040..041).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "r1/fixedpoint/hemera.hpp"
#include "r1/fixedpoint/int128.hpp"
#include "r1/spec/crystal.hpp"

namespace r1 {

using ParticleId = hemera::Digest;
using NeuronId = hemera::Digest;

inline constexpr std::size_t kRecordBytes = 128;
// section 4.1 / decision 2: the anchor set is the first min(1024, |P|) particles.
inline constexpr std::size_t kAnchorMax = 1024;
inline std::size_t anchor_count(std::size_t particles) { return particles < kAnchorMax ? particles : kAnchorMax; }

struct Token {
  std::string symbol;
  std::uint64_t weight_permille = 1000;  // 1000 = 1.0x (integer per-mille, never a float)
};

struct SnapshotConfig {
  std::string chain_id;
  std::uint64_t block = 0;
  std::int64_t captured_at = 0;
  std::int64_t format_version = 1;
  std::map<std::uint32_t, Token> tokens;
};

// One cyberlink. Endpoints and neuron are indices into the snapshot's tables; together with
// those tables a Link reproduces its 128-byte record exactly (padding is always zero).
struct Link {
  u128 amount = 0;           // stake amount, smallest unit (text inputs: weight * 2^32)
  std::uint64_t height = 0;  // block height
  std::uint32_t neuron = 0;  // index into Snapshot::neurons
  std::uint32_t from = 0;    // index into Snapshot::particles
  std::uint32_t to = 0;
  std::uint32_t token = 0;   // key of SnapshotConfig::tokens
  std::int8_t valence = 0;   // -1, 0, +1
};

struct Snapshot {
  std::string source;                  // where it came from, for messages
  SnapshotConfig config;
  std::string card;                    // markdown description
  std::vector<ParticleId> particles;   // canonical order: first appearance, source before target
  std::vector<NeuronId> neurons;       // first appearance order
  std::vector<Link> links;             // chain order
  std::vector<std::string> names;      // text inputs: the name each particle id hashes; else empty
  std::vector<std::string> titles;     // per particle ("" = none); empty vector = no titles
  std::vector<CrystalTag> crystal;     // per particle; empty vector = no crystal metadata
};

// Serialises one link as its canonical 128-byte little-endian record.
void encode_record(const Snapshot& s, const Link& l, std::uint8_t out[kRecordBytes]);

// The snapshot digest (decision 9, R1-IN-040): Hemera tree hash of the canonical record stream.
hemera::Digest snapshot_digest(const Snapshot& s);

// SHA-256 (FIPS 180-4) of a byte string.
using Sha256 = std::array<std::uint8_t, 32>;
Sha256 sha256(std::span<const std::uint8_t> bytes);

// Per 4096-byte chunk of the record stream (R1-EPO-017, an epoch's `records.chunks`): the chunk's
// SHA-256 and its leaf in the digest's tree.
struct RecordChunks {
  std::vector<Sha256> sha;
  std::vector<hemera::Digest> leaves;
  // How many leaves the snapshot_digest that filled these hashed with Hemera (the others came
  // from `previous`); not stored in the file.
  std::size_t hashed = 0;
};

// Leaves taken from an earlier version of a chunked byte stream (R1-EPO-017, R1-EPO-018): where
// both have more than one chunk and previous_sha has a leaf for each, leaves[i] =
// previous_leaves[i] for every i with sha[i] == previous_sha[i] (a leaf binds its chunk, its index
// and the ROOT flag alone). Returns the other indices, ascending: the chunks to hash.
// leaves.size() == sha.size().
std::vector<std::uint64_t> leaves_by_sha(std::span<const Sha256> sha, std::span<const Sha256> previous_sha,
                                         std::span<const hemera::Digest> previous_leaves, std::span<hemera::Digest> leaves);

// The snapshot digest and, in `chunks`, every chunk's SHA-256 and leaf. With `previous` (the
// chunks of an earlier version of the stream: the epoch before in a chain), chunk i takes
// previous's leaf i instead of being hashed when its SHA-256 is previous's sha[i] and both streams
// have more than one chunk. The digest is the same with or without `previous`.
hemera::Digest snapshot_digest(const Snapshot& s, RecordChunks& chunks, const RecordChunks* previous = nullptr);

// Title of particle i for display: its title, else its name, else the first 16 hex digits of its id.
std::string display_name(const Snapshot& s, std::size_t i);

}  // namespace r1
