// The encoding stage: radius, luminosity, hue, saturation, base colour, roles and shapes, overlays, serial or parallel (R1-ENC-001..005, R1-ENC-019, R1-ENC-020, R1-ENC-030, R1-ENC-041, R1-ENC-050).
#include <algorithm>
#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "r1/fixedpoint/elementary.hpp"
#include "r1/fixedpoint/exact_sum.hpp"
#include "r1/reference/encoding.hpp"
#include "r1/reference/intern_index.hpp"

namespace r1 {

namespace {

// The schemaless shape of a role (R1-ENC-019).
Shape role_shape(Role r) {
  switch (r) {
    case Role::kBridge: return Shape::kTorus;
    case Role::kLeaf: return Shape::kTetrahedron;
    case Role::kHub:
    case Role::kNone: break;
  }
  return Shape::kSphere;
}

// fn(p) for every particle p in [0, n): on TBB workers when `parallel` (R1-ENC-020). Every fn
// here writes only particle p's own outputs, so any split gives the same values.
template <class Fn>
void for_each_particle(std::size_t n, bool parallel, const Fn& fn) {
  if (!parallel) {
    for (std::size_t p = 0; p < n; ++p) fn(p);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t p = r.begin(); p < r.end(); ++p) fn(p);
  });
}

Status check_inputs(const Snapshot& snapshot, const Graph& graph, const Focus<Q32>& focus, const Spectrum<Q32>& spectrum) {
  const std::size_t n = snapshot.particles.size();
  if (graph.n != n)
    return Status::internal("encoding: the graph has " + std::to_string(graph.n) + " particles, the snapshot " + std::to_string(n));
  if (focus.phi.size() != n)
    return Status::internal("encoding: focus has " + std::to_string(focus.phi.size()) + " entries for " + std::to_string(n) +
                            " particles");
  fx::ExactSum sum;
  for (std::size_t p = 0; p < n; ++p) {
    if (focus.phi[p].raw <= 0) return Status::internal("encoding: focus of particle " + std::to_string(p) + " is not positive");
    sum.add(focus.phi[p]);
  }
  if (sum.checked_round() != Q32::one()) return Status::internal("encoding: focus does not sum to exactly 1");
  for (std::size_t k : {std::size_t{3}, std::size_t{4}})
    if (!spectrum.u[k].empty() && spectrum.u[k].size() != n)
      return Status::internal("encoding: eigenvector u_" + std::to_string(k + 2) + " has " +
                              std::to_string(spectrum.u[k].size()) + " entries for " + std::to_string(n) + " particles");
  return Status::ok();
}

// Each particle's own [particle] entry, resolved by name first, then by 64-hex id (R1-ENC-041).
Result<std::vector<const OverlayStyle*>> resolve_particles(const Snapshot& s, const CustomOverlay& o, const std::string& name) {
  std::vector<const OverlayStyle*> own(s.particles.size(), nullptr);
  std::vector<std::size_t> line(s.particles.size(), 0);
  if (o.particles.empty()) return own;
  const NameIndex by_name = NameIndex::over(s.names);
  const IdIndex by_id = IdIndex::over(s.particles);
  for (const auto& e : o.particles) {
    std::int64_t p = s.names.empty() ? -1 : by_name.find(e.key, s.names);
    ParticleId id;
    if (p < 0 && hemera::from_hex(e.key, id)) p = by_id.find(id, s.particles);
    if (p < 0) continue;  // an overlay may cover many snapshots
    const auto i = static_cast<std::size_t>(p);
    if (own[i])
      return Status::input(name + ":" + std::to_string(std::max(line[i], e.line)) + ": a second entry for particle '" +
                           e.key.substr(0, 80) + "'");
    own[i] = &e.style;
    line[i] = e.line;
  }
  return own;
}

}  // namespace

Q32 radius_of(Q32 phi, Q32 multiplier, std::int64_t r0_squared_raw) {
  // r0^2 phi rounds once (exact when r0^2 is an integer, as R_scene^2 is); phi <= 1 and
  // r0^2 <= R_scene^2 keep it far inside Q32. The root and the product round once each.
  const i128 prod = fx::detail::rne_shift(static_cast<i128>(r0_squared_raw) * phi.raw, Q32::kFracBits);
  const Q32 base = fx::sqrt(Q32::from_raw(static_cast<std::int64_t>(prod)));
  return base * multiplier;
}

std::vector<Q32> apportion_luminosity(std::span<const Q32> phi, Q32 total) {
  const std::size_t n = phi.size();
  std::vector<Q32> out(n);
  std::vector<std::uint32_t> rem(n);
  std::int64_t assigned = 0;
  for (std::size_t p = 0; p < n; ++p) {
    // floor(L0 raw x phi raw / 2^32) and its remainder; phi raws sum to 2^32, so the floors fall
    // short of L0's raw by sum(remainders) / 2^32 < n units (R1-ENC-002).
    const i128 prod = static_cast<i128>(total.raw) * phi[p].raw;
    out[p] = Q32::from_raw(static_cast<std::int64_t>(prod >> 32));
    rem[p] = static_cast<std::uint32_t>(prod & 0xFFFFFFFF);
    assigned += out[p].raw;
  }
  const std::int64_t deficit = total.raw - assigned;
  if (deficit <= 0) return out;
  std::vector<std::uint32_t> idx(n);
  for (std::uint32_t i = 0; i < n; ++i) idx[i] = i;
  // Largest remainder first, ties to the lowest index: a strict total order, so the chosen set
  // does not depend on nth_element's arrangement.
  const auto d = static_cast<std::size_t>(std::min<std::int64_t>(deficit, static_cast<std::int64_t>(n)));
  std::nth_element(idx.begin(), idx.begin() + static_cast<std::ptrdiff_t>(d - 1), idx.end(),
                   [&](std::uint32_t a, std::uint32_t b) { return rem[a] != rem[b] ? rem[a] > rem[b] : a < b; });
  for (std::size_t k = 0; k < d; ++k) out[idx[k]].raw += 1;
  return out;
}

Q32 hue_of(Q32 u5, Q32 u6) {
  // The angle of (u5, u6) in [-pi, pi], then turns: one rounding each (R1-ENC-003).
  const Q32 q = fx::atan2(u6, u5) / fx::kTwoPi;
  return q.raw < 0 ? q + Q32::one() : q;
}

std::vector<Q32> saturation_from_a2(const Graph& g) {
  std::vector<Q32> out(g.n, Q32::one());
  for (std::uint32_t p = 0; p < g.n; ++p) {
    u128 w = 0, pos = 0, neg = 0;
    for (std::uint64_t k = g.row_ptr[p]; k < g.row_ptr[p + 1]; ++k) {
      w += static_cast<std::uint64_t>(g.w[k]);
      if (g.a2[k] > 0) pos += static_cast<std::uint64_t>(g.a2[k]);
      if (g.a2[k] < 0) neg += static_cast<std::uint64_t>(-g.a2[k]);
    }
    if (w == 0) continue;  // no links: nothing disagrees (R1-ENC-004)
    const u128 twice_min = 2 * std::min(pos, neg);
    // P + N <= W holds for every graph r1 builds (|a2| <= w); the clamp only keeps a foreign graph
    // that breaks it at saturation 0 instead of a negative value.
    const u128 num = twice_min >= w ? 0 : w - twice_min;
    out[p] = Q32::from_raw(static_cast<std::int64_t>(fx::detail::rne_div(static_cast<i128>(num << 32), static_cast<i128>(w))));
  }
  return out;
}

Result<Encoding> encode_with_overlay(const Snapshot& snapshot, const Graph& graph, const Focus<Q32>& focus,
                                     const Spectrum<Q32>& spectrum, const EncodingOptions& options,
                                     const CustomOverlay* overlay, EncodingInfo* info, const ProgressFn& progress) {
  R1_TRY(check_inputs(snapshot, graph, focus, spectrum));
  const std::size_t n = snapshot.particles.size();
  try {
    Encoding e;
    e.overlay = overlay ? options.overlay : "none";
    EncodingInfo inf;
    e.luminosity = apportion_luminosity(focus.phi, Q32::one());
    e.saturation = saturation_from_a2(graph);
    e.hue.resize(n);
    e.color.resize(n);
    const auto& u5 = spectrum.u[3];
    const auto& u6 = spectrum.u[4];
    for_each_particle(n, options.parallel, [&](std::size_t p) {
      e.hue[p] = hue_of(u5.empty() ? Q32{} : u5[p], u6.empty() ? Q32{} : u6[p]);
      // 6 x hue in turns is exact: the sixths form hsl_to_srgb8 takes.
      e.color[p] = hsl_to_srgb8(Q32::from_raw(6 * e.hue[p].raw), e.saturation[p], kBaseLightnessPermille);
    });

    e.role.assign(n, Role::kNone);
    e.shape.assign(n, Shape::kSphere);
    if (options.role_shapes) {
      if (options.carried_betweenness) {
        // R1-INC-037: the earlier epoch's values, by particle.
        if (options.carried_betweenness->size() != n)
          return Status::internal("encoding: " + std::to_string(options.carried_betweenness->size()) + " carried betweenness values for " +
                                  std::to_string(n) + " particles");
        e.betweenness = *options.carried_betweenness;
      } else {
        Betweenness b = betweenness(graph, snapshot.particles, options.betweenness, progress, BetweennessRun{options.parallel, true});
        inf.betweenness_exact = b.exact;
        inf.betweenness_sources = b.sources;
        e.betweenness = std::move(b.value);
      }
      e.role = infer_roles(graph, e.betweenness, &inf.roles);
      for (std::size_t p = 0; p < n; ++p) e.shape[p] = role_shape(e.role[p]);
    }

    std::vector<Q32> multiplier(n, Q32::one());
    if (overlay) {
      R1_ASSIGN(const auto own, resolve_particles(snapshot, *overlay, options.custom_name.empty() ? "overlay" : options.custom_name));
      static const CrystalTag kNoTag{};
      for (std::size_t p = 0; p < n; ++p) {
        const CrystalTag& tag = snapshot.crystal.empty() ? kNoTag : snapshot.crystal[p];
        const OverlayStyle st = overlay_style(*overlay, tag, own[p]);
        if (st.shape) e.shape[p] = *st.shape;
        if (st.color) e.color[p] = *st.color;
        if (st.size) multiplier[p] = *st.size;
        if (st.shape || st.color || st.size) ++inf.overlay_particles;
      }
    }
    e.radius.resize(n);
    const std::int64_t r0sq = options.r0_squared_raw.value_or(kSceneR0SquaredRaw);
    if (r0sq <= 0 || r0sq > kSceneR0SquaredRaw)
      return Status::input("encoding: r0^2 raw " + std::to_string(r0sq) + " outside (0, R_scene^2]");
    e.radius_scale = options.r0_squared_raw ? options.radius_scale : "scene";
    e.r0_squared_raw = r0sq;
    for_each_particle(n, options.parallel, [&](std::size_t p) { e.radius[p] = radius_of(focus.phi[p], multiplier[p], r0sq); });
    if (info) *info = inf;
    return e;
  } catch (const std::exception& ex) {
    // fx::OverflowError / DomainError cannot arise from checked inputs; if one does, it is a bug.
    return Status::internal(std::string("encoding: ") + ex.what());
  }
}

Result<Encoding> encode(const Snapshot& snapshot, const Graph& graph, const Focus<Q32>& focus, const Spectrum<Q32>& spectrum,
                        const EncodingOptions& options, EncodingInfo* info, const ProgressFn& progress) {
  if (options.overlay == "none") return encode_with_overlay(snapshot, graph, focus, spectrum, options, nullptr, info, progress);
  if (options.overlay == "crystal-v5")
    return encode_with_overlay(snapshot, graph, focus, spectrum, options, &crystal_v5_overlay(), info, progress);
  if (options.overlay == "custom") {
    // The overlay arrives as a value (R1-BKD-014): the caller read the file.
    if (!options.custom) return Status::input("overlay custom needs an overlay file");
    return encode_with_overlay(snapshot, graph, focus, spectrum, options, options.custom.get(), info, progress);
  }
  return Status::input("unknown overlay '" + options.overlay.substr(0, 80) + "' (none, crystal-v5, custom)");
}

}  // namespace r1
