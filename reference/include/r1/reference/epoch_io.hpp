// The epoch directory: writing it atomically, reading and validating it, exporting TSV
// (R1-EPO-010..020).
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "r1/spec/epoch.hpp"
#include "r1/spec/status.hpp"

namespace r1 {

// The files of an epoch as read (R1-EPO-016): its directory and each listed file's tree leaves
// (R1-HASH-024), which were checked against the manifest's digest, and, for the files checked
// through the chunk table (R1-EPO-018), their chunks' SHA-256s.
struct EpochLeaves {
  std::filesystem::path dir;
  std::map<std::string, std::vector<hemera::Digest>> leaves;
  std::map<std::string, std::vector<Sha256>> sha;
};

// How read_epoch checks the files against the manifest's digests (R1-EPO-014, R1-EPO-018):
// hashing every chunk with Hemera, or, for the files the chunk table covers, each chunk's SHA-256
// against the table and the table's leaves against the digest (the chain's next epoch reading
// PREV, which trusts PREV's pairing of SHA-256 and leaf as it trusts the rest of PREV).
enum class DigestCheck { kHashEveryChunk, kChunkTable };

struct EpochWriteOptions {
  bool timings = true;  // R1-EPO-013: false leaves timings_s out so every byte is reproducible
  // Files made beside the stages' (the trained field, R1-NRF-030), by name: written and listed in
  // the manifest like the others.
  std::vector<std::pair<std::string, std::string>> extra;
  // The epoch before (R1-EPO-016): a file it lists is digested by hashing only the chunks that
  // differ from its file there. The digests do not depend on it.
  const EpochLeaves* previous = nullptr;
};

// The canonical bytes of each output file of the stages, by file name (manifest.json and the
// chunk table, which write_epoch makes from these, excluded).
Result<std::vector<std::pair<std::string, std::string>>> epoch_files(const Epoch& e);

Status write_epoch(const Epoch& e, const std::filesystem::path& dir, const EpochWriteOptions& o = {});
// `leaves`, if given, receives the directory and every listed file's tree leaves (R1-EPO-016).
Result<Epoch> read_epoch(const std::filesystem::path& dir, EpochLeaves* leaves = nullptr,
                         DigestCheck check = DigestCheck::kHashEveryChunk);

// The record chunks of the epoch in `dir` (its records.chunks) read by themselves and checked
// against nothing: empty when the manifest does not list the file or the file is missing or not
// whole rows. For the next epoch of a chain,
// whose digest reuses them while read_epoch is still checking the rest of PREV; that read then
// checks them, and the caller compares the two (R1-EPO-019).
RecordChunks peek_record_chunks(const std::filesystem::path& dir);

// Adds (or replaces) the file `name` of an existing epoch directory and lists it in the manifest
// with its size and digest (R1-NRF-030): the file, then the manifest, each written atomically.
Status add_epoch_file(const std::filesystem::path& dir, const std::string& name, std::string_view bytes);

// R1-EPO-020: one row per particle.
std::string export_tsv(const Epoch& e);

}  // namespace r1
