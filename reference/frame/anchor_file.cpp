// The anchor file: the first min(1024, |P|) particles with their positions, read and written
// (R1-FRM-020..023); the bytes are the format library's (r1/format/anchor.hpp).
#include <utility>

#include "r1/reference/atomic_file.hpp"
#include "r1/reference/frame.hpp"
#include "r1/reference/input_file.hpp"

namespace r1 {

Anchor make_anchor(const Snapshot& snapshot, const Frame& frame) {
  Anchor a;
  const std::size_t count = anchor_count(snapshot.particles.size());
  a.entries.resize(count);
  for (std::size_t i = 0; i < count; ++i) a.entries[i] = {snapshot.particles[i], frame.position[i]};
  return a;
}

Result<Anchor> read_anchor(const std::string& path) {
  R1_ASSIGN(auto file, InputFile::open(path));
  return parse_anchor(file->bytes(), file->name());
}

Status load_anchor(EpochOptions& options, const std::string& path) {
  if (path.empty()) return Status::ok();
  R1_ASSIGN(Anchor anchor, read_anchor(path));
  options.anchor = std::move(anchor);
  options.anchor_name = path;
  return Status::ok();
}

Result<hemera::Digest> write_anchor(const Anchor& anchor, const std::string& path) {
  R1_ASSIGN(const std::string bytes, anchor_bytes(anchor));
  R1_TRY(write_file_atomic(path, bytes));
  return hemera::root_hash(std::span(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()));
}

}  // namespace r1
