// r_0 from the layout (R1-ENC-007): the median spacing of the distinct positions and the median
// focus set the scene-scale constant so that a median particle's radius is half the median
// spacing: two median particles at the median spacing touch, never overlap. Exact integer
// distances through the hierarchy's k-d tree.
#include <algorithm>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "../hierarchy/kd_tree.hpp"
#include "r1/reference/encoding.hpp"

namespace r1 {

RadiusScale radius_scale_from_layout(std::span<const std::array<Q32, 3>> position, std::span<const Q32> phi,
                                     bool parallel) {
  RadiusScale out;
  std::vector<hier::Point> pts(position.size());
  for (std::size_t i = 0; i < position.size(); ++i)
    pts[i] = {position[i][0].raw, position[i][1].raw, position[i][2].raw};
  std::sort(pts.begin(), pts.end());
  pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
  out.distinct = pts.size();
  if (pts.size() < 2 || phi.empty()) return out;  // one place: nothing to space, r_0 = R_scene

  // Each distinct position's squared distance to the nearest other one.
  const hier::KdTree tree(pts, parallel);
  std::vector<u128> d2(pts.size());
  auto query = [&](std::size_t begin, std::size_t end) {
    std::vector<hier::Hit> hit;
    for (std::size_t i = begin; i < end; ++i) {
      tree.nearest_from_readonly(static_cast<std::uint32_t>(i), u128_max, 1, hit);
      d2[i] = hit.front().d2;
    }
  };
  if (parallel) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pts.size(), 4096),
                      [&](const tbb::blocked_range<std::size_t>& r) { query(r.begin(), r.end()); });
  } else {
    query(0, pts.size());
  }
  const auto mid = d2.begin() + static_cast<std::ptrdiff_t>(d2.size() / 2);
  std::nth_element(d2.begin(), mid, d2.end());
  out.spacing2 = *mid;

  std::vector<std::int64_t> f(phi.size());
  for (std::size_t i = 0; i < phi.size(); ++i) f[i] = phi[i].raw;
  const auto fm = f.begin() + static_cast<std::ptrdiff_t>(f.size() / 2);
  std::nth_element(f.begin(), fm, f.end());
  out.median_phi_raw = std::max<std::int64_t>(*fm, 1);

  // r_0^2 = (d / 2)^2 / phi_med with d^2 = D / 2^64 and phi = F / 2^32, so its Q32 raw is
  // D / (4 F): one rounding, then clamped to [1 raw, R_scene^2].
  const i128 raw = fx::detail::rne_div(static_cast<i128>(out.spacing2), static_cast<i128>(4) * out.median_phi_raw);
  out.r0_squared_raw = static_cast<std::int64_t>(std::clamp<i128>(raw, 1, kSceneR0SquaredRaw));
  return out;
}

}  // namespace r1
