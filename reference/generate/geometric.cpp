// Random geometric graph in the unit cube with exact integer distances and a cell grid
// (R1-GEN-030..032).
#include <array>

#include "gen_internal.hpp"

namespace r1::gen {

namespace {

// Point i's coordinates: the top 32 bits of bits(seed, i, d) for d = 0, 1, 2, i.e. the unit cube
// scaled by 2^32 (R1-GEN-030).
std::array<std::uint32_t, 3> point(std::uint64_t seed, std::uint32_t i) {
  return {static_cast<std::uint32_t>(rng::bits(seed, i, 0) >> 32),
          static_cast<std::uint32_t>(rng::bits(seed, i, 1) >> 32),
          static_cast<std::uint32_t>(rng::bits(seed, i, 2) >> 32)};
}

u128 dist2(const std::array<std::uint32_t, 3>& a, const std::array<std::uint32_t, 3>& b) {
  u128 s = 0;
  for (int d = 0; d < 3; ++d) {
    const std::uint64_t x = a[d] > b[d] ? a[d] - b[d] : b[d] - a[d];
    s += static_cast<u128>(x) * x;  // < 2^64 each, < 3 * 2^64 in all: exact in 128 bits
  }
  return s;
}

}  // namespace

Result<Snapshot> gen_rgg(const Resolved& p, std::string card, const ProgressFn& progress) {
  const std::uint32_t n = p.n;
  // The radius in coordinate units, floor(r * 2^32) (exact: a power-of-two scale); a pair is
  // linked when its squared integer distance is at most rq^2.
  const std::uint64_t rq = static_cast<std::uint64_t>(p.radius * 0x1p32);
  const u128 r2 = static_cast<u128>(rq) * rq;

  std::vector<std::array<std::uint32_t, 3>> pts(n);
  tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, n, 4096), [&](const tbb::blocked_range<std::uint32_t>& r) {
    for (std::uint32_t i = r.begin(); i != r.end(); ++i) pts[i] = point(p.seed, i);
  });

  // Cells per axis g: each cell is at least rq wide (so linked points lie in neighbouring cells)
  // and g^3 <= n (so the grid costs no more memory than the points). The grid only speeds the
  // search: the links are the same for every g.
  std::uint64_t g = 1;
  const std::uint64_t g_width = rq == 0 ? (std::uint64_t{1} << 32) : (std::uint64_t{1} << 32) / rq;
  while ((g + 1) <= g_width && (g + 1) * (g + 1) * (g + 1) <= n) ++g;
  const auto cell_of = [g](std::uint32_t x) { return static_cast<std::uint32_t>((x * g) >> 32); };
  const std::uint64_t cells = g * g * g;
  std::vector<std::uint32_t> cell(n), start(cells + 1, 0), sorted(n);
  for (std::uint32_t i = 0; i < n; ++i) {
    cell[i] = static_cast<std::uint32_t>((cell_of(pts[i][2]) * g + cell_of(pts[i][1])) * g + cell_of(pts[i][0]));
    ++start[cell[i] + 1];
  }
  for (std::uint64_t c = 0; c < cells; ++c) start[c + 1] += start[c];
  {
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (std::uint32_t i = 0; i < n; ++i) sorted[fill[cell[i]]++] = i;
  }

  // Points in fixed blocks of 1024, decided in parallel, concatenated in block order: pairs come
  // out sorted by (i, j) whatever the thread count.
  constexpr std::uint32_t kBlock = 1024;
  const std::uint32_t blocks = (n + kBlock - 1) / kBlock;
  std::vector<std::vector<Edge>> out(blocks);
  std::atomic<std::uint64_t> done{0};
  tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, blocks, 1), [&](const tbb::blocked_range<std::uint32_t>& r) {
    std::vector<std::uint32_t> near;
    for (std::uint32_t blk = r.begin(); blk != r.end(); ++blk) {
      const std::uint32_t last = std::min(n, (blk + 1) * kBlock);
      for (std::uint32_t i = blk * kBlock; i < last; ++i) {
        near.clear();
        const std::int64_t cx = cell_of(pts[i][0]), cy = cell_of(pts[i][1]), cz = cell_of(pts[i][2]);
        const std::int64_t gi = static_cast<std::int64_t>(g);
        for (std::int64_t z = std::max<std::int64_t>(cz - 1, 0); z <= std::min(cz + 1, gi - 1); ++z)
          for (std::int64_t y = std::max<std::int64_t>(cy - 1, 0); y <= std::min(cy + 1, gi - 1); ++y)
            for (std::int64_t x = std::max<std::int64_t>(cx - 1, 0); x <= std::min(cx + 1, gi - 1); ++x) {
              const auto c = static_cast<std::uint64_t>((z * gi + y) * gi + x);
              for (std::uint32_t s = start[c]; s < start[c + 1]; ++s) {
                const std::uint32_t j = sorted[s];
                if (j > i && dist2(pts[i], pts[j]) <= r2) near.push_back(j);
              }
            }
        std::sort(near.begin(), near.end());
        for (std::uint32_t j : near) out[blk].push_back(Edge{i, j});
      }
      report(progress, "generating rgg", done += last - blk * kBlock, n);
    }
  });
  std::vector<std::uint32_t>().swap(cell);
  std::vector<std::uint32_t>().swap(sorted);
  std::vector<std::uint32_t>().swap(start);

  std::size_t count = 0;
  for (const auto& v : out) count += v.size();
  Emitter e("gen:rgg", n, indexed_names("rgg"));
  e.reserve_links(count);
  for (auto& v : out) {
    for (const Edge& x : v) e.link(x.a, x.b);
    std::vector<Edge>().swap(v);
  }
  return e.finish(std::move(card), progress);
}

}  // namespace r1::gen
