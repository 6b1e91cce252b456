// .graph v1 reader: container, config, records, extension sections (R1-IN-002..007, R1-IN-020..023).
#include <algorithm>
#include <cstring>
#include <unordered_map>

#include "readers.hpp"
#include "r1/reference/snapshot_builder.hpp"
#include "toml_subset.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

namespace r1::detail {

namespace {

std::size_t line_at(std::string_view b, std::size_t offset) {
  return 1 + static_cast<std::size_t>(std::count(b.begin(), b.begin() + static_cast<std::ptrdiff_t>(offset), '\n'));
}

Status read_config(std::string_view text, const std::string& file, std::size_t first_line, SnapshotConfig& c) {
  R1_ASSIGN(toml::table t, toml_subset::parse(text, file, first_line));
  const std::string where = file + ": config: ";
  const auto chain = t["chain_id"].value<std::string>();
  if (!chain) return Status::input(where + "needs a string chain_id");
  c.chain_id = *chain;
  const auto block = t["block"].value<std::int64_t>();
  if (!block || *block < 1) return Status::input(where + "needs an integer block >= 1");
  c.block = static_cast<std::uint64_t>(*block);
  const auto captured = t["captured_at"].value<std::int64_t>();
  if (!captured) return Status::input(where + "needs an integer captured_at");
  c.captured_at = *captured;
  const auto version = t["format_version"].value<std::int64_t>();
  if (!version) return Status::input(where + "needs format_version = 1");
  if (*version != 1)
    return Status::input(where + "format_version " + std::to_string(*version) + " is not supported (r1 reads version 1)");
  c.format_version = *version;
  const toml::table* tokens = t["tokens"].as_table();
  if (tokens == nullptr || tokens->empty()) return Status::input(where + "needs a [tokens] table with at least one token");
  for (const auto& [key, node] : *tokens) {
    const std::string k(key.str());
    std::uint64_t index = 0;
    if (k.empty() || k.size() > 10 || !std::all_of(k.begin(), k.end(), [](char ch) { return ch >= '0' && ch <= '9'; }) ||
        (index = std::stoull(k)) > 0xFFFFFFFFull)
      return Status::input(where + "token key '" + k + "' is not an index 0..4294967295");
    const toml::table* tok = node.as_table();
    if (tok == nullptr) return Status::input(where + "token " + k + " must be { symbol = \"...\", weight = N }");
    const auto symbol = (*tok)["symbol"].value<std::string>();
    const auto weight = (*tok)["weight"].value<std::int64_t>();
    if (!symbol || !weight) return Status::input(where + "token " + k + " needs a string symbol and an integer weight");
    if (*weight < 0) return Status::input(where + "token " + k + " has a negative weight");
    c.tokens[static_cast<std::uint32_t>(index)] = Token{*symbol, static_cast<std::uint64_t>(*weight)};
  }
  return Status::ok();
}

template <class T>
T get_le(const std::uint8_t* p, std::size_t n) {
  T v = 0;
  for (std::size_t i = 0; i < n; ++i) v |= static_cast<T>(p[i]) << (8 * i);
  return v;
}

// Snapshots with at least this many records are parsed in two halves (R1-IN-021).
constexpr std::size_t kSplitRecords = std::size_t{1} << 16;

struct RangeContext {
  const std::uint8_t* base;  // the first record
  std::uint64_t offset;      // its byte offset in the file, for messages
  const std::string& file;
  const SnapshotConfig& config;
  const std::function<void(std::string_view)>& consumed;  // R1-IN-022; may be empty
};

// Decodes and checks records [first, last) into out[first, last), numbering ids with `numbering` (the
// snapshot's builder, or for the second half a builder of its own); `last_height` is the height of the record before
// `first` (0 for the first record). Returns the first bad record's error.
template <class Numbering, class Tick>
Status parse_records(const RangeContext& ctx, std::size_t first, std::size_t last, std::uint64_t last_height,
                     Numbering& numbering, Link* out, const Tick& tick) {
  // The id lookups are cache misses on large snapshots: the index slots of the record kAhead on
  // are fetched early (from the part's second record on, when its index is not empty).
  constexpr std::size_t kAhead = 16;
  // Every kRelease records the bytes parsed since are handed back (R1-IN-022).
  constexpr std::size_t kRelease = std::size_t{1} << 16;
  std::size_t released = first;
  for (std::size_t i = first; i < last; ++i) {
    if (ctx.consumed && i - released == kRelease) {
      ctx.consumed(std::string_view(reinterpret_cast<const char*>(ctx.base + released * kRecordBytes), kRelease * kRecordBytes));
      released = i;
    }
    if (i > first && i + kAhead < last) {
      ParticleId ahead;
      for (const std::size_t field : {32u, 64u}) {
        std::memcpy(ahead.data(), ctx.base + (i + kAhead) * kRecordBytes + field, 32);
        numbering.prefetch_particle(ahead);
      }
    }
    const std::uint8_t* r = ctx.base + i * kRecordBytes;
    const std::uint64_t off = ctx.offset + i * kRecordBytes;
    auto fail = [&](std::size_t field, const std::string& what) {
      return Status::input(ctx.file + ": byte " + std::to_string(off + field) + ": record " + std::to_string(i) + ": " + what);
    };
    Link l;
    l.token = get_le<std::uint32_t>(r + 96, 4);
    l.amount = get_le<u128>(r + 100, 16);
    l.valence = static_cast<std::int8_t>(r[116]);
    l.height = get_le<std::uint64_t>(r + 117, 8);
    if (l.valence < -1 || l.valence > 1) return fail(116, "valence " + std::to_string(l.valence) + " is not -1, 0 or +1");
    if (r[125] != 0 || r[126] != 0 || r[127] != 0) return fail(125, "padding bytes are not zero");
    if (ctx.config.tokens.find(l.token) == ctx.config.tokens.end())
      return fail(96, "token " + std::to_string(l.token) + " is not in the config's [tokens] table");
    if (l.height < 1 || l.height > ctx.config.block)
      return fail(117, "block height " + std::to_string(l.height) + " is outside [1, " + std::to_string(ctx.config.block) + "]");
    if (l.height < last_height)
      return fail(117, "block height " + std::to_string(l.height) + " after " + std::to_string(last_height) +
                           ": records must be in chain order");
    last_height = l.height;
    NeuronId nu;
    ParticleId from, to;
    std::copy(r, r + 32, nu.begin());
    std::copy(r + 32, r + 64, from.begin());
    std::copy(r + 64, r + 96, to.begin());
    l.neuron = numbering.neuron_by_id(nu);
    l.from = numbering.particle_by_id(from);  // source before target: decision 2
    l.to = numbering.particle_by_id(to);
    out[i] = l;
    tick(i);
  }
  if (ctx.consumed && last > released)
    ctx.consumed(std::string_view(reinterpret_cast<const char*>(ctx.base + released * kRecordBytes), (last - released) * kRecordBytes));
  return Status::ok();
}

}  // namespace

Result<Snapshot> read_graph_file(std::string_view bytes, const std::string& file, const ProgressFn& progress,
                                 const std::function<void(std::string_view)>& consumed) {
  R1_ASSIGN(Container c, parse_container(bytes, file));
  for (const char* required : {"card", "config", "cyberlinks"})
    if (c.find(required) == nullptr) return Status::input(file + ": required section '" + required + "' is missing");

  SnapshotBuilder b(file);
  Snapshot& s = b.snapshot();
  const ContainerSection* card = c.find("card");
  if (card->binary) return Status::input(file + ": section 'card' must be text");
  s.card = std::string(card->body);
  const ContainerSection* config = c.find("config");
  if (config->binary) return Status::input(file + ": section 'config' must be text");
  R1_TRY(read_config(config->body, file, line_at(bytes, config->offset), s.config));

  const ContainerSection* links = c.find("cyberlinks");
  if (!links->binary) return Status::input(file + ": section 'cyberlinks' must be binary (give its size in [[files]])");
  for (const auto& f : c.files)
    if (f.name == "cyberlinks" && f.format != "records")
      return Status::input(file + ": section 'cyberlinks' has format '" + f.format + "', expected 'records'");
  if (links->body.size() % kRecordBytes != 0)
    return Status::input(file + ": byte " + std::to_string(links->offset) + ": cyberlinks size " +
                         std::to_string(links->body.size()) + " is not a multiple of 128");
  const std::size_t n = links->body.size() / kRecordBytes;
  const auto* base = reinterpret_cast<const std::uint8_t*>(links->body.data());
  // Two halves of the records on two threads (R1-IN-021): the first numbers into the builder as a
  // serial parse would; the second into tables of its own, which are then numbered in their order
  // of first appearance after the first half's: the serial numbering exactly. Small snapshots stay
  // on one thread.
  const std::size_t half = n >= kSplitRecords ? n / 2 : n;
  Status first_status = Status::ok(), second_status = Status::ok();
  const RangeContext ctx{base, links->offset, file, s.config, consumed};
  // Sized first (the pages touched here, not by the parse), so both halves write in place.
  s.links.resize(n);
  const auto parse_first = [&] {
    first_status = parse_records(ctx, 0, half, 0, b, s.links.data(), [&](std::size_t i) {
      if ((i & 0xFFFF) == 0) report(progress, "reading records", half < n ? 2 * i : i, n);
    });
  };
  if (half == n) {
    parse_first();
  } else {
    // The second half's order check starts from the height of the record before it.
    const std::uint64_t before = get_le<std::uint64_t>(base + (half - 1) * kRecordBytes + 117, 8);
    SnapshotBuilder second(file);  // its own first-appearance tables
    tbb::parallel_invoke(parse_first,
                         [&] { second_status = parse_records(ctx, half, n, before, second, s.links.data(), [](std::size_t) {}); });
    R1_TRY(first_status);
    R1_TRY(second_status);
    // The second half's particles and neurons in its order of first appearance, numbered after the
    // first half's (those it already holds keep their numbers), then its links renumbered.
    const std::vector<ParticleId>& local_particles = second.snapshot().particles;
    const std::vector<NeuronId>& local_neurons = second.snapshot().neurons;
    std::vector<std::uint32_t> particle(local_particles.size()), neuron(local_neurons.size());
    for (std::size_t j = 0; j < local_neurons.size(); ++j) neuron[j] = b.neuron_by_id(local_neurons[j]);
    for (std::size_t j = 0; j < local_particles.size(); ++j) {
      if (j + 16 < local_particles.size()) b.prefetch_particle(local_particles[j + 16]);
      particle[j] = b.particle_by_id(local_particles[j]);
    }
    tbb::parallel_for(tbb::blocked_range<std::size_t>(half, n, std::size_t{1} << 16), [&](const auto& r) {
      for (std::size_t i = r.begin(); i < r.end(); ++i) {
        Link& l = s.links[i];
        l.neuron = neuron[l.neuron];
        l.from = particle[l.from];
        l.to = particle[l.to];
      }
    });
  }
  R1_TRY(first_status);
  for (const auto& sec : c.sections) {
    if (sec.name != "titles" && sec.name != "crystal") continue;
    if (sec.binary) return Status::input(file + ": section '" + sec.name + "' must be text");
    R1_TRY(apply_side_text(s, sec.body, file, sec.name == "titles" ? SideKind::kTitles : SideKind::kCrystal, true,
                           line_at(bytes, sec.offset), nullptr));
  }
  return b.finish(progress);
}

}  // namespace r1::detail
