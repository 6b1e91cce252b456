// Parking the layout graph's arrays the spectral solve does not read (R1-EPO-006): each array is
// cut into chunks of 1 MiB, a chunk's entries are split into byte planes (byte b of every entry
// together: the high bytes of small weights and indices are runs that compress to nothing) and
// compressed with zstd at level 1. Restoring reverses both, bit for bit.
#include "r1/reference/graph_park.hpp"

#include <zstd.h>

#include <algorithm>
#include <atomic>
#include <string>
#include <type_traits>
#include <vector>

#include <tbb/parallel_for.h>

namespace r1 {

namespace {

constexpr std::size_t kChunkBytes = std::size_t{1} << 20;
constexpr int kLevel = 1;

// Calls f(array) for every parked array of g, in one fixed order (park and restore share it).
template <class F>
void each_parked(Graph& g, F&& f) {
  f(g.w);
  f(g.a2);
  f(g.out_ptr);
  f(g.out_col);
  f(g.out_w);
  f(g.prior);
  f(g.dangling);
  f(g.component);
}

// Runs body(c) for c in [0, count), on TBB workers when `parallel`; returns the first failure.
template <class Body>
Status for_chunks(std::size_t count, bool parallel, Body&& body) {
  std::atomic<bool> failed{false};
  std::string message;
  auto one = [&](std::size_t c) {
    const std::string err = body(c);
    if (!err.empty() && !failed.exchange(true)) message = err;
  };
  if (parallel && count > 1) {
    tbb::parallel_for(std::size_t{0}, count, one);
  } else {
    for (std::size_t c = 0; c < count; ++c) one(c);
  }
  return failed.load() ? Status::internal("graph park: " + message) : Status::ok();
}

template <class T>
Result<ParkedGraph::Packed> pack(const std::vector<T>& v, bool parallel) {
  constexpr std::size_t W = sizeof(T);
  constexpr std::size_t per_chunk = kChunkBytes / W;
  ParkedGraph::Packed p;
  p.elements = v.size();
  p.width = W;
  p.chunks.resize((v.size() + per_chunk - 1) / per_chunk);
  const auto* bytes = reinterpret_cast<const unsigned char*>(v.data());
  R1_TRY(for_chunks(p.chunks.size(), parallel, [&](std::size_t c) -> std::string {
    const std::size_t first = c * per_chunk, count = std::min(per_chunk, v.size() - first);
    std::vector<unsigned char> planes(count * W);
    for (std::size_t i = 0; i < count; ++i)
      for (std::size_t b = 0; b < W; ++b) planes[b * count + i] = bytes[(first + i) * W + b];
    std::vector<unsigned char>& out = p.chunks[c];
    out.resize(ZSTD_compressBound(planes.size()));
    const std::size_t got = ZSTD_compress(out.data(), out.size(), planes.data(), planes.size(), kLevel);
    if (ZSTD_isError(got)) return ZSTD_getErrorName(got);
    out.resize(got);
    out.shrink_to_fit();
    return {};
  }));
  return p;
}

template <class T>
Status unpack(const ParkedGraph::Packed& p, std::vector<T>& v, bool parallel) {
  constexpr std::size_t W = sizeof(T);
  constexpr std::size_t per_chunk = kChunkBytes / W;
  if (p.width != W || p.chunks.size() != (p.elements + per_chunk - 1) / per_chunk)
    return Status::internal("graph park: an array came back in another shape");
  v.resize(p.elements);
  auto* bytes = reinterpret_cast<unsigned char*>(v.data());
  return for_chunks(p.chunks.size(), parallel, [&](std::size_t c) -> std::string {
    const std::size_t first = c * per_chunk, count = std::min(per_chunk, p.elements - first);
    std::vector<unsigned char> planes(count * W);
    const std::size_t got = ZSTD_decompress(planes.data(), planes.size(), p.chunks[c].data(), p.chunks[c].size());
    if (ZSTD_isError(got)) return ZSTD_getErrorName(got);
    if (got != planes.size()) return "a chunk came back short";
    for (std::size_t i = 0; i < count; ++i)
      for (std::size_t b = 0; b < W; ++b) bytes[(first + i) * W + b] = planes[b * count + i];
    return {};
  });
}

}  // namespace

void release_unread_by_spectral(Graph& g) {
  each_parked(g, [](auto& v) { std::remove_reference_t<decltype(v)>().swap(v); });
}

Result<ParkedGraph> ParkedGraph::park(Graph& g, bool parallel) {
  ParkedGraph out;
  Status st = Status::ok();
  each_parked(g, [&](auto& v) {
    if (!st.is_ok()) return;
    auto packed = pack(v, parallel);
    if (!packed) {
      st = packed.status();
      return;
    }
    out.arrays_.push_back(std::move(*packed));
  });
  R1_TRY(st);
  // Every array is packed: only now is any released, so a failure leaves g whole.
  each_parked(g, [](auto& v) { std::remove_reference_t<decltype(v)>().swap(v); });
  return out;
}

Status ParkedGraph::restore(Graph& g, bool parallel) {
  if (arrays_.empty()) return Status::ok();
  std::size_t k = 0;
  Status st = Status::ok();
  each_parked(g, [&](auto& v) {
    if (!st.is_ok()) return;
    st = unpack(arrays_[k], v, parallel);
    std::vector<std::vector<unsigned char>>().swap(arrays_[k].chunks);  // each array's chunks go as it returns
    ++k;
  });
  arrays_.clear();
  return st;
}

std::uint64_t ParkedGraph::raw_bytes() const {
  std::uint64_t s = 0;
  for (const Packed& p : arrays_) s += static_cast<std::uint64_t>(p.elements) * p.width;
  return s;
}

std::uint64_t ParkedGraph::packed_bytes() const {
  std::uint64_t s = 0;
  for (const Packed& p : arrays_)
    for (const auto& c : p.chunks) s += c.size();
  return s;
}

}  // namespace r1
