// The epoch directory: writing it atomically, reading and validating it, exporting TSV
// (R1-EPO-010..020).
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "r1/spec/epoch.hpp"
#include "r1/spec/status.hpp"

namespace r1 {

struct EpochWriteOptions {
  bool timings = true;  // R1-EPO-013: false leaves timings_s out so every byte is reproducible
  // Files made beside the stages' (the trained field, R1-NRF-030), by name: written and listed in
  // the manifest like the others.
  std::vector<std::pair<std::string, std::string>> extra;
};

// The canonical bytes of each output file, by file name (manifest.json excluded).
Result<std::vector<std::pair<std::string, std::string>>> epoch_files(const Epoch& e);
std::string epoch_manifest(const Epoch& e, const std::vector<std::pair<std::string, std::string>>& files,
                           const EpochWriteOptions& o);

Status write_epoch(const Epoch& e, const std::filesystem::path& dir, const EpochWriteOptions& o = {});
Result<Epoch> read_epoch(const std::filesystem::path& dir);

// Adds (or replaces) the file `name` of an existing epoch directory and lists it in the manifest
// with its size and digest (R1-NRF-030): the file, then the manifest, each written atomically.
Status add_epoch_file(const std::filesystem::path& dir, const std::string& name, std::string_view bytes);

// R1-EPO-020: one row per particle.
std::string export_tsv(const Epoch& e);

}  // namespace r1
