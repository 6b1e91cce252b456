// The anchor file's bytes: 16-byte header, 56 bytes per entry, digest (R1-FRM-020..023, R1-FMT-020).
#include <algorithm>
#include <cstring>
#include <vector>

#include "r1/format/anchor.hpp"
#include "r1/format/bytes.hpp"

namespace r1 {

namespace {

constexpr char kMagic[8] = {'R', '1', 'A', 'N', 'C', 'H', 'O', 'R'};

bool coord_in_range(fx::Q32 x) { return x.raw >= -kAnchorCoordMax && x.raw <= kAnchorCoordMax; }

// Entry indices sorted by id, then by position, so a duplicate is reported at its second place.
std::vector<std::uint32_t> by_id(const Anchor& a) {
  std::vector<std::uint32_t> order(a.entries.size());
  for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::uint32_t x, std::uint32_t y) {
    if (a.entries[x].id != a.entries[y].id) return a.entries[x].id < a.entries[y].id;
    return x < y;
  });
  return order;
}

// The first entry (in file order) whose id appeared earlier, or -1.
std::int64_t first_duplicate(const Anchor& a) {
  const auto order = by_id(a);
  std::int64_t dup = -1;
  for (std::size_t k = 1; k < order.size(); ++k)
    if (a.entries[order[k]].id == a.entries[order[k - 1]].id && (dup < 0 || order[k] < dup)) dup = order[k];
  return dup;
}

}  // namespace

Result<std::string> anchor_bytes(const Anchor& anchor) {
  const std::size_t count = anchor.entries.size();
  if (count == 0 || count > kAnchorMax)
    return Status::input("anchor: " + std::to_string(count) + " entries (the format holds 1 to 1024)");
  if (const auto d = first_duplicate(anchor); d >= 0)
    return Status::input("anchor: entry " + std::to_string(d) + " repeats a particle id");
  std::string out;
  out.reserve(kAnchorHeaderBytes + kAnchorEntryBytes * count);
  out.append(kMagic, sizeof kMagic);
  format::put_u32(out, kAnchorVersion);
  format::put_u32(out, static_cast<std::uint32_t>(count));
  for (std::size_t i = 0; i < count; ++i) {
    const auto& e = anchor.entries[i];
    format::put_bytes(out, e.id);
    for (const fx::Q32 x : e.position) {
      if (!coord_in_range(x))
        return Status::input("anchor: entry " + std::to_string(i) + " has a coordinate beyond 2^20 scene units");
      format::put_i64(out, x.raw);
    }
  }
  return out;
}

Result<Anchor> parse_anchor(std::span<const std::uint8_t> bytes, const std::string& name) {
  auto at = [&](std::size_t offset, const std::string& why) {
    return Status::input(name + ": byte " + std::to_string(offset) + ": " + why);
  };
  if (bytes.size() < kAnchorHeaderBytes)
    return at(bytes.size(), "truncated anchor header (" + std::to_string(bytes.size()) + " of 16 bytes)");
  if (std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0) return at(0, "not an r1 anchor file (magic is not R1ANCHOR)");
  const std::uint32_t version = format::load_u32(bytes.data() + 8);
  if (version != kAnchorVersion) return at(8, "unsupported anchor version " + std::to_string(version) + " (r1 reads 1)");
  const std::uint32_t count = format::load_u32(bytes.data() + 12);
  if (count == 0 || count > kAnchorMax)
    return at(12, "anchor count " + std::to_string(count) + " is outside 1..1024");
  const std::size_t want = kAnchorHeaderBytes + kAnchorEntryBytes * count;
  if (bytes.size() < want) {
    const std::size_t entry = (bytes.size() - kAnchorHeaderBytes) / kAnchorEntryBytes;
    return at(bytes.size(), "truncated: entry " + std::to_string(entry) + " of " + std::to_string(count) + " is incomplete");
  }
  if (bytes.size() > want) return at(want, std::to_string(bytes.size() - want) + " trailing bytes after the last entry");

  Anchor a;
  a.entries.resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t base = kAnchorHeaderBytes + kAnchorEntryBytes * i;
    std::memcpy(a.entries[i].id.data(), bytes.data() + base, 32);
    for (std::size_t c = 0; c < 3; ++c) {
      const std::size_t off = base + 32 + 8 * c;
      const fx::Q32 x = fx::Q32::from_raw(format::load_i64(bytes.data() + off));
      if (!coord_in_range(x)) return at(off, "anchor coordinate beyond 2^20 scene units");
      a.entries[i].position[c] = x;
    }
  }
  if (const auto d = first_duplicate(a); d >= 0)
    return at(kAnchorHeaderBytes + kAnchorEntryBytes * static_cast<std::size_t>(d),
              "entry " + std::to_string(d) + " repeats particle id " + hemera::to_hex(a.entries[static_cast<std::size_t>(d)].id));
  return a;
}

Result<hemera::Digest> anchor_digest(const Anchor& anchor) {
  R1_ASSIGN(const std::string bytes, anchor_bytes(anchor));
  return hemera::root_hash(std::span(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()));
}

}  // namespace r1
