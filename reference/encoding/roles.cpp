// Role inference: hub by an exact integer degree test, bridge by a betweenness threshold, leaf by degree 1 (R1-ENC-010..011, R1-ENC-017..018).
#include <cmath>

#include "r1/fixedpoint/pairwise.hpp"
#include "r1/fixedpoint/q32.hpp"
#include "r1/reference/encoding.hpp"

namespace r1 {

namespace {

// Margin of R1-ENC-017: 2^-20 of the mean lies far above the ~2^-40 relative rounding noise of
// betweenness, so mathematically uniform betweenness never yields a bridge.
constexpr double kBridgeMargin = 0x1p-20;

}  // namespace

bool is_hub(std::uint64_t degree, std::uint64_t n, u128 s1, u128 s2) {
  // d > mean + 2 sigma  <=>  A = n d - S1 > 2 sqrt(B), B = n S2 - S1^2 >= 0 (Cauchy-Schwarz).
  // For an integer A > 0: A^2 > 4B <=> A > floor(sqrt(4B)), whether or not 4B is a square.
  const u128 nd = static_cast<u128>(n) * degree;
  if (nd <= s1) return false;
  const u128 a = nd - s1;
  const u128 b = static_cast<u128>(n) * s2 - s1 * s1;
  return a > fx::detail::isqrt(4 * b);
}

std::vector<Role> infer_roles(const Graph& g, std::span<const double> betweenness, RoleStats* stats) {
  const std::uint32_t n = g.n;
  // With n <= 2^32 and nnz < 2^40, S1 < 2^40 and S2 <= nnz x max degree < 2^72: n S2 < 2^104 and
  // 4B < 2^106, all inside u128.
  u128 s1 = 0, s2 = 0;
  for (std::uint32_t p = 0; p < n; ++p) {
    const u128 d = g.neighbours(p);
    s1 += d;
    s2 += d * d;
  }
  double mu = 0, theta = 0, sigma = 0;
  const bool have_b = betweenness.size() == n && n > 0;
  if (have_b) {
    // Population mean and standard deviation, two passes over the fixed pairwise tree (R1-NUM-051).
    mu = fx::pairwise_sum(betweenness) / static_cast<double>(n);
    std::vector<double> dev(n);
    for (std::uint32_t p = 0; p < n; ++p) dev[p] = betweenness[p] - mu;
    sigma = std::sqrt(fx::pairwise_dot(dev, dev) / static_cast<double>(n));
    theta = (mu + 2.0 * sigma) + kBridgeMargin * mu;
  }
  std::vector<Role> role(n, Role::kNone);
  RoleStats st;
  for (std::uint32_t p = 0; p < n; ++p) {
    const std::uint32_t d = g.neighbours(p);
    // Precedence hub, bridge, leaf (R1-ENC-018).
    if (is_hub(d, n, s1, s2)) {
      role[p] = Role::kHub;
    } else if (have_b && betweenness[p] > theta) {
      role[p] = Role::kBridge;
    } else if (d == 1) {
      role[p] = Role::kLeaf;
    }
    ++st.count[static_cast<std::size_t>(role[p])];
  }
  if (stats) {
    // Informational values for the manifest (the hub test above is exact).
    auto to_d = [](u128 v) {
      return static_cast<double>(static_cast<std::uint64_t>(v >> 64)) * 0x1p64 + static_cast<double>(static_cast<std::uint64_t>(v));
    };
    const double nd = static_cast<double>(n);
    st.degree_mean = n ? to_d(s1) / nd : 0;
    const double var = n ? to_d(s2) / nd - st.degree_mean * st.degree_mean : 0;
    st.degree_sigma = std::sqrt(var > 0 ? var : 0);
    st.betweenness_mean = mu;
    st.betweenness_sigma = sigma;
    st.bridge_threshold = theta;
    *stats = st;
  }
  return role;
}

}  // namespace r1
