// The epoch directory: canonical arrays (the format library's codecs), manifest, atomic write,
// validated read, TSV export (R1-EPO-010..020, R1-FMT-010).
#include "r1/reference/epoch_io.hpp"
#include "r1/reference/atomic_file.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <fstream>
#include <future>
#include <map>
#include <memory>
#include <optional>

#include <functional>
#include <tbb/parallel_for.h>

#include "../snapshot/text_util.hpp"
#include "file_chunks.hpp"
#include "r1/format/arrays.hpp"
#include "r1/reference/atomic_dir.hpp"
#include "r1/reference/frame.hpp"
#include "r1/reference/hierarchy.hpp"
#include "r1/reference/input_file.hpp"
#include "r1/solvers/focus.hpp"

namespace r1 {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr const char* kFormat = "r1-epoch";
constexpr int kVersion = 6;  // 2: edges.bin; hierarchy.bin read back and checked; 3: outrows.u64, betweenness.f64;
                             // 4: image.i128 with residual_sums, heat.q32; 5: records.chunks; 6: files.chunks
constexpr int kOldestVersion = 4;  // read as well: version 4 has no records.chunks, 4 and 5 no files.chunks
constexpr const char* kChunkTable = "files.chunks";  // R1-EPO-018
constexpr std::size_t kChunkRowBytes = 64;  // records.chunks: SHA-256, then the Hemera leaf

// The chunks of a snapshot's record stream of `links` records (R1-IN-040, records.chunks).
std::size_t record_chunk_count(std::uint64_t links) {
  return static_cast<std::size_t>(hemera::leaf_count(links * kRecordBytes));
}

// records.chunks' rows: per chunk its SHA-256, then its leaf.
RecordChunks record_chunks_of(std::string_view b, std::size_t chunks) {
  RecordChunks out;
  out.sha = format::read_bytes32_column(b, chunks, 2, 0);
  out.leaves = format::read_bytes32_column(b, chunks, 2, 1);
  return out;
}

using format::kEdgeBytes;
using format::q32_column;

std::string hex(const hemera::Digest& d) { return hemera::to_hex(d); }

std::span<const std::uint8_t> as_bytes(std::string_view s) {
  return {reinterpret_cast<const std::uint8_t*>(s.data()), s.size()};
}

std::string file_digest(std::string_view bytes) { return hex(hemera::root_hash(as_bytes(bytes))); }

// The chunks of the epoch file `name`, their SHA-256s and leaves (R1-EPO-016, R1-EPO-018): against
// the epoch before, when it lists the file, only the chunks that differ from it are hashed with
// Hemera; which differ is told by its chunk table's SHA-256s where PREV was read with them, else
// by comparing with its file as it is on disk then (when it still opens). The leaves are
// tree_leaves(bytes) either way.
epoch_chunks::FileChunks file_chunks(const std::string& name, std::string_view bytes, const EpochLeaves* previous) {
  if (previous != nullptr) {
    const auto it = previous->leaves.find(name);
    if (it != previous->leaves.end()) {
      const auto sha = previous->sha.find(name);
      if (sha != previous->sha.end()) return epoch_chunks::chunk_file(as_bytes(bytes), sha->second, it->second);
      auto file = InputFile::open((previous->dir / name).string());
      if (file.is_ok())
        return {epoch_chunks::chunk_sha(as_bytes(bytes)),
                hemera::tree_leaves_reusing(as_bytes(bytes), (*file)->bytes(), it->second)};
    }
  }
  return epoch_chunks::chunk_file(as_bytes(bytes));
}

const char* role_name(Role r) {
  switch (r) {
    case Role::kHub: return "hub";
    case Role::kBridge: return "bridge";
    case Role::kLeaf: return "leaf";
    case Role::kNone: break;
  }
  return "none";
}

const char* domain_name(NumericDomain d) { return d == NumericDomain::kQ32 ? "q32" : "fp64"; }

// Q32 parameters as their exact decimal strings: a JSON number would pass through a double.
json q32_json(Q32 q) { return q.to_exact_string(); }

// JSON has no infinity: an unbounded certificate is written as null (R1-INC-040).
json bound_json(double x) { return std::isfinite(x) ? json(x) : json(nullptr); }
double bound_from(const json& j) { return j.is_null() ? std::numeric_limits<double>::infinity() : j.get<double>(); }

// The carried residual sums (R1-INC-038): each exact integer as its three 64-bit two's complement
// limbs, most significant first, 48 hex digits.
// An exact sum as 48 lower-case hex digits of its 192-bit two's complement, most significant first.
std::string exact_hex(const fx::ExactSum& x) {
  const auto l = x.limbs();
  char b[49];
  std::snprintf(b, sizeof b, "%016llx%016llx%016llx", static_cast<unsigned long long>(l[2]),
                static_cast<unsigned long long>(l[1]), static_cast<unsigned long long>(l[0]));
  return b;
}

std::optional<fx::ExactSum> exact_from_hex(const json& j) {
  const std::string h = j.is_string() ? j.get<std::string>() : "";
  if (h.size() != 48) return std::nullopt;
  std::array<std::uint64_t, 3> l{};
  for (std::size_t d = 0; d < 48; ++d) {
    const char ch = h[d];
    const int v = ch >= '0' && ch <= '9' ? ch - '0' : ch >= 'a' && ch <= 'f' ? ch - 'a' + 10 : -1;
    if (v < 0) return std::nullopt;
    l[2 - d / 16] = (l[2 - d / 16] << 4) | static_cast<std::uint64_t>(v);
  }
  return fx::ExactSum::from_limbs(l);
}

json sums_json(const Spectrum<Q32>& s) {
  json vectors = json::array();
  for (const auto& v : s.sums) {
    json three = json::array();
    for (const fx::ExactSum& x : v) three.push_back(exact_hex(x));
    vectors.push_back(three);
  }
  return {{"shift", s.sums_shift}, {"sums", vectors}};
}

Status sums_from(const json& j, Spectrum<Q32>& s, const std::string& manifest) {
  const json& vectors = j.at("sums");
  const int shift = j.at("shift").get<int>();
  if (shift < 0 || shift > 16 || !vectors.is_array() || vectors.size() != 5)
    return Status::input(manifest + ": residual_sums: a shift of 0..16 and five vectors expected");
  for (std::size_t c = 0; c < 5; ++c) {
    if (!vectors[c].is_array() || vectors[c].size() != 3) return Status::input(manifest + ": residual_sums: three sums per vector expected");
    for (std::size_t k = 0; k < 3; ++k) {
      const auto x = exact_from_hex(vectors[c][k]);
      if (!x) return Status::input(manifest + ": residual_sums: vector " + std::to_string(c + 2) + ": not 48 lower-case hex digits");
      s.sums[c][k] = *x;
    }
    // Sums of squares are never negative.
    if (s.sums[c][0].signum() < 0 || s.sums[c][2].signum() < 0)
      return Status::input(manifest + ": residual_sums: vector " + std::to_string(c + 2) + ": a negative sum of squares");
  }
  s.sums_shift = shift;
  return Status::ok();
}

json update_json(const UpdateInfo& u) {
  json vb = json::array();
  for (double x : u.vector_bound) vb.push_back(bound_json(x));
  return {{"mode", u.incremental ? "incremental" : "full"},
          {"reason", u.reason},
          {"epochs_since_full", u.epochs_since_full},
          {"hops", u.hops},
          {"touched", u.touched},
          {"added", u.added},
          {"dropped", u.dropped},
          {"resized_since_full", u.resized_since_full},
          {"region", u.region},
          {"rows", u.rows},
          {"focus", u.focus_local ? "local" : "full"},
          {"certified", u.certified},
          {"betweenness", u.betweenness_carried ? "carried" : "computed"},
          {"hierarchy_radius", u.hierarchy_radius_kept ? "kept" : "searched"},
          {"radius_scale", u.radius_scale_kept ? "kept" : "measured"},
          {"delta_norm", u.delta_norm},
          {"delta_norm_since_full", u.delta_norm_since_full},
          {"full_eigenvalues", u.full_eigenvalues},
          {"full_residuals", u.full_residuals},
          {"vector_bound", vb},
          {"certificate", bound_json(u.certificate)},
          {"eps_x", u.eps_x}};
}

UpdateInfo update_from(const json& j) {
  UpdateInfo u;
  u.incremental = j.at("mode").get<std::string>() == "incremental";
  u.reason = j.at("reason").get<std::string>();
  u.epochs_since_full = j.at("epochs_since_full").get<std::uint32_t>();
  u.hops = j.at("hops").get<std::uint32_t>();
  u.touched = j.at("touched").get<std::uint64_t>();
  u.added = j.at("added").get<std::uint64_t>();
  u.dropped = j.at("dropped").get<std::uint64_t>();
  u.resized_since_full = j.at("resized_since_full").get<std::uint64_t>();
  u.region = j.at("region").get<std::uint64_t>();
  u.rows = j.at("rows").get<std::uint64_t>();
  u.focus_local = j.at("focus").get<std::string>() == "local";
  u.certified = j.at("certified").get<bool>();
  u.betweenness_carried = j.at("betweenness").get<std::string>() == "carried";
  // Absent in epochs made before R1-INC-035 kept the radius: they searched it.
  u.hierarchy_radius_kept = j.value("hierarchy_radius", std::string("searched")) == "kept";
  u.radius_scale_kept = j.value("radius_scale", std::string("measured")) == "kept";
  u.delta_norm = j.at("delta_norm").get<double>();
  u.delta_norm_since_full = j.at("delta_norm_since_full").get<double>();
  u.full_eigenvalues = j.at("full_eigenvalues").get<std::array<double, 6>>();
  u.full_residuals = j.at("full_residuals").get<std::array<double, 6>>();
  const json& vb = j.at("vector_bound");
  if (!vb.is_array() || vb.size() != 5) throw json::type_error::create(302, "vector_bound is not 5 numbers", &vb);
  for (std::size_t k = 0; k < 5; ++k) u.vector_bound[k] = bound_from(vb[k]);
  u.certificate = bound_from(j.at("certificate"));
  u.eps_x = j.at("eps_x").get<double>();
  return u;
}

Q32 q32_from(const json& j, const char* what, const std::string& manifest) {
  const auto q = Q32::checked_from_decimal(j.at(what).get<std::string>());
  if (!q) throw json::type_error::create(302, manifest + ": parameter " + what + " is not a Q32 decimal", &j);
  return *q;
}

bool is_epoch_dir(const fs::path& dir) { return manifest_format_is(dir, kFormat); }

}  // namespace

Result<std::vector<std::pair<std::string, std::string>>> epoch_files(const Epoch& e) {
  const std::size_t n = e.ids.size();
  if (e.out_rows.size() != n)
    return Status::internal("epoch: " + std::to_string(e.out_rows.size()) + " out-row digests for " + std::to_string(n) + " particles");
  if (!e.focus.heat.empty() && e.focus.heat.size() != n)
    return Status::internal("epoch: " + std::to_string(e.focus.heat.size()) + " heat values for " + std::to_string(n) + " particles");
  if (!e.encoding.betweenness.empty() && e.encoding.betweenness.size() != n)
    return Status::internal("epoch: " + std::to_string(e.encoding.betweenness.size()) + " betweenness values for " + std::to_string(n) +
                            " particles");
  if (e.spectrum.sums_shift >= 0 && e.spectrum.image.size() != n * 5)
    return Status::internal("epoch: " + std::to_string(e.spectrum.image.size()) + " image numerators for " + std::to_string(n) +
                            " particles");
  const std::size_t chunks = record_chunk_count(e.links);
  if (!e.record_chunks.leaves.empty() && (e.record_chunks.leaves.size() != chunks || e.record_chunks.sha.size() != chunks))
    return Status::internal("epoch: " + std::to_string(e.record_chunks.leaves.size()) + " record chunks for " +
                            std::to_string(e.links) + " links");
  // The anchor: the first min(1024, n) particles with their positions (R1-FRM, decision 7).
  Anchor anchor;
  for (std::size_t i = 0; i < anchor_count(n); ++i) anchor.entries.push_back({e.ids[i], e.frame.position[i]});
  R1_ASSIGN(std::string anchor_file, anchor_bytes(anchor));

  // Each file's bytes by a job of its own, the jobs on the TBB workers (hundreds of megabytes at
  // 10^6 particles; the files come out in this order whatever runs when).
  std::vector<std::pair<std::string, std::function<std::string()>>> jobs;
  jobs.emplace_back("particles.ids", [&] {
    const std::span<const format::Bytes32> ids[] = {e.ids};
    return format::bytes32_rows(ids, n);
  });
  jobs.emplace_back("titles.tsv", [&] {
    std::string t;
    for (std::size_t i = 0; i < n && i < e.titles.size(); ++i)
      if (!e.titles[i].empty()) t += hex(e.ids[i]) + "\t" + text::escape_cell(e.titles[i]) + "\n";
    return t;
  });
  jobs.emplace_back("focus.q32", [&] { return q32_column(e.focus.phi); });
  // R1-INC-052: what the next epoch's focus update starts from.
  if (!e.focus.heat.empty()) jobs.emplace_back("heat.q32", [&] { return q32_column(e.focus.heat); });
  jobs.emplace_back("spectral.q32", [&] { return format::q32_rows(e.spectrum.u, n); });
  jobs.emplace_back("positions.q32", [&] { return format::q32_triples(e.frame.position); });
  jobs.emplace_back("radius.q32", [&] { return q32_column(e.encoding.radius); });
  jobs.emplace_back("luminosity.q32", [&] { return q32_column(e.encoding.luminosity); });
  jobs.emplace_back("hue.q32", [&] { return q32_column(e.encoding.hue); });
  jobs.emplace_back("saturation.q32", [&] { return q32_column(e.encoding.saturation); });
  jobs.emplace_back("role.u8", [&] {
    std::string r;
    for (Role x : e.encoding.role) r.push_back(static_cast<char>(x));
    return r;
  });
  jobs.emplace_back("shape.u8", [&] {
    std::string s;
    for (Shape x : e.encoding.shape) s.push_back(static_cast<char>(x));
    return s;
  });
  jobs.emplace_back("color.rgb8", [&] {
    std::string c;
    for (const auto& rgb : e.encoding.color) c.append(reinterpret_cast<const char*>(rgb.data()), 3);
    return c;
  });
  jobs.emplace_back("clusters.u32", [&] { return format::u32_rows(e.hierarchy.cluster_of, n); });
  jobs.emplace_back("hierarchy.bin", [&] { return hierarchy_bytes(e.hierarchy); });
  jobs.emplace_back("edges.bin", [&] { return format::edge_rows(e.edges); });
  jobs.emplace_back("outrows.u64", [&] { return format::u64_column(e.out_rows); });
  if (!e.encoding.betweenness.empty()) jobs.emplace_back("betweenness.f64", [&] { return format::f64_column(e.encoding.betweenness); });
  // What an incremental epoch carries (R1-INC-038): the exact image numerators, five per particle.
  if (e.spectrum.sums_shift >= 0) jobs.emplace_back("image.i128", [&] { return format::i128_column(e.spectrum.image); });
  // The record stream's chunks (R1-EPO-017): SHA-256 then leaf, per chunk.
  if (!e.record_chunks.leaves.empty())
    jobs.emplace_back("records.chunks", [&] {
      const std::span<const format::Bytes32> columns[] = {e.record_chunks.sha, e.record_chunks.leaves};
      return format::bytes32_rows(columns, chunks);
    });
  std::vector<std::pair<std::string, std::string>> f(jobs.size());
  tbb::parallel_for(std::size_t{0}, jobs.size(), [&](std::size_t i) { f[i] = {jobs[i].first, jobs[i].second()}; });
  f.emplace_back("anchor.bin", std::move(anchor_file));
  return f;
}

namespace {

// The manifest of an epoch whose files (the chunk table last) have `digests` (R1-EPO-012).
std::string epoch_manifest(const Epoch& e, const std::vector<std::pair<std::string, std::string>>& files,
                           const std::vector<std::string>& digests, const EpochWriteOptions& o) {
  json m;
  m["format"] = kFormat;
  m["version"] = kVersion;
  m["snapshot"] = {{"source", e.source},
                   {"digest", hex(e.snapshot_digest)},
                   {"particles", e.ids.size()},
                   {"links", e.links},
                   {"layout_edges", e.edges.size()},
                   {"components", e.components}};
  m["domain"] = domain_name(e.domain);
  const TriKernelParams& t = e.trikernel;
  m["parameters"] = {{"lambda_d", q32_json(t.lambda_d)},
                     {"lambda_s", q32_json(t.lambda_s)},
                     {"lambda_h", q32_json(t.lambda_h)},
                     {"teleport", q32_json(t.teleport)},
                     {"mu", q32_json(t.mu)},
                     {"tau", q32_json(t.tau)},
                     {"eps", q32_json(t.eps)},
                     {"max_steps", t.max_steps},
                     {"chebyshev_degree", t.chebyshev_degree},
                     {"rho", e.spectral_params.rho ? json(*e.spectral_params.rho) : json("auto")},
                     {"basis", e.spectral_params.basis},
                     {"filter_degree", e.spectral_params.filter_degree},
                     {"tolerance", e.spectral_params.tolerance},
                     {"overlay", e.encoding.overlay},
                     {"radius_scale", e.encoding.radius_scale},
                     {"r0_squared", Q32::from_raw(e.encoding.r0_squared_raw).to_string()},
                     {"r0_squared_raw", e.encoding.r0_squared_raw}};
  m["eigenvalues"] = e.spectrum.eigenvalues;
  m["residuals"] = e.spectrum.residuals;
  m["found"] = e.spectrum.found;
  m["rho"] = e.spectrum.rho;
  m["spectral_work"] = {{"restarts", e.spectrum.restarts}, {"matvecs", e.spectrum.matvecs},
                         {"block_applications", e.spectrum.passes}};
  if (e.spectrum.sums_shift >= 0) m["residual_sums"] = sums_json(e.spectrum);
  m["scale"] = e.frame.scale;
  const Alignment& a = e.frame.alignment;
  m["alignment"] = {{"genesis", a.genesis},         {"rotation", a.rotation},   {"scale", a.scale},
                    {"translation", a.translation}, {"reflected", a.reflected}, {"matched", a.matched},
                    {"rms", a.rms}};
  json top = json::array();
  for (std::size_t k = 0; k < e.focus.cyberank.size() && k < 10; ++k) {
    const std::uint32_t i = e.focus.cyberank[k];
    top.push_back({{"particle", hex(e.ids[i])},
                   {"title", i < e.titles.size() ? e.titles[i] : ""},
                   {"focus", e.focus.phi[i].to_string()}});
  }
  m["focus"] = {{"steps", e.focus.steps},
                {"kappa", e.focus.kappa},
                {"lambda_max", e.focus.lambda_max},
                {"syntropy", e.focus.syntropy},
                {"top", top}};
  // The exact sum behind the syntropy, which the next incremental epoch updates (R1-INC-054).
  if (e.focus.plogp) m["focus"]["plogp"] = exact_hex(*e.focus.plogp);
  json counts = json::array(), radii = json::array();
  for (std::size_t l = 0; l < kLevels; ++l) {
    counts.push_back(e.hierarchy.levels[l].size());
    radii.push_back(Q32::from_raw(e.hierarchy.radius_raw[l]).to_string());
  }
  m["hierarchy"] = {{"tau0", e.hierarchy.tau0}, {"radii", radii}, {"clusters_per_level", counts}};
  json fj = json::object();
  for (std::size_t k = 0; k < files.size(); ++k) {
    const std::string& name = files[k].first;
    fj[name] = {{"bytes", files[k].second.size()}, {"hemera", digests[k]}};
    if (name == "hierarchy.bin") m["topology_digest"] = digests[k];
    if (name == "anchor.bin") m["anchor_digest"] = digests[k];
  }
  m["files"] = fj;
  // The files the chunk table covers, in the order of its rows (R1-EPO-018).
  json chunked = json::array();
  for (const auto& [name, bytes] : files)
    if (name != kChunkTable) chunked.push_back({{"file", name}, {"bytes", bytes.size()}});
  m["chunked"] = chunked;
  if (e.update) m["update"] = update_json(*e.update);
  if (o.timings) {
    json tj = json::object();
    for (const auto& st : e.timings) tj[st.stage] = st.seconds;
    m["timings_s"] = tj;
  }
  return m.dump(2) + "\n";
}

// Each file's digest, and the chunk table's bytes (R1-EPO-018).
std::vector<std::string> digest_files(const std::vector<std::pair<std::string, std::string>>& files,
                                      const EpochLeaves* previous, std::string& table) {
  std::vector<std::string> digests;
  std::vector<epoch_chunks::FileChunks> chunks;
  chunks.reserve(files.size());
  for (const auto& [name, bytes] : files) {
    chunks.push_back(file_chunks(name, bytes, previous));
    digests.push_back(hex(hemera::root_of_leaves(chunks.back().leaves)));
  }
  table = epoch_chunks::table_bytes(chunks);
  return digests;
}

}  // namespace

Status write_epoch(const Epoch& e, const fs::path& dir, const EpochWriteOptions& o) {
  R1_ASSIGN(auto files, epoch_files(e));
  for (const auto& [name, bytes] : o.extra) {
    for (const auto& [have, unused] : files)
      if (have == name || name == kChunkTable) return Status::internal("epoch: extra file " + name + " is one of the stages' files");
    files.emplace_back(name, bytes);
  }
  AtomicDirectory out(dir, is_epoch_dir);
  R1_TRY(out.open());
  // The files go to disk (each flushed: mostly waiting on the device) on a thread of their own
  // while their digests are computed on the TBB workers; then the chunk table, itself digested
  // whole like any file, and the manifest.
  auto written = std::async(std::launch::async, [&out, &files]() -> Status {
    for (const auto& [name, bytes] : files) R1_TRY(out.write(name, bytes));
    return Status::ok();
  });
  std::string table;
  std::vector<std::string> digests = digest_files(files, o.previous, table);
  R1_TRY(written.get());
  R1_TRY(out.write(kChunkTable, table));
  digests.push_back(file_digest(table));
  files.emplace_back(kChunkTable, std::move(table));
  R1_TRY(out.write("manifest.json", epoch_manifest(e, files, digests, o)));
  return out.commit();
}

Status add_epoch_file(const fs::path& dir, const std::string& name, std::string_view bytes) {
  if (name.empty() || name == "manifest.json" || name.find('/') != std::string::npos || name.front() == '.')
    return Status::internal("epoch: cannot add a file named '" + name + "'");
  const fs::path manifest = dir / "manifest.json";
  R1_ASSIGN(auto mf, InputFile::open(manifest.string()));
  json m;
  try {
    m = json::parse(mf->text());
  } catch (const json::exception&) {
    return Status::input(manifest.string() + ": not JSON");
  }
  if (!m.is_object() || m.value("format", "") != kFormat || !m.contains("files") || !m.at("files").is_object())
    return Status::input(manifest.string() + ": not an r1 epoch manifest");
  if (name == kChunkTable) return Status::internal(std::string("epoch: cannot replace ") + kChunkTable);
  R1_TRY(write_file_atomic(dir / name, bytes));
  m["files"][name] = {{"bytes", bytes.size()}, {"hemera", file_digest(bytes)}};
  // A replaced file leaves the chunk table's cover; its rows stay, unnamed (R1-EPO-018).
  if (m.contains("chunked") && m.at("chunked").is_array())
    for (json& entry : m.at("chunked"))
      if (entry.is_object() && entry.value("file", json()) == name) entry["file"] = nullptr;
  return write_file_atomic(manifest, m.dump(2) + "\n");
}

namespace {

// The manifest-listed files of an epoch directory, each checked against its size and digest.
class EpochFiles {
 public:
  EpochFiles(fs::path dir, std::size_t n) : dir_(std::move(dir)), n_(n) {}

  // The files the manifest `m` lists, each checked by `check` (R1-EPO-014, R1-EPO-018); `keep`,
  // if given, receives each file's tree leaves (R1-EPO-016) and the SHA-256s the table gave.
  Status load(const json& m, EpochLeaves* keep, DigestCheck check) {
    const json& listed = m.at("files");
    if (keep) {
      keep->dir = dir_;
      keep->leaves.clear();
      keep->sha.clear();
    }
    // The chunk table first, hashed whole; then each file it covers has its rows.
    std::map<std::string, std::string_view> rows_of;
    if (check == DigestCheck::kChunkTable && listed.contains(kChunkTable) && m.contains("chunked")) {
      R1_TRY(load_one(kChunkTable, listed.at(kChunkTable), keep, {}));
      R1_ASSIGN(rows_of, table_rows(m.at("chunked"), listed, data_.at(kChunkTable)->text()));
    }
    for (const auto& [name, info] : listed.items()) {
      if (data_.count(name)) continue;
      const auto rows = rows_of.find(name);
      R1_TRY(load_one(name, info, keep, rows == rows_of.end() ? std::optional<std::string_view>() : rows->second));
    }
    return Status::ok();
  }

  // The bytes of `name`, which must hold n rows of `per_row` bytes.
  Result<std::string_view> rows(const std::string& name, std::size_t per_row) const {
    auto it = data_.find(name);
    if (it == data_.end()) return Status::input((dir_ / name).string() + ": not listed in the manifest");
    if (it->second->bytes().size() != n_ * per_row)
      return Status::input((dir_ / name).string() + ": " + std::to_string(it->second->bytes().size()) + " bytes for " +
                           std::to_string(n_) + " particles (expected " + std::to_string(n_ * per_row) + ")");
    return it->second->text();
  }

  const InputFile* find(const std::string& name) const {
    auto it = data_.find(name);
    return it == data_.end() ? nullptr : it->second.get();
  }

 private:
  // One listed file: its size, then its digest, from every chunk hashed or, with `rows`, from its
  // rows of the chunk table.
  Status load_one(const std::string& name, const json& info, EpochLeaves* keep, std::optional<std::string_view> rows) {
    const fs::path p = dir_ / name;
    R1_ASSIGN(auto f, InputFile::open(p.string()));
    const auto bytes = info.at("bytes").get<std::size_t>();
    if (f->bytes().size() != bytes)
      return Status::input(p.string() + ": " + std::to_string(f->bytes().size()) + " bytes, the manifest says " +
                           std::to_string(bytes) + " (truncated or replaced?)");
    std::vector<hemera::Digest> leaves;
    if (rows) {
      hemera::Digest want{};
      if (!hemera::from_hex(info.at("hemera").get<std::string>(), want))
        return Status::input((dir_ / "manifest.json").string() + ": " + name + ": digest is not 64 hex digits");
      R1_ASSIGN(epoch_chunks::FileChunks c, epoch_chunks::check_file(f->bytes(), *rows, want, p.string()));
      leaves = std::move(c.leaves);
      if (keep) keep->sha.emplace(name, std::move(c.sha));
    } else {
      leaves = hemera::tree_leaves(f->bytes());
      if (hex(hemera::root_of_leaves(leaves)) != info.at("hemera").get<std::string>())
        return Status::input(p.string() + ": Hemera digest differs from the manifest (the file was modified)");
    }
    if (keep) keep->leaves.emplace(name, std::move(leaves));
    data_.emplace(name, std::move(f));
    return Status::ok();
  }

  // Each covered file's rows of the chunk table `table` (R1-EPO-018): the manifest's `chunked`
  // list gives the files in row order with the size each had when the table was made; an entry
  // whose file was replaced since (add_epoch_file) has no name, and its rows are skipped.
  Result<std::map<std::string, std::string_view>> table_rows(const json& chunked, const json& listed,
                                                            std::string_view table) const {
    const std::string where = (dir_ / "manifest.json").string() + ": chunked: ";
    if (!chunked.is_array()) return Status::input(where + "not a list");
    std::map<std::string, std::string_view> rows;
    std::uint64_t at = 0;
    for (const json& entry : chunked) {
      if (!entry.is_object() || !entry.contains("bytes") || !entry.at("bytes").is_number_unsigned() || !entry.contains("file") ||
          !(entry.at("file").is_string() || entry.at("file").is_null()))
        return Status::input(where + "an entry is not {file, bytes}");
      const std::uint64_t count = hemera::leaf_count(entry.at("bytes").get<std::uint64_t>());
      if (count > (table.size() - at) / epoch_chunks::kRowBytes)
        return Status::input(where + "more chunks than " + kChunkTable + " holds");
      if (entry.at("file").is_string()) {
        const std::string name = entry.at("file").get<std::string>();
        if (name == kChunkTable || !listed.contains(name) || rows.count(name))
          return Status::input(where + "'" + name.substr(0, 80) + "' is not a listed file, or twice");
        rows.emplace(name, table.substr(static_cast<std::size_t>(at), static_cast<std::size_t>(count * epoch_chunks::kRowBytes)));
      }
      at += count * epoch_chunks::kRowBytes;
    }
    if (at != table.size()) return Status::input(where + std::string(kChunkTable) + " holds more rows than its files have chunks");
    return rows;
  }

  fs::path dir_;
  std::size_t n_;
  std::map<std::string, std::unique_ptr<InputFile>> data_;
};

using format::read_q32_column;

Status read_titles(const InputFile& f, const std::string& where, Epoch& e) {
  if (f.bytes().empty()) return Status::ok();  // no titles: no index of 10^6 ids to build
  // Particle ids in byte order with their index, for the lookups below.
  std::vector<std::pair<hemera::Digest, std::size_t>> index(e.ids.size());
  for (std::size_t i = 0; i < e.ids.size(); ++i) index[i] = {e.ids[i], i};
  std::sort(index.begin(), index.end());
  text::LineReader lines(f.text());
  std::string_view line;
  while (lines.next(line)) {
    const std::string at = where + ":" + std::to_string(lines.line_number()) + ": ";
    const auto tab = line.find('\t');
    hemera::Digest id{};
    if (tab == std::string_view::npos || !hemera::from_hex(line.substr(0, tab), id))
      return Status::input(at + "expected a 64-hex id, TAB, title");
    auto title = text::unescape_cell(line.substr(tab + 1));
    const auto it = std::lower_bound(index.begin(), index.end(), std::make_pair(id, std::size_t{0}));
    if (!title || it == index.end() || it->first != id)
      return Status::input(at + "title for an unknown particle or with a bad escape");
    e.titles[it->second] = std::move(*title);
  }
  return Status::ok();
}

// edges.bin (R1-EPO-011): `count` rows of 24 bytes, strictly ascending (p, q) with p < q < n,
// 0 < w <= 1 and |a2| <= w.
Status read_edges(const EpochFiles& files, const fs::path& path, std::size_t n, std::size_t count, Epoch& e) {
  const InputFile* f = files.find("edges.bin");
  if (!f) return Status::input(path.string() + ": not listed in the manifest");
  const std::string_view b = f->text();
  if (b.size() != count * kEdgeBytes)
    return Status::input(path.string() + ": " + std::to_string(b.size()) + " bytes for " + std::to_string(count) +
                         " layout edges (expected " + std::to_string(count * kEdgeBytes) + ")");
  e.edges.resize(count);
  for (std::size_t k = 0; k < count; ++k) {
    LayoutEdge& edge = e.edges[k];
    edge = format::edge_at(b, k);
    const bool ordered = k == 0 || std::pair(e.edges[k - 1].p, e.edges[k - 1].q) < std::pair(edge.p, edge.q);
    if (edge.p >= edge.q || edge.q >= n || !ordered || edge.w_raw <= 0 || edge.w_raw > Q32::kOneRaw ||
        edge.a2_raw < -edge.w_raw || edge.a2_raw > edge.w_raw)
      return Status::input(path.string() + ": byte " + std::to_string(k * kEdgeBytes) +
                           ": layout edge out of order or out of range");
  }
  return Status::ok();
}

Result<Epoch> read_epoch_json(const fs::path& dir, const json& m, EpochLeaves* keep, DigestCheck check) {
  const std::string manifest = (dir / "manifest.json").string();
  if (m.value("format", "") != kFormat) return Status::input(manifest + ": not an r1 epoch manifest");
  const int version = m.value("version", 0);
  if (version < kOldestVersion || version > kVersion)
    return Status::input(manifest + ": epoch version " + std::to_string(version) + " is not supported (r1 reads versions " +
                         std::to_string(kOldestVersion) + " to " + std::to_string(kVersion) + "): compute it again with r1 epoch");
  Epoch e;
  const std::size_t n = m.at("snapshot").at("particles").get<std::size_t>();
  e.source = m.at("snapshot").at("source").get<std::string>();
  if (!hemera::from_hex(m.at("snapshot").at("digest").get<std::string>(), e.snapshot_digest))
    return Status::input(manifest + ": snapshot digest is not 64 hex digits");
  e.links = m.at("snapshot").at("links").get<std::uint64_t>();
  e.components = m.at("snapshot").at("components").get<std::uint64_t>();
  e.domain = m.at("domain").get<std::string>() == "fp64" ? NumericDomain::kFp64 : NumericDomain::kQ32;
  e.spectrum.eigenvalues = m.at("eigenvalues").get<std::array<double, 6>>();
  e.spectrum.residuals = m.at("residuals").get<std::array<double, 6>>();
  e.spectrum.found = m.at("found").get<std::uint32_t>();
  e.spectrum.rho = m.at("rho").get<double>();
  if (m.contains("residual_sums")) R1_TRY(sums_from(m.at("residual_sums"), e.spectrum, manifest));
  e.frame.scale = m.at("scale").get<double>();
  const json& al = m.at("alignment");
  Alignment& a = e.frame.alignment;
  a.genesis = al.at("genesis").get<bool>();
  a.rotation = al.at("rotation").get<std::array<double, 9>>();
  a.scale = al.at("scale").get<double>();
  a.translation = al.at("translation").get<std::array<double, 3>>();
  a.reflected = al.at("reflected").get<bool>();
  a.matched = al.at("matched").get<std::uint32_t>();
  a.rms = al.at("rms").get<double>();
  const json& pj = m.at("parameters");
  e.encoding.overlay = pj.at("overlay").get<std::string>();
  if (pj.contains("radius_scale")) {  // epochs written before R1-ENC-007 used r_0 = R_scene
    e.encoding.radius_scale = pj.at("radius_scale").get<std::string>();
    e.encoding.r0_squared_raw = pj.at("r0_squared_raw").get<std::int64_t>();
  }
  TriKernelParams& tk = e.trikernel;
  tk.lambda_d = q32_from(pj, "lambda_d", manifest);
  tk.lambda_s = q32_from(pj, "lambda_s", manifest);
  tk.lambda_h = q32_from(pj, "lambda_h", manifest);
  tk.teleport = q32_from(pj, "teleport", manifest);
  tk.mu = q32_from(pj, "mu", manifest);
  tk.tau = q32_from(pj, "tau", manifest);
  tk.eps = q32_from(pj, "eps", manifest);
  tk.max_steps = pj.at("max_steps").get<std::uint32_t>();
  tk.chebyshev_degree = pj.at("chebyshev_degree").get<std::uint32_t>();
  if (pj.at("rho").is_number()) e.spectral_params.rho = pj.at("rho").get<double>();
  e.spectral_params.basis = pj.at("basis").get<std::uint32_t>();
  // Epochs written before the filter (R1-SPEC-080) ran without it.
  e.spectral_params.filter_degree = pj.value("filter_degree", std::uint32_t{0});
  e.spectral_params.tolerance = pj.at("tolerance").get<double>();
  if (m.contains("update")) e.update = update_from(m.at("update"));
  if (m.at("focus").contains("plogp")) {
    e.focus.plogp = exact_from_hex(m.at("focus").at("plogp"));
    // phi ln phi is never positive for 0 < phi <= 1.
    if (!e.focus.plogp || e.focus.plogp->signum() > 0)
      return Status::input(manifest + ": focus.plogp: not 48 lower-case hex digits of a sum at most 0");
  }

  EpochFiles files(dir, n);
  R1_TRY(files.load(m, keep, check));
  R1_ASSIGN(const std::string_view ids, files.rows("particles.ids", 32));
  e.ids = format::read_bytes32_column(ids, n);
  R1_ASSIGN(const std::string_view focus, files.rows("focus.q32", 8));
  e.focus.phi = read_q32_column(focus, n);
  if (e.domain == NumericDomain::kQ32) {
    // What the focus stages leave (R1-FOC-012): raws summing to 2^32, each at least 1. An epoch
    // that holds it has its cyberank places found here (R1-FOC-070), so that an incremental epoch
    // from it updates both on its region (R1-INC-051, R1-FOC-072).
    u128 sum = 0;
    bool positive = true;
    for (const Q32 x : e.focus.phi) {
      positive = positive && x.raw >= 1;
      sum += static_cast<u128>(x.raw < 0 ? 0 : x.raw);
    }
    if (positive && sum == (u128{1} << 32)) {
      e.focus.on_simplex = true;
      e.focus.cyberank = cyberank_places(e.focus.phi);
    }
  }
  if (files.find("heat.q32")) {
    R1_ASSIGN(const std::string_view heat, files.rows("heat.q32", 8));
    e.focus.heat = read_q32_column(heat, n);
    // The heat of a distribution stays near [0, 1]: beyond 2 it was not written by r1.
    for (std::size_t i = 0; i < n; ++i)
      if (e.focus.heat[i].raw > (std::int64_t{2} << 32) || e.focus.heat[i].raw < -(std::int64_t{2} << 32))
        return Status::input((dir / "heat.q32").string() + ": byte " + std::to_string(8 * i) + ": a heat value beyond 2");
  }
  R1_ASSIGN(const std::string_view spectral, files.rows("spectral.q32", 40));
  for (std::size_t k = 0; k < 5; ++k) {
    e.spectrum.u[k] = read_q32_column(spectral, n, 5, k);
    // Unit vectors have entries of magnitude at most 1 (a little more after incremental updates):
    // beyond 2 they were not written by r1, and the carried image's bounds would not hold.
    for (std::size_t i = 0; i < n; ++i)
      if (e.spectrum.u[k][i].raw > (std::int64_t{2} << 32) || e.spectrum.u[k][i].raw < -(std::int64_t{2} << 32))
        return Status::input((dir / "spectral.q32").string() + ": byte " + std::to_string(40 * i + 8 * k) + ": u_" +
                             std::to_string(k + 2) + " has an entry beyond 2 (not a unit vector)");
  }
  R1_ASSIGN(const std::string_view pos, files.rows("positions.q32", 24));
  e.frame.position = format::read_q32_triples(pos, n);
  R1_ASSIGN(const std::string_view radius, files.rows("radius.q32", 8));
  R1_ASSIGN(const std::string_view lum, files.rows("luminosity.q32", 8));
  R1_ASSIGN(const std::string_view hue, files.rows("hue.q32", 8));
  R1_ASSIGN(const std::string_view sat, files.rows("saturation.q32", 8));
  e.encoding.radius = read_q32_column(radius, n);
  e.encoding.luminosity = read_q32_column(lum, n);
  e.encoding.hue = read_q32_column(hue, n);
  e.encoding.saturation = read_q32_column(sat, n);
  R1_ASSIGN(const std::string_view role, files.rows("role.u8", 1));
  R1_ASSIGN(const std::string_view shape, files.rows("shape.u8", 1));
  R1_ASSIGN(const std::string_view color, files.rows("color.rgb8", 3));
  e.encoding.role.resize(n);
  e.encoding.shape.resize(n);
  e.encoding.color.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto r = static_cast<std::uint8_t>(role[i]), s = static_cast<std::uint8_t>(shape[i]);
    if (r > 3) return Status::input((dir / "role.u8").string() + ": byte " + std::to_string(i) + ": unknown role " + std::to_string(r));
    if (s > 5) return Status::input((dir / "shape.u8").string() + ": byte " + std::to_string(i) + ": unknown shape " + std::to_string(s));
    e.encoding.role[i] = static_cast<Role>(r);
    e.encoding.shape[i] = static_cast<Shape>(s);
    std::memcpy(e.encoding.color[i].data(), color.data() + 3 * i, 3);
  }
  R1_ASSIGN(const std::string_view clusters, files.rows("clusters.u32", 4 * kLevels));
  for (std::size_t l = 0; l < kLevels; ++l) e.hierarchy.cluster_of[l] = format::read_u32_column(clusters, n, kLevels, l);
  e.titles.assign(n, {});
  if (const InputFile* t = files.find("titles.tsv")) R1_TRY(read_titles(*t, (dir / "titles.tsv").string(), e));
  R1_TRY(read_edges(files, dir / "edges.bin", n, m.at("snapshot").at("layout_edges").get<std::size_t>(), e));
  if (const InputFile* c = files.find("records.chunks")) {
    const std::size_t chunks = record_chunk_count(e.links);
    const std::string_view b = c->text();
    if (b.size() != chunks * kChunkRowBytes)
      return Status::input((dir / "records.chunks").string() + ": " + std::to_string(b.size()) + " bytes for " +
                           std::to_string(e.links) + " links (expected " + std::to_string(chunks * kChunkRowBytes) + ")");
    e.record_chunks = record_chunks_of(b, chunks);
    // The leaves are the snapshot digest's: a file from another snapshot, or one of leaves that
    // do not make its digest, is not carried into the next epoch's digest.
    if (hemera::root_of_leaves(e.record_chunks.leaves) != e.snapshot_digest)
      return Status::input((dir / "records.chunks").string() + ": its leaves do not combine to the snapshot digest");
  }
  R1_ASSIGN(const std::string_view out_rows, files.rows("outrows.u64", 8));
  e.out_rows = format::read_u64_column(out_rows, n);
  if (e.spectrum.sums_shift >= 0) {
    if (!files.find("image.i128")) return Status::input(manifest + ": residual_sums without image.i128");
    R1_ASSIGN(const std::string_view img, files.rows("image.i128", 80));
    e.spectrum.image = format::read_i128_column(img, n * 5);
    // r1's numerators stay below 2^83 (entries below 2^50 and an image of norm at most twice
    // theirs): beyond 2^94 the rounded image would leave int64 (R1-INC-038).
    const i128 limit = i128{1} << 94;
    for (std::size_t k = 0; k < e.spectrum.image.size(); ++k)
      if (e.spectrum.image[k] >= limit || e.spectrum.image[k] <= -limit)
        return Status::input((dir / "image.i128").string() + ": byte " + std::to_string(16 * k) + ": a numerator beyond 2^94");
  }
  if (files.find("betweenness.f64")) {
    R1_ASSIGN(const std::string_view b, files.rows("betweenness.f64", 8));
    e.encoding.betweenness = format::read_f64_column(b, n);
    for (std::size_t i = 0; i < n; ++i)
      if (!(e.encoding.betweenness[i] >= 0 && std::isfinite(e.encoding.betweenness[i])))
        return Status::input((dir / "betweenness.f64").string() + ": byte " + std::to_string(8 * i) + ": not a finite betweenness >= 0");
  }
  // The hierarchy the renderer walks: parsed, and checked against the particle data (R1-HIER-052).
  const std::string hier_path = (dir / "hierarchy.bin").string();
  const InputFile* hier = files.find("hierarchy.bin");
  if (!hier) return Status::input(hier_path + ": not listed in the manifest");
  R1_ASSIGN(e.hierarchy, parse_hierarchy_bytes(hier->text(), hier_path));
  if (e.hierarchy.cluster_of[0].size() != n)
    return Status::input(hier_path + ": hierarchy of " + std::to_string(e.hierarchy.cluster_of[0].size()) + " particles, the epoch has " +
                         std::to_string(n));
  const Status valid = check_hierarchy(e.hierarchy, e.frame.position, e.focus.phi, e.encoding.color, e.ids);
  if (!valid) return Status::input(hier_path + ": " + valid.message());
  return e;
}

}  // namespace

RecordChunks peek_record_chunks(const fs::path& dir) {
  // Only a file the manifest lists: the read that checks PREV reads no other.
  try {
    auto mf = InputFile::open((dir / "manifest.json").string());
    if (!mf.is_ok()) return {};
    const json m = json::parse(mf.value()->text());
    if (!m.contains("files") || !m.at("files").is_object() || !m.at("files").contains("records.chunks")) return {};
  } catch (const std::exception&) {
    return {};
  }
  auto in = InputFile::open((dir / "records.chunks").string());
  if (!in.is_ok()) return {};
  const std::string_view b = in.value()->text();
  if (b.empty() || b.size() % kChunkRowBytes != 0) return {};
  return record_chunks_of(b, b.size() / kChunkRowBytes);
}

Result<Epoch> read_epoch(const fs::path& dir, EpochLeaves* leaves, DigestCheck check) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return Status::input(dir.string() + ": not an epoch directory (make one with r1 epoch)");
  R1_ASSIGN(auto mf, InputFile::open((dir / "manifest.json").string()));
  try {
    return read_epoch_json(dir, json::parse(mf->text()), leaves, check);
  } catch (const json::exception& ex) {
    return Status::input((dir / "manifest.json").string() + ": malformed manifest: " + ex.what());
  }
}

std::string export_tsv(const Epoch& e) {
  std::string o =
      "particle\ttitle\tx\ty\tz\tu5\tu6\tfocus\tradius\tluminosity\thue\tsaturation\trole\tcluster0\tcluster1\tcluster2\tcluster3\n";
  for (std::size_t i = 0; i < e.ids.size(); ++i) {
    o += hex(e.ids[i]);
    o += '\t';
    o += text::escape_cell(i < e.titles.size() ? e.titles[i] : "");
    for (Q32 c : e.frame.position[i]) o += "\t" + c.to_string();
    o += "\t" + e.spectrum.u[3][i].to_string() + "\t" + e.spectrum.u[4][i].to_string();
    o += "\t" + e.focus.phi[i].to_string();
    o += "\t" + e.encoding.radius[i].to_string() + "\t" + e.encoding.luminosity[i].to_string();
    o += "\t" + e.encoding.hue[i].to_string() + "\t" + e.encoding.saturation[i].to_string();
    o += "\t";
    o += role_name(e.encoding.role[i]);
    for (std::size_t l = 0; l < kLevels; ++l) o += "\t" + std::to_string(e.hierarchy.cluster_of[l][i]);
    o += '\n';
  }
  return o;
}

}  // namespace r1
