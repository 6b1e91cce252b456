// Largest-remainder apportionment and the projection to the simplex in Q32 and fp64
// (R1-FOC-010, R1-FOC-051..053).
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "apportion.hpp"
#include "r1/fixedpoint/pairwise.hpp"
#include "r1/solvers/focus.hpp"

namespace r1 {
namespace focus {

void apportion_into_plain(std::uint64_t total, std::span<const std::uint64_t> w, std::span<std::int64_t> out,
                    ApportionScratch& scratch) {
  const std::size_t n = w.size();
  if (n == 0 || out.size() != n) throw std::invalid_argument("apportion: no weights or size mismatch");
  if (total >= (std::uint64_t{1} << 63)) throw std::invalid_argument("apportion: total must be below 2^63");
  u128 sum = 0;
  for (const std::uint64_t x : w) sum += x;
  // All weights zero: every item counts as weight 1 (R1-FOC-010), so the total is spread evenly.
  const bool equal = sum == 0;
  if (equal) sum = n;
  auto& rem = scratch.remainder;
  rem.resize(n);
  std::uint64_t given = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const u128 p = static_cast<u128>(total) * (equal ? 1 : w[i]);  // < 2^127: exact
    const u128 q = p / sum;
    rem[i] = p - q * sum;
    out[i] = static_cast<std::int64_t>(q);  // q <= total < 2^63
    given += static_cast<std::uint64_t>(q);
  }
  // 0 <= left < n: each floor loses less than one unit.
  const std::uint64_t left = total - given;
  if (left == 0) return;
  // The `left` largest remainders get one more unit; only items with a remainder can be among
  // them (sum of remainders = sum * left with each below sum, so more than `left` are non-zero).
  auto& order = scratch.order;
  order.clear();
  for (std::size_t i = 0; i < n; ++i)
    if (rem[i] != 0) order.push_back(static_cast<std::uint32_t>(i));
  // Larger remainder first, then the lower index: a strict total order, so the chosen set is
  // unique whatever nth_element's internal steps are.
  const auto before = [&rem](std::uint32_t a, std::uint32_t b) { return rem[a] != rem[b] ? rem[a] > rem[b] : a < b; };
  const auto cut = order.begin() + static_cast<std::ptrdiff_t>(left);
  std::nth_element(order.begin(), cut, order.end(), before);
  for (auto it = order.begin(); it != cut; ++it) ++out[*it];
}

namespace {

// The same shares for many weights whose sum is below 2^63 and a total of at most 2^40 (every
// prior and every projection, R1-FOC-011, R1-FOC-051): each quotient from a double estimate,
// made exact by its remainder (the estimate is within one of the quotient; the loops make it
// exact whatever it is), and the `left` largest remainders found through 2^16 buckets that a
// monotone map of the remainder picks: the items above the threshold's bucket all get a unit,
// and only that bucket is ordered. The order is the strict (remainder desc, index asc) of
// apportion_into_plain, so the chosen set, and every share, is the same.
constexpr std::size_t kFastFrom = 4096;
constexpr std::uint32_t kBuckets = 1u << 16;

bool fast_apportion(std::uint64_t total, std::span<const std::uint64_t> w, std::span<std::int64_t> out, u128 sum,
                    ApportionScratch& scratch) {
  const std::size_t n = w.size();
  // Remainders below 2^63: one signed conversion each.
  if (n < kFastFrom || sum == 0 || sum >= (u128{1} << 63) || total > (std::uint64_t{1} << 40)) return false;
  const auto s = static_cast<std::uint64_t>(sum);
  const double ratio = static_cast<double>(total) / static_cast<double>(s);
  const double scale = static_cast<double>(kBuckets) / static_cast<double>(s);
  auto& rem = scratch.rem64;
  auto& bucket = scratch.bucket_of;
  auto& count = scratch.buckets;
  rem.resize(n);
  bucket.resize(n);
  count.assign(kBuckets, 0);
  std::uint64_t given = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const u128 p = static_cast<u128>(total) * w[i];
    std::uint64_t q = static_cast<std::uint64_t>(static_cast<double>(w[i]) * ratio);
    if (q > total) q = total;
    i128 r = static_cast<i128>(p) - static_cast<i128>(static_cast<u128>(q) * s);
    while (r < 0) {
      --q;
      r += s;
    }
    while (r >= static_cast<i128>(s)) {
      ++q;
      r -= s;
    }
    rem[i] = static_cast<std::uint64_t>(r);
    out[i] = static_cast<std::int64_t>(q);
    given += q;
    // A monotone map of the remainder (r < s < 2^63): rounding, scaling by a positive constant,
    // truncation and the clamp all keep the order, ties included.
    const auto k = std::min<std::uint32_t>(static_cast<std::uint32_t>(static_cast<double>(static_cast<std::int64_t>(r)) * scale),
                                           kBuckets - 1);
    bucket[i] = static_cast<std::uint16_t>(k);
    ++count[k];
  }
  std::uint64_t left = total - given;
  if (left == 0) return true;
  std::uint32_t b = kBuckets - 1;
  while (count[b] < left) {  // more than `left` remainders are non-zero, so this stops
    left -= count[b];
    --b;
  }
  auto& candidates = scratch.order;
  candidates.clear();
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t k = bucket[i];
    if (k > b) ++out[i];
    else if (k == b) candidates.push_back(static_cast<std::uint32_t>(i));
  }
  const auto before = [&rem](std::uint32_t x, std::uint32_t y) { return rem[x] != rem[y] ? rem[x] > rem[y] : x < y; };
  const auto cut = candidates.begin() + static_cast<std::ptrdiff_t>(left);
  std::nth_element(candidates.begin(), cut, candidates.end(), before);
  for (auto it = candidates.begin(); it != cut; ++it) ++out[*it];
  return true;
}

}  // namespace

void apportion_into(std::uint64_t total, std::span<const std::uint64_t> w, std::span<std::int64_t> out,
                    ApportionScratch& scratch) {
  // Equal weights (a row of unit links): every quotient is floor(T / n) and every remainder the
  // same, so the ties go to the first T mod n items (R1-FOC-010 in closed form; all zero counts
  // every weight as 1, the same shares).
  const auto equal = [&w](std::uint64_t x) { return x == w[0]; };
  if (!w.empty() && out.size() == w.size() && total < (std::uint64_t{1} << 63) && std::all_of(w.begin(), w.end(), equal)) {
    const std::uint64_t q = total / w.size(), extra = total % w.size();
    for (std::size_t i = 0; i < w.size(); ++i) out[i] = static_cast<std::int64_t>(q + (i < extra ? 1 : 0));
    return;
  }
  if (w.size() >= kFastFrom && out.size() == w.size() && total < (std::uint64_t{1} << 63)) {
    u128 sum = 0;
    for (const std::uint64_t x : w) sum += x;
    if (fast_apportion(total, w, out, sum, scratch)) return;
  }
  apportion_into_plain(total, w, out, scratch);
}

}  // namespace focus

std::vector<std::int64_t> apportion(std::uint64_t total, std::span<const std::uint64_t> weights) {
  std::vector<std::int64_t> out(weights.size());
  focus::ApportionScratch scratch;
  focus::apportion_into(total, weights, out, scratch);
  return out;
}

namespace {
void check_simplex_size(std::size_t n, const char* what) {
  // One raw of 2^32 for each entry must fit: n = 2^32 would leave nothing to distribute and no
  // room for positivity beyond it.
  if (n == 0 || n >= (std::size_t{1} << 32)) throw std::invalid_argument(std::string(what) + ": need 1 <= n < 2^32 entries");
}
}  // namespace

namespace focus {
void project_onto(std::span<const Q32> v, std::uint64_t total, std::span<Q32> out) {
  const std::size_t n = v.size();
  if (n == 0 || out.size() != n || total < n || total > (std::uint64_t{1} << 32))
    throw std::invalid_argument("project_onto: need 1 <= entries <= total <= 2^32");
  // Reserve the floor of one raw per entry first (R1-FOC-051), then share out the rest in
  // proportion to each entry's excess over that floor.
  const std::uint64_t rest = total - n;
  std::vector<std::uint64_t> excess(n);
  for (std::size_t i = 0; i < n; ++i) excess[i] = v[i].raw > 1 ? static_cast<std::uint64_t>(v[i].raw) - 1 : 0;
  std::vector<std::int64_t> share(n);
  ApportionScratch scratch;
  apportion_into(rest, excess, share, scratch);
  for (std::size_t i = 0; i < n; ++i) out[i] = Q32::from_raw(share[i] + 1);
}
}  // namespace focus

std::vector<Q32> project_to_simplex_q32(std::span<const Q32> v) {
  check_simplex_size(v.size(), "project_to_simplex_q32");
  std::vector<Q32> out(v.size());
  focus::project_onto(v, std::uint64_t{1} << 32, out);
  return out;
}

std::vector<double> project_to_simplex_f64(std::span<const double> v) {
  check_simplex_size(v.size(), "project_to_simplex_f64");
  // The same floor as the Q32 domain: one raw, 2^-32 (R1-FOC-053).
  constexpr double kFloor = 0x1p-32;
  std::vector<double> x(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (!std::isfinite(v[i])) throw std::invalid_argument("project_to_simplex_f64: non-finite value at " + std::to_string(i));
    x[i] = v[i] > kFloor ? v[i] : kFloor;
  }
  const double s = fx::pairwise_sum(x);
  for (double& e : x) e /= s;
  return x;
}

Result<std::vector<Q32>> simplex_from_f64(std::span<const double> phi) {
  if (phi.empty()) return Status::input("simplex_from_f64: empty phi");
  if (phi.size() >= (std::size_t{1} << 32)) return Status::input("simplex_from_f64: 2^32 or more entries");
  std::vector<Q32> q(phi.size());
  for (std::size_t i = 0; i < phi.size(); ++i) {
    const auto r = Q32::checked_from_double(phi[i]);
    if (!r) return Status::input("simplex_from_f64: phi[" + std::to_string(i) + "] is not a finite Q32 value");
    q[i] = *r;
  }
  return project_to_simplex_q32(q);
}

}  // namespace r1
