// T0 content of an epoch (spec/epoch.md R1-EPO-030..036): the content side file given to
// `r1 epoch --content`, the copies and the index (content.tsv) written into the epoch directory,
// and reading them back for the renderer and the viewer. Here rather than in the core library
// because telling an image from other bytes takes OpenImageIO.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "r1/spec/snapshot.hpp"
#include "r1/spec/status.hpp"

namespace r1::render {

// What became of a side-file entry (R1-EPO-032): read and copied, absent, present but not
// readable (not a regular file, too large, a text that is not UTF-8, an image OpenImageIO cannot
// read), or refused because its path leaves the side file's folder.
enum class ContentStatus : std::uint8_t { kOk, kMissing, kUnreadable, kRefused };
// How T0 draws it (R1-EPO-033, R1-RND-130): an image on a panel, text on a curved surface, or a
// card naming its type.
enum class ContentKind : std::uint8_t { kImage, kText, kOther };

struct ContentEntry {
  std::uint32_t particle = 0;
  ContentStatus status = ContentStatus::kOk;
  ContentKind kind = ContentKind::kOther;  // meaningful for kOk
  std::string type;    // lower-case extension ("png", "txt", "pdf"), "binary" or "text" without one
  std::string source;  // the path as the side file gives it
  std::string file;    // kOk: the copy's name inside the epoch, content/K[.ext]
  std::string reason;  // otherwise: why, one line
  std::string bytes;   // kOk: the content
  std::filesystem::path path;  // kOk: where the bytes were read (the source, or the epoch's copy)
};

struct ContentSet {
  std::vector<ContentEntry> entries;  // ascending particle index, at most one per particle
  std::size_t unknown = 0;            // side-file entries naming no particle of the snapshot
};

// Largest content file copied into an epoch (R1-EPO-032).
inline constexpr std::uint64_t kMaxContentBytes = 64ull << 20;

const char* content_status_name(ContentStatus s);
const char* content_kind_name(ContentKind k);

// R1-EPO-030..033: reads the side file at `side` and the files it names. A particle is found by
// name (its id is Hemera(name bytes), R1-IN) and then by 64-hex id among `ids`. Syntax errors and
// a second entry for one particle are input errors naming file:line; content that is absent,
// unreadable or outside the side file's folder is recorded as such, never an error.
Result<ContentSet> read_content_side_file(const std::filesystem::path& side, std::span<const ParticleId> ids);

// R1-EPO-031: the epoch's files for `c`: content.tsv and content/K[.ext] for every readable entry.
std::vector<std::pair<std::string, std::string>> content_epoch_files(const ContentSet& c);

// R1-EPO-034: the content of the epoch at `dir` with `n` particles (an empty set when it has no
// content.tsv); every row and copy checked against the index (size and Hemera digest). Call after
// read_epoch, which checked both against the manifest.
Result<ContentSet> read_epoch_content(const std::filesystem::path& dir, std::size_t n);

// The one-line summary `r1 epoch` prints ("3 particles: 1 image, 1 text, 1 other; 0 missing, ...").
std::string content_summary(const ContentSet& c);

}  // namespace r1::render
