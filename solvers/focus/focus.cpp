// Focus driver: parameter checks, kappa and T(eps), the coupled tri-kernel iteration in Q32 and
// fp64, cyberank and syntropy (R1-FOC-001..003, R1-FOC-012, R1-FOC-050, R1-FOC-060..072, R1-FOC-083).
#include "r1/solvers/focus.hpp"

#include <algorithm>
#include <deque>
#include <cmath>
#include <new>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <string>

#include "focus_operators.hpp"
#include "apportion.hpp"
#include "heat_kernel.hpp"
#include "r1/fixedpoint/elementary.hpp"
#include "r1/fixedpoint/exact_sum.hpp"
#include "r1/fixedpoint/pairwise.hpp"

namespace r1 {

namespace {

constexpr std::int64_t kOneRaw = Q32::kOneRaw;
// max_steps above this is a typo, not a plan: 10^5 steps of a 10^7-link graph take days.
constexpr std::uint32_t kMaxStepsLimit = 100000;
constexpr std::uint32_t kDegreeLimit = 32;              // R1-FOC-002: higher c_k round to 0
constexpr std::int64_t kTauLimitRaw = std::int64_t{64} << 32;  // R1-FOC-002: cost ceil(tau/2) K products

Status bad_param(const std::string& name, Q32 value, const std::string& range) {
  return Status::input("focus: " + name + " = " + value.to_string() + " must lie in " + range);
}

bool in_unit(Q32 q) { return q.raw >= 0 && q.raw <= kOneRaw; }

Status validate_lambda2(double lambda2) {
  // The normalized Laplacian's spectrum lies in [0, 2]; NaN fails both comparisons.
  if (!(lambda2 >= 0.0 && lambda2 <= 2.0))
    return Status::input("focus: lambda2 = " + std::to_string(lambda2) + " must be a number in [0, 2]");
  return Status::ok();
}

// ln n = fx::log(n / 2^k) + k ln 2 with the smallest k that brings n / 2^k below 2^31 (Q32 range);
// n / 2^k is the exact raw n << (32 - k) (R1-FOC-071).
Q32 log_count(std::uint32_t n) {
  std::int64_t k = 0;
  while ((static_cast<std::uint64_t>(n) >> k) >= (std::uint64_t{1} << 31)) ++k;
  const Q32 scaled = Q32::from_raw(static_cast<std::int64_t>(static_cast<std::uint64_t>(n) << (32 - k)));
  return fx::log(scaled) + Q32::from_raw(fx::kLn2.raw * k);
}

// The first min(n, kCyberankPlaces) particle indices by phi descending, ties to the lower index:
// a strict total order, so the places are unique (R1-FOC-070).
template <class Key>
std::vector<std::uint32_t> rank_by(std::span<const Key> key) {
  std::vector<std::uint32_t> order(key.size());
  std::iota(order.begin(), order.end(), 0u);
  const auto places = static_cast<std::ptrdiff_t>(std::min<std::size_t>(key.size(), kCyberankPlaces));
  std::partial_sort(order.begin(), order.begin() + places, order.end(), [&key](std::uint32_t a, std::uint32_t b) {
    return key[a] != key[b] ? key[b] < key[a] : a < b;
  });
  order.resize(static_cast<std::size_t>(places));
  return order;
}

// The same places for Q32 phi (raws 1..2^32, as every focus holds): one 64-bit key per particle,
// (2^32 - raw) above the index, the smallest keys kept in a max-heap of the places, so one pass
// over phi and no array of n.
std::vector<std::uint32_t> rank_by(std::span<const Q32> phi) {
  constexpr std::int64_t kTop = std::int64_t{1} << 32;
  const std::size_t places = std::min<std::size_t>(phi.size(), kCyberankPlaces);
  std::vector<std::uint64_t> heap;
  heap.reserve(places);
  for (std::size_t i = 0; i < phi.size(); ++i) {
    if (phi[i].raw < 1 || phi[i].raw > kTop) return rank_by<Q32>(phi);
    const std::uint64_t key = (static_cast<std::uint64_t>(kTop - phi[i].raw) << 32) | i;
    if (heap.size() < places) {
      heap.push_back(key);
      std::push_heap(heap.begin(), heap.end());
    } else if (key < heap.front()) {
      std::pop_heap(heap.begin(), heap.end());
      heap.back() = key;
      std::push_heap(heap.begin(), heap.end());
    }
  }
  std::sort_heap(heap.begin(), heap.end());
  std::vector<std::uint32_t> order(heap.size());
  for (std::size_t k = 0; k < heap.size(); ++k) order[k] = static_cast<std::uint32_t>(heap[k]);
  return order;
}

// sum_i phi_log_phi(phi_i), exact: the terms on the row threads, the sum in one order.
fx::ExactSum plogp_of(std::span<const Q32> phi, bool parallel) {
  const auto n = static_cast<std::uint32_t>(phi.size());
  std::vector<i128> terms(n);
  focus::for_rows(parallel, n, [&](std::uint32_t b, std::uint32_t e) {
    for (std::uint32_t i = b; i < e; ++i) terms[i] = phi_log_phi(phi[i]);
  });
  fx::ExactSum s;
  for (const i128 t : terms) s.add_term(t);
  return s;
}

// Runs a stage body and turns the exceptions a numeric path can raise into Status values
// (R1-FOC-003, R1-ERR-004).
template <class F>
auto guarded(const F& body) -> decltype(body()) {
  try {
    return body();
  } catch (const fx::OverflowError& e) {
    return Status::internal(std::string("focus: Q32 overflow: ") + e.what());
  } catch (const fx::DomainError& e) {
    return Status::internal(std::string("focus: Q32 domain error: ") + e.what());
  } catch (const std::invalid_argument& e) {
    return Status::internal(std::string("focus: ") + e.what());
  } catch (const std::bad_alloc&) {
    return Status::internal("focus: out of memory");
  } catch (const focus::ProductError& e) {
    return Status::internal(std::string("focus: ") + e.what());
  }
}

template <class Scalar>
Focus<Scalar> make_result(std::vector<Scalar> phi, const FocusPlan& plan) {
  Focus<Scalar> f;
  f.phi = std::move(phi);
  f.steps = plan.steps;
  f.kappa = plan.kappa.to_double();
  f.lambda_max = plan.norm_l;
  return f;
}

}  // namespace

std::vector<std::uint32_t> cyberank_places(std::span<const Q32> phi) { return rank_by(phi); }

i128 phi_log_phi(Q32 x) { return x.raw < 1 ? 0 : static_cast<i128>(x.raw) * fx::log(x).raw; }

Status validate_tri_kernel_params(const TriKernelParams& p) {
  if (!in_unit(p.lambda_d)) return bad_param("lambda_d", p.lambda_d, "[0, 1]");
  if (!in_unit(p.lambda_s)) return bad_param("lambda_s", p.lambda_s, "[0, 1]");
  if (!in_unit(p.lambda_h)) return bad_param("lambda_h", p.lambda_h, "[0, 1]");
  // Exactly 1: the combination is convex with no tolerance to argue about (R1-FOC-002).
  if (p.lambda_d.raw + p.lambda_s.raw + p.lambda_h.raw != kOneRaw)
    return Status::input("focus: lambda_d + lambda_s + lambda_h = " +
                         Q32::from_raw(p.lambda_d.raw + p.lambda_s.raw + p.lambda_h.raw).to_string() +
                         " must be exactly 1");
  if (!in_unit(p.teleport)) return bad_param("teleport", p.teleport, "[0, 1]");
  if (p.mu.raw <= 0) return bad_param("mu", p.mu, "(0, 2^31)");
  if (p.tau.raw <= 0 || p.tau.raw > kTauLimitRaw) return bad_param("tau", p.tau, "(0, 64]");
  if (p.eps.raw <= 0 || p.eps.raw >= kOneRaw) return bad_param("eps", p.eps, "(0, 1)");
  if (p.max_steps < 1 || p.max_steps > kMaxStepsLimit)
    return Status::input("focus: max_steps = " + std::to_string(p.max_steps) + " must lie in [1, 100000]");
  if (p.chebyshev_degree < 1 || p.chebyshev_degree > kDegreeLimit)
    return Status::input("focus: chebyshev_degree = " + std::to_string(p.chebyshev_degree) + " must lie in [1, 32]");
  return Status::ok();
}

std::uint32_t steps_for_kappa(Q32 kappa, Q32 eps, std::uint32_t max_steps) {
  if (kappa.raw >= kOneRaw) return max_steps;  // no contraction to count on
  if (kappa.raw <= 0) return 1;                // one step reaches the fixed point
  const Q32 a = fx::log2(eps), b = fx::log2(kappa);
  if (b.raw >= 0) return max_steps;  // kappa within an ulp of 1: log2 rounds to 0
  if (a.raw >= 0) return 1;
  // Exact ceiling of a.raw / b.raw, both negative (R1-FOC-061); |a.raw| <= 32 * 2^32.
  const std::uint64_t num = static_cast<std::uint64_t>(-a.raw), den = static_cast<std::uint64_t>(-b.raw);
  const std::uint64_t t = (num + den - 1) / den;
  return static_cast<std::uint32_t>(std::clamp<std::uint64_t>(t, 1, max_steps));
}

Result<FocusPlan> plan_focus_steps(const Graph& g, const TriKernelParams& p, double lambda2) {
  R1_TRY(validate_tri_kernel_params(p));
  R1_TRY(validate_lambda2(lambda2));
  if (g.n == 0 || g.degree.size() != g.n) return Status::input("focus: the graph has no particles or no degrees");
  return guarded([&]() -> Result<FocusPlan> {
    const std::uint64_t max_degree = g.summarised() ? g.max_degree : *std::max_element(g.degree.begin(), g.degree.end());
    // ||L|| = 2 max d: the Gershgorin bound on the combinatorial Laplacian (R1-FOC-060).
    const i128 norm_l = 2 * static_cast<i128>(max_degree);
    const Q32 term_d = p.lambda_d * (Q32::one() - p.teleport);
    const Q32 term_s = Q32::from_raw(static_cast<std::int64_t>(
        fx::detail::rne_div(static_cast<i128>(p.lambda_s.raw) * norm_l, norm_l + p.mu.raw)));
    const Q32 term_h = p.lambda_h * fx::exp(-(p.tau * Q32::from_double(lambda2)));
    FocusPlan plan;
    plan.kappa = term_d + term_s + term_h;
    plan.norm_l = static_cast<double>(static_cast<u128>(norm_l)) * 0x1p-32;  // one rounding, exact scaling
    plan.steps = steps_for_kappa(plan.kappa, p.eps, p.max_steps);
    return plan;
  });
}

namespace {

// How many iterates before the current one a repeat is looked for among (R1-FOC-093): periods up
// to this are found. Speed only.
constexpr std::size_t kRepeatWindow = 16;

// A fingerprint of x's first `active` raws (wrapping sums of raw times an odd weight per index):
// equal vectors have equal fingerprints; the converse is checked entry by entry.
std::uint64_t fingerprint(const std::vector<Q32>& x, std::uint32_t active) {
  std::uint64_t h = 0;
  for (std::uint32_t i = 0; i < active; ++i)
    h += static_cast<std::uint64_t>(x[i].raw) * ((std::uint64_t{i} << 1) * 0x9E3779B97F4A7C15u + 1);
  return h;
}

// The tri-kernel steps (R1-FOC-050, R1-INC-051): `steps` times v = l_d D + l_s S + l_h H on the
// first `active` entries of phi, then Proj onto `total` raws there; entries from `active` on stay.
// `heat_offset` (empty, or one raw per active entry) is added exactly to the heat term (R1-INC-052).
//
// R1-FOC-093: a step reads phi (and the fixed operators, parameters and offset) and nothing else,
// so once an iterate x_(t+1) equals an earlier x_m, the iterates from m on repeat with period
// t + 1 - m, and x_steps is the kept x_(m + (steps - m) mod (t + 1 - m)): with `stop_at_repeat`
// the remaining steps are not run. Q32 iterates settle into such a cycle once the contraction
// leaves only the projection's last-raw ties moving (BA 10^5: period 2 from step 36; BA 300:
// period 6 from step 36; BA 10^6: period 2 from step 79).
void run_steps_q32(const focus::OperatorsQ32& ops, const TriKernelParams& p, std::uint32_t steps, std::uint32_t active,
                   std::uint64_t total, bool parallel, bool stop_at_repeat, std::vector<Q32>& phi,
                   const ProgressFn& progress, const std::vector<std::int64_t>& heat_offset = {}) {
  const bool use_d = p.lambda_d.raw != 0, use_s = p.lambda_s.raw != 0, use_h = p.lambda_h.raw != 0;
  const HeatCoefficients heat = use_h ? heat_coefficients(p.tau, p.chebyshev_degree) : HeatCoefficients{};
  const bool offset = !heat_offset.empty();
  std::vector<Q32> d, s, h, v(active), walk;
  focus::HeatScratch scratch;
  // The springs and the heat kernel's first product N phi gather phi over the same rows: one pass
  // serves both (R1-FOC-090) where the heat kernel has a first product.
  const bool together = use_s && use_h && heat.q32.size() > 1 && !ops.on_products();
  // The iterates before phi (oldest first) with their indices and fingerprints; the next iterate
  // is projected into `next`. Every vector holds phi's entries from `active` on, which no step
  // changes.
  struct Kept {
    std::uint32_t index;
    std::uint64_t print;
    std::vector<Q32> x;
  };
  std::deque<Kept> kept;
  std::vector<Q32> next;
  std::uint64_t phi_print = 0;
  if (stop_at_repeat) {
    next = phi;
    phi_print = fingerprint(phi, active);
  }
  const auto same = [&](const std::vector<Q32>& a, const std::vector<Q32>& b) {
    return std::equal(a.begin(), a.begin() + active, b.begin(), [](Q32 x, Q32 y) { return x.raw == y.raw; });
  };
  for (std::uint32_t step = 0; step < steps; ++step) {
    // A zero-weight operator contributes exactly 0 and is skipped (R1-FOC-050).
    if (use_d) ops.diffusion(phi, d);
    if (together) {
      ops.springs_and_walk(phi, s, walk);
      focus::heat_q32(ops, heat, phi, h, &scratch, &walk);
    } else {
      if (use_s) ops.springs(phi, s);
      if (use_h) focus::heat_q32(ops, heat, phi, h, &scratch);
    }
    focus::for_rows(parallel, active, [&](std::uint32_t b, std::uint32_t e) {
      for (std::uint32_t i = b; i < e; ++i) {
        i128 acc = 0;  // three products below 2^96: exact
        if (use_d) acc += static_cast<i128>(p.lambda_d.raw) * d[i].raw;
        if (use_s) acc += static_cast<i128>(p.lambda_s.raw) * s[i].raw;
        if (use_h) acc += static_cast<i128>(p.lambda_h.raw) * (offset ? i128{h[i].raw} + heat_offset[i] : i128{h[i].raw});
        v[i] = Q32::from_raw(focus::round_q32(acc));
      }
    });
    if (!stop_at_repeat) {
      focus::project_onto(v, total, std::span<Q32>(phi).first(active));
      report(progress, "focus", step + 1, steps);
      continue;
    }
    focus::project_onto(v, total, std::span<Q32>(next).first(active));
    const std::uint64_t print = fingerprint(next, active);
    // The latest m <= step with x_m = x_(step + 1) (the shortest period): phi is x_step, the kept
    // ones come before it.
    std::optional<std::uint32_t> m;
    if (print == phi_print && same(next, phi)) m = step;
    for (auto it = kept.rbegin(); !m && it != kept.rend(); ++it)
      if (it->print == print && same(next, it->x)) m = it->index;
    if (m) {
      const std::uint32_t at = *m + (steps - *m) % (step + 1 - *m);  // x_steps = x_at, m <= at <= step
      if (at != step)
        for (Kept& k : kept)
          if (k.index == at) phi.swap(k.x);
      report(progress, "focus", steps, steps);
      return;
    }
    std::vector<Q32> spare;
    if (kept.size() == kRepeatWindow) {
      spare = std::move(kept.front().x);
      kept.pop_front();
    } else {
      spare = phi;  // a fresh vector with phi's fixed entries
    }
    kept.push_back({step, phi_print, std::move(phi)});
    phi = std::move(next);
    next = std::move(spare);
    phi_print = print;
    report(progress, "focus", step + 1, steps);
  }
}

// The places after a local update (R1-FOC-072): when the start's places hold no particle of the
// region, every other particle has the start's phi and ranked below all of them, so it still does
// and the places are among the start's and the region's; else one pass over phi.
std::vector<std::uint32_t> places_after(std::span<const Q32> phi, const std::vector<std::uint32_t>& start_places,
                                        std::span<const std::uint32_t> region) {
  const std::size_t places = std::min<std::size_t>(phi.size(), kCyberankPlaces);
  bool local = start_places.size() == places && places < phi.size();
  for (std::size_t k = 0; local && k < places; ++k)
    local = start_places[k] < phi.size() && !std::binary_search(region.begin(), region.end(), start_places[k]);
  if (!local) return rank_by(phi);
  std::vector<std::uint32_t> order(start_places);
  order.insert(order.end(), region.begin(), region.end());
  std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(places), order.end(),
                    [&phi](std::uint32_t a, std::uint32_t b) { return phi[a] != phi[b] ? phi[b] < phi[a] : a < b; });
  order.resize(places);
  return order;
}

// Syntropy RNE(sum phi_i ln phi_i + ln n), an exact sum (R1-FOC-071), from `plogp` when the
// caller has it (R1-INC-054), and cyberank (R1-FOC-070; from the start's places after a local
// update, R1-FOC-072).
Focus<Q32> finish_q32(std::vector<Q32> phi, const FocusPlan& plan, bool parallel,
                      const std::optional<fx::ExactSum>& plogp = std::nullopt,
                      const std::vector<std::uint32_t>* start_places = nullptr, std::span<const std::uint32_t> region = {}) {
  const auto n = static_cast<std::uint32_t>(phi.size());
  fx::ExactSum j = plogp ? *plogp : plogp_of(phi, parallel);
  Focus<Q32> f = make_result(std::move(phi), plan);
  f.plogp = j;
  j.add(log_count(n));
  f.syntropy = j.round().to_double();
  f.cyberank = start_places != nullptr ? places_after(f.phi, *start_places, region) : rank_by(std::span<const Q32>(f.phi));
  f.on_simplex = true;
  return f;
}

}  // namespace

Result<Focus<Q32>> compute_focus_q32(const Graph& g, const TriKernelParams& p, double lambda2,
                                     const ProgressFn& progress, const FocusOptions& options) {
  return guarded([&]() -> Result<Focus<Q32>> {
    R1_ASSIGN(const FocusPlan plan, plan_focus_steps(g, p, lambda2));
    R1_ASSIGN(auto ops, focus::OperatorsQ32::build(g, p, options.parallel));
    if (options.products) R1_TRY(ops.use_products(options.products));
    std::vector<Q32> phi = project_to_simplex_q32(ops.prior());  // R1-FOC-012
    run_steps_q32(ops, p, plan.steps, g.n, std::uint64_t{1} << 32, options.parallel, options.stop_at_repeat, phi, progress);
    // The heat term of the result, which the next incremental epoch starts from (R1-INC-052).
    std::vector<Q32> heat;
    if (p.lambda_h.raw != 0) focus::heat_q32(ops, heat_coefficients(p.tau, p.chebyshev_degree), phi, heat);
    Focus<Q32> f = finish_q32(std::move(phi), plan, options.parallel);
    f.heat = std::move(heat);
    return f;
  });
}

Result<std::vector<Q32>> heat_term_q32(const Graph& g, const TriKernelParams& p, std::span<const Q32> x, const FocusOptions& options) {
  return guarded([&]() -> Result<std::vector<Q32>> {
    if (x.size() != g.n) return Status::input("heat term: " + std::to_string(x.size()) + " values for " + std::to_string(g.n) + " particles");
    R1_ASSIGN(auto ops, focus::OperatorsQ32::build(g, p, options.parallel));
    if (options.products) R1_TRY(ops.use_products(options.products));
    std::vector<Q32> heat;
    focus::heat_q32(ops, heat_coefficients(p.tau, p.chebyshev_degree), x, heat);
    return heat;
  });
}

Result<Focus<Q32>> update_focus_q32(const Graph& g, const TriKernelParams& p, double lambda2, Focus<Q32> start,
                                    std::span<const std::uint32_t> region, const ProgressFn& progress,
                                    const FocusOptions& options) {
  return guarded([&]() -> Result<Focus<Q32>> {
    R1_ASSIGN(const FocusPlan plan, plan_focus_steps(g, p, lambda2));
    if (start.phi.size() != g.n)
      return Status::input("focus update: " + std::to_string(start.phi.size()) + " start values for " + std::to_string(g.n) + " particles");
    const bool use_h = p.lambda_h.raw != 0;
    if (use_h && start.heat.size() != g.n)
      return Status::input("focus update: " + std::to_string(start.heat.size()) + " start heat values for " + std::to_string(g.n) +
                           " particles");
    for (std::size_t a = 0; a < region.size(); ++a)
      if (region[a] >= g.n || (a > 0 && region[a] <= region[a - 1]))
        return Status::input("focus update: region entry " + std::to_string(a) + " out of range or out of order");
    std::vector<Q32> phi = std::move(start.phi);
    // The frozen particles keep their raws (each at least 1); the region holds the rest of 2^32
    // (R1-INC-051). A start known to be on the simplex holds 2^32 with every raw at least 1;
    // otherwise one pass over phi with no array beside it: the raws of at least 1 and the count of
    // the others. Then the region's taken out.
    u128 frozen = 0;
    std::uint64_t below = 0;
    if (start.on_simplex) {
      frozen = u128{1} << 32;
    } else {
      for (const Q32 x : phi) {
        if (x.raw < 1) ++below;
        else frozen += static_cast<std::uint64_t>(x.raw);
      }
    }
    for (const std::uint32_t i : region) {
      if (phi[i].raw < 1) --below;
      else frozen -= static_cast<std::uint64_t>(phi[i].raw);
    }
    if (below != 0)
      for (std::uint32_t i = 0; i < g.n; ++i)
        if (phi[i].raw < 1 && !std::binary_search(region.begin(), region.end(), i))
          return Status::input("focus update: frozen particle " + std::to_string(i) + " has phi raw " + std::to_string(phi[i].raw) + " < 1");
    const u128 one = u128{1} << 32;
    if (frozen + region.size() > one)
      return Status::input("focus update: the frozen particles hold " + std::to_string(static_cast<std::uint64_t>(frozen)) +
                           " raws, leaving fewer than one for each of the region's " + std::to_string(region.size()) + " particles");
    const auto total = static_cast<std::uint64_t>(one - frozen);
    // No region (an empty edit batch): nothing moves; the start must already be a focus.
    if (region.empty()) {
      if (total != 0)
        return Status::input("focus update: no region, and the start sums to " + std::to_string(static_cast<std::uint64_t>(frozen)) +
                             " raws, not 2^32");
      Focus<Q32> f = finish_q32(std::move(phi), plan, options.parallel, start.plogp, &start.cyberank, region);
      if (use_h) f.heat = std::move(start.heat);
      return f;
    }
    std::vector<std::uint32_t> global;
    R1_ASSIGN(const auto ops, focus::OperatorsQ32::build_local(g, p, options.parallel, region, phi, global));
    std::vector<Q32> x(global.size());
    for (std::size_t a = 0; a < global.size(); ++a) x[a] = phi[global[a]];
    const auto active = static_cast<std::uint32_t>(region.size());
    // The start's sum of phi ln phi without the region's terms (R1-INC-054).
    std::optional<fx::ExactSum> plogp = start.plogp;
    if (plogp)
      for (std::uint32_t a = 0; a < active; ++a) plogp->add_term(-phi_log_phi(x[a]));
    // The heat term (R1-INC-052): inside the region's ring the walk runs on, beyond it the start
    // holds. The ring stands in for the rest of the graph as fixed points, which the start is not,
    // so the step uses start_heat + H_local(x) - H_local(start): the carried heat at the start
    // (exact when start_heat is the heat of the start on this graph) and first order in x - start.
    std::vector<std::int64_t> heat_offset;
    const HeatCoefficients heat = use_h ? heat_coefficients(p.tau, p.chebyshev_degree) : HeatCoefficients{};
    if (use_h) {
      std::vector<Q32> hl;
      focus::heat_q32(ops, heat, x, hl);
      heat_offset.resize(active);
      for (std::uint32_t a = 0; a < active; ++a) {
        const i128 d = i128{start.heat[global[a]].raw} - hl[a].raw;
        if (!fx::detail::fits_i64(d)) return Status::input("focus update: start heat of particle " + std::to_string(global[a]) + " out of range");
        heat_offset[a] = static_cast<std::int64_t>(d);
      }
    }
    // The start on R, projected onto the region's share (the identity when it already holds it).
    std::vector<Q32> first(x.begin(), x.begin() + active);
    focus::project_onto(first, total, std::span<Q32>(x).first(active));
    run_steps_q32(ops, p, plan.steps, active, total, options.parallel, options.stop_at_repeat, x, progress, heat_offset);
    for (std::uint32_t a = 0; a < active; ++a) phi[global[a]] = x[a];
    if (plogp)
      for (std::uint32_t a = 0; a < active; ++a) plogp->add_term(phi_log_phi(x[a]));
    // The result's heat: the carried one, and on the region the step's term at the result.
    std::vector<Q32> result_heat;
    if (use_h) {
      result_heat = std::move(start.heat);
      std::vector<Q32> hl;
      focus::heat_q32(ops, heat, x, hl);
      for (std::uint32_t a = 0; a < active; ++a) {
        const i128 v = i128{hl[a].raw} + heat_offset[a];
        if (!fx::detail::fits_i64(v)) return Status::internal("focus update: the heat term leaves the Q32 range");
        result_heat[global[a]] = Q32::from_raw(static_cast<std::int64_t>(v));
      }
    }
    Focus<Q32> f = finish_q32(std::move(phi), plan, options.parallel, plogp, &start.cyberank, region);
    f.heat = std::move(result_heat);
    return f;
  });
}

Result<Focus<double>> compute_focus_f64(const Graph& g, const TriKernelParams& p, double lambda2,
                                        const ProgressFn& progress, const FocusOptions& options) {
  return guarded([&]() -> Result<Focus<double>> {
    R1_ASSIGN(const FocusPlan plan, plan_focus_steps(g, p, lambda2));
    R1_ASSIGN(const auto ops, focus::OperatorsF64::build(g, p, options.parallel));
    const std::uint32_t n = g.n;
    const bool use_d = p.lambda_d.raw != 0, use_s = p.lambda_s.raw != 0, use_h = p.lambda_h.raw != 0;
    const double ld = p.lambda_d.to_double(), ls = p.lambda_s.to_double(), lh = p.lambda_h.to_double();
    const HeatCoefficients heat = use_h ? heat_coefficients(p.tau, p.chebyshev_degree) : HeatCoefficients{};
    std::vector<double> phi = project_to_simplex_f64(ops.prior());
    std::vector<double> d, s, h, v(n);
    for (std::uint32_t step = 0; step < plan.steps; ++step) {
      if (use_d) ops.diffusion(phi, d);
      if (use_s) ops.springs(phi, s);
      if (use_h) focus::heat_f64(ops, heat, phi, h);
      focus::for_rows(options.parallel, n, [&](std::uint32_t b, std::uint32_t e) {
        for (std::uint32_t i = b; i < e; ++i) {
          // (l_d D + l_s S) + l_h H, left to right over the evaluated terms (R1-FOC-082).
          double acc = 0.0;
          bool first = true;
          const auto add = [&](double term) {
            acc = first ? term : acc + term;
            first = false;
          };
          if (use_d) add(ld * d[i]);
          if (use_s) add(ls * s[i]);
          if (use_h) add(lh * h[i]);
          v[i] = acc;
        }
      });
      phi = project_to_simplex_f64(v);
      report(progress, "focus", step + 1, plan.steps);
    }
    // Syntropy: pairwise sum of phi_i ln phi_i with the Q32 logarithm, plus ln n (R1-FOC-083).
    std::vector<double> terms(n);
    focus::for_rows(options.parallel, n, [&](std::uint32_t b, std::uint32_t e) {
      for (std::uint32_t i = b; i < e; ++i) {
        const Q32 q = std::max(Q32::from_double(phi[i]), Q32::epsilon());  // log needs >= 1 raw
        terms[i] = phi[i] * fx::log(q).to_double();
      }
    });
    const double syntropy = fx::pairwise_sum(terms) + log_count(n).to_double();
    Focus<double> f = make_result(std::move(phi), plan);
    f.syntropy = syntropy;
    f.cyberank = rank_by(std::span<const double>(f.phi));
    return f;
  });
}

}  // namespace r1
