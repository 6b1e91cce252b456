// Genesis positions: (u_2, u_3, u_4) scaled to R_scene from an exact max norm (R1-FRM-002, R1-FRM-010..013).
#include <string>

#include "r1/fixedpoint/int128.hpp"
#include "r1/reference/frame.hpp"

namespace r1 {

namespace {

// floor(sqrt(n)) rounded to nearest: sqrt(n) >= s + 1/2 iff n >= s^2 + s + 1/4 iff n - s^2 > s for
// integers; a tie would need n = s^2 + s + 1/4, so none occurs.
u128 round_sqrt(u128 n) {
  u128 s = fx::detail::isqrt(n);
  if (n - s * s > s) ++s;
  return s;
}

}  // namespace

Result<Frame> genesis_frame(const Spectrum<Q32>& s, std::uint32_t n) {
  if (s.n != n)
    return Status::internal("frame: the spectrum has " + std::to_string(s.n) + " particles, the snapshot " + std::to_string(n));
  for (std::size_t k = 0; k < s.u.size(); ++k)
    if (!s.u[k].empty() && s.u[k].size() != n)
      return Status::internal("frame: eigenvector u_" + std::to_string(k + 2) + " has " + std::to_string(s.u[k].size()) +
                              " entries for " + std::to_string(n) + " particles");

  // Coordinate c of particle p: u_{c+2}(p), or 0 when that vector is missing (R1-FRM-002).
  auto coord = [&](std::size_t c, std::size_t p) { return s.u[c].empty() ? std::int64_t{0} : s.u[c][p].raw; };

  // Exact squared norms in units of 2^-64; each square is at most 2^126 and the sum of three
  // stays below 2^128 for any raws.
  u128 max_norm2 = 0;
  for (std::size_t p = 0; p < n; ++p) {
    u128 n2 = 0;
    for (std::size_t c = 0; c < 3; ++c) {
      const i128 x = coord(c, p);
      n2 += static_cast<u128>(x * x);
    }
    if (n2 > max_norm2) max_norm2 = n2;
  }

  Frame f;
  f.position.assign(n, {Q32{}, Q32{}, Q32{}});
  f.alignment = Alignment{};
  f.alignment.rotation = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  if (max_norm2 == 0) {
    f.scale = 0;  // nothing to scale: every particle sits at the origin (R1-FRM-012)
    return f;
  }
  // max |X| as the correctly rounded Q32 value: sqrt of a 2^-64-unit integer is in 2^-32 units.
  const u128 m = round_sqrt(max_norm2);
  if (m > static_cast<u128>(INT64_MAX)) return Status::internal("frame: max |X| does not fit Q32 (eigenvectors are not unit-norm)");
  const auto scale = fx::checked_div(Q32::from_int(kSceneRadius), Q32::from_raw(static_cast<std::int64_t>(m)));
  if (!scale) return Status::internal("frame: R_scene / max |X| does not fit Q32 (eigenvectors are not unit-norm)");
  f.scale = scale->to_double();
  R1_ASSIGN(f.position, scaled_positions(s.u, n, *scale));
  return f;
}

Result<std::vector<std::array<Q32, 3>>> scaled_positions(const std::array<std::vector<Q32>, 5>& u, std::size_t n, Q32 scale) {
  std::vector<std::array<Q32, 3>> pos(n);
  for (std::size_t p = 0; p < n; ++p)
    for (std::size_t c = 0; c < 3; ++c) {
      const auto x = fx::checked_mul(u[c].empty() ? Q32{} : u[c][p], scale);
      if (!x) return Status::internal("frame: a scaled coordinate does not fit Q32 (eigenvectors are not unit-norm)");
      pos[p][c] = *x;
    }
  return pos;
}

}  // namespace r1
