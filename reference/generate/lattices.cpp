// Deterministic generators: ring, path, star, grid, torus, complete (R1-GEN-010..015).
#include <algorithm>

#include "gen_internal.hpp"

namespace r1::gen {

namespace {

// Progress every 2^20 links: often enough for a smooth line, rarely enough to cost nothing.
constexpr std::uint64_t kReportEvery = std::uint64_t{1} << 20;

// Undirected edge {u, v} as one link from the lower to the higher index (R1-GEN-009).
void edge(Emitter& e, std::uint32_t u, std::uint32_t v) { e.link(std::min(u, v), std::max(u, v)); }

// Reports when `done`, just advanced by `step`, crossed a multiple of kReportEvery or the end.
void tick(const ProgressFn& progress, std::string_view stage, std::uint64_t done, std::uint64_t total,
          std::uint64_t step = 1) {
  if (done % kReportEvery < step || done == total) report(progress, stage, done, total);
}

}  // namespace

Result<Snapshot> gen_ring(const Resolved& p, std::string card, const ProgressFn& progress) {
  Emitter e("gen:ring", p.n, indexed_names("ring"));
  e.reserve_links(p.n);
  // Edge k joins k and k + 1 (mod n); the closing edge n-1 is emitted last as 0 -> n-1.
  for (std::uint32_t k = 0; k < p.n; ++k) {
    edge(e, k, (k + 1) % p.n);
    tick(progress, "generating ring", k + 1, p.n);
  }
  return e.finish(std::move(card), progress);
}

Result<Snapshot> gen_path(const Resolved& p, std::string card, const ProgressFn& progress) {
  Emitter e("gen:path", p.n, indexed_names("path"));
  e.reserve_links(p.n - 1);
  for (std::uint32_t k = 0; k + 1 < p.n; ++k) {
    edge(e, k, k + 1);
    tick(progress, "generating path", k + 1, p.n - 1);
  }
  return e.finish(std::move(card), progress);
}

Result<Snapshot> gen_star(const Resolved& p, std::string card, const ProgressFn& progress) {
  Emitter e("gen:star", p.n, indexed_names("star"));
  e.reserve_links(p.n - 1);
  // Node 0 is the centre.
  for (std::uint32_t k = 1; k < p.n; ++k) {
    edge(e, 0, k);
    tick(progress, "generating star", k, p.n - 1);
  }
  return e.finish(std::move(card), progress);
}

Result<Snapshot> gen_grid(const Resolved& p, std::string card, const ProgressFn& progress) {
  const std::uint32_t w = p.dims[0], h = p.dims[1];
  Emitter e("gen:grid", p.n, indexed_names("grid"));
  const std::uint64_t total = static_cast<std::uint64_t>(w - 1) * h + static_cast<std::uint64_t>(w) * (h - 1);
  e.reserve_links(total);
  std::uint64_t done = 0;
  // Node (x, y) is y * w + x; each node links to its right, then its lower neighbour.
  for (std::uint32_t y = 0; y < h; ++y) {
    for (std::uint32_t x = 0; x < w; ++x) {
      const std::uint32_t i = y * w + x;
      if (x + 1 < w) {
        edge(e, i, i + 1);
        tick(progress, "generating grid", ++done, total);
      }
      if (y + 1 < h) {
        edge(e, i, i + w);
        tick(progress, "generating grid", ++done, total);
      }
    }
  }
  return e.finish(std::move(card), progress);
}

Result<Snapshot> gen_torus(const Resolved& p, std::string card, const ProgressFn& progress) {
  const std::uint32_t a = p.dims[0], b = p.dims[1], c = p.dims[2];
  Emitter e("gen:torus", p.n, indexed_names("torus"));
  const std::uint64_t total = 3 * static_cast<std::uint64_t>(p.n);
  e.reserve_links(total);
  std::uint64_t done = 0;
  const auto index = [&](std::uint32_t x, std::uint32_t y, std::uint32_t z) { return (z * b + y) * a + x; };
  // Node (x, y, z) is (z * b + y) * a + x; each node links to its +x, +y, +z neighbour with
  // periodic wrap. Sides >= 3 make the 3abc edges distinct, so every node has degree 6.
  for (std::uint32_t z = 0; z < c; ++z) {
    for (std::uint32_t y = 0; y < b; ++y) {
      for (std::uint32_t x = 0; x < a; ++x) {
        const std::uint32_t i = index(x, y, z);
        edge(e, i, index((x + 1) % a, y, z));
        edge(e, i, index(x, (y + 1) % b, z));
        edge(e, i, index(x, y, (z + 1) % c));
        done += 3;
        tick(progress, "generating torus", done, total, 3);
      }
    }
  }
  return e.finish(std::move(card), progress);
}

Result<Snapshot> gen_complete(const Resolved& p, std::string card, const ProgressFn& progress) {
  Emitter e("gen:complete", p.n, indexed_names("complete"));
  const std::uint64_t total = static_cast<std::uint64_t>(p.n) * (p.n - 1) / 2;
  e.reserve_links(total);
  std::uint64_t done = 0;
  for (std::uint32_t i = 0; i < p.n; ++i) {
    for (std::uint32_t j = i + 1; j < p.n; ++j) e.link(i, j);
    done += p.n - 1 - i;
    report(progress, "generating complete graph", done, total);
  }
  return e.finish(std::move(card), progress);
}

}  // namespace r1::gen
