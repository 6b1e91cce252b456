// The crystal-genesis-like default graph: 5040 particles in 21 domains, typed and sized, with
// community structure by domain and triad and a spanning backbone (R1-GEN-040..046).
#include <array>

#include "gen_internal.hpp"

namespace r1::gen {

namespace {

constexpr std::uint32_t kDomains = 21;
constexpr std::uint32_t kPerDomain = 240;  // the crystal's axiom: 240 particles per domain
constexpr std::uint32_t kNodes = kDomains * kPerDomain;
static_assert(kDomains == kCrystalDomains.size());

// The 21-slot type pattern: smooth weighted round robin over the shares 10:4:3:2:1:1 (each step
// every type gains its share, the type with the most credit, lowest index on ties, is chosen and
// pays 21). It spreads every type evenly, so each domain's 240-slot window holds every type within
// one of its exact share (R1-GEN-041).
constexpr std::array<std::uint8_t, 21> type_pattern() {
  std::array<std::uint8_t, 21> out{};
  std::array<int, 6> credit{};
  for (std::size_t s = 0; s < out.size(); ++s) {
    std::size_t best = 0;
    for (std::size_t t = 0; t < credit.size(); ++t) {
      credit[t] += kCrystalTypeShares[t];
      if (credit[t] > credit[best]) best = t;  // strict: ties keep the lowest index
    }
    credit[best] -= 21;
    out[s] = static_cast<std::uint8_t>(best);
  }
  return out;
}
constexpr std::array<std::uint8_t, 21> kTypePattern = type_pattern();
static_assert(kTypePattern == std::array<std::uint8_t, 21>{0, 1, 0, 2, 3, 0, 0, 1, 4, 0, 2, 0, 5, 0, 1, 0, 3, 0, 2, 1, 0});

// Size shares atom:enzyme:bridge:article:deep = 8:5:4:2:1 (of 20): most pages are short, a few
// are deep (R1-GEN-042).
constexpr std::array<std::uint32_t, 5> kSizeShares = {8, 5, 4, 2, 1};

// Decision numbers c in pair_dim(c, j) and the per-node dimensions (R1-GEN-008).
constexpr std::uint64_t kDimLink = 0, kDimOrient = 1, kDimValence = 2, kDimAmount = 3;
constexpr std::uint64_t kDimParent = pair_dim(4, 0), kDimSize = pair_dim(5, 0);

// Node i is position q = i / 21 of domain d = i % 21 (see node_table): interleaving the domains
// spreads each of them along the particle order, so the anchor set covers all 21 evenly.
std::uint32_t domain_of(std::uint32_t i) { return i % kDomains; }

struct NodeInfo {
  CrystalTag tag;
  std::uint32_t k = 0;       // 1-based number among the domain's particles of this type
  std::uint32_t parent = 0;  // backbone parent (node 0: itself)
};

std::vector<NodeInfo> node_table(std::uint64_t seed) {
  std::vector<NodeInfo> t(kNodes);
  std::array<std::array<std::uint32_t, 6>, kDomains> seen{};
  // Position order within each domain, so the type numbers k count up along q.
  for (std::uint32_t q = 0; q < kPerDomain; ++q) {
    for (std::uint32_t d = 0; d < kDomains; ++d) {
      const std::uint32_t i = q * kDomains + d;
      NodeInfo& x = t[i];
      // The 5040 slots in domain-major order walk the pattern exactly 240 times, so the totals
      // are exactly 2400/960/720/480/240/240.
      x.tag.type = kTypePattern[(d * kPerDomain + q) % 21];
      x.tag.domain = static_cast<std::uint8_t>(d);
      x.k = ++seen[d][x.tag.type];
      std::uint32_t u = static_cast<std::uint32_t>(rng::uniform_below(seed, i, kDimSize, 20));
      std::uint8_t size = 0;
      while (u >= kSizeShares[size]) u -= kSizeShares[size++];
      x.tag.size = size;
      if (q > 0) {
        // Random recursive tree inside the domain: a uniformly chosen earlier position.
        x.parent = static_cast<std::uint32_t>(rng::uniform_below(seed, i, kDimParent, q)) * kDomains + d;
      } else if (d == 0) {
        x.parent = 0;  // the root
      } else {
        // Domain hubs (q = 0): chain the three hubs of a triad, and each triad's first hub to the
        // previous triad's first hub. With the trees this spans all 5040 nodes: connected.
        x.parent = d % 3 != 0 ? d - 1 : d - 3;
      }
    }
  }
  return t;
}

std::string capitalised(std::string_view s) {
  std::string out(s);
  // ASCII only, no locale: domain names are lower-case ASCII.
  if (!out.empty() && out[0] >= 'a' && out[0] <= 'z') out[0] = static_cast<char>(out[0] - 'a' + 'A');
  return out;
}

}  // namespace

Result<Snapshot> gen_crystal(const Resolved& p, std::string card, const ProgressFn& progress) {
  const std::vector<NodeInfo> nodes = node_table(p.seed);
  const std::uint64_t t_domain = prob_threshold(p.p_in), t_triad = prob_threshold(p.p_triad),
                      t_out = prob_threshold(p.p_out);
  // Backbone pairs are always linked; every other pair by its class's probability.
  const auto accept = [&](std::uint32_t i, std::uint32_t j) {
    if (nodes[j].parent == i) return true;  // j > i >= 0, so never the root's self-parent
    const std::uint32_t di = domain_of(i), dj = domain_of(j);
    const std::uint64_t t = di == dj ? t_domain : di / 3 == dj / 3 ? t_triad : t_out;
    return bernoulli(p.seed, i, pair_dim(kDimLink, j), t);
  };
  const std::vector<Edge> edges = sample_pairs(kNodes, accept, progress, "generating crystal");

  Emitter e("gen:crystal", kNodes, [&nodes](std::uint32_t i) {
    const CrystalTag& c = nodes[i].tag;
    return "crystal/" + std::string(kCrystalDomains[c.domain]) + "/" + std::string(kCrystalTypes[c.type]) + "/" +
           std::to_string(nodes[i].k);
  });
  e.reserve_links(edges.size());
  for (const Edge& x : edges) {
    const std::uint64_t i = x.a, j = x.b;
    // Direction by a fair coin: crystal pages link both ways.
    const bool flip = rng::uniform_below(p.seed, i, pair_dim(kDimOrient, j), 2) == 1;
    // Valence: -1 with 1/20, 0 with 2/20, +1 with 17/20 (mostly agreement, some neutral and
    // contradicting links).
    const std::uint64_t v = rng::uniform_below(p.seed, i, pair_dim(kDimValence, j), 20);
    const std::int8_t valence = v == 0 ? -1 : v <= 2 ? 0 : 1;
    // Weight uniform in {0.25, 0.5, ..., 2.0}: amount = 2^30 * (1 + uniform_below(8)).
    const u128 amount = (u128{1} << 30) * (1 + rng::uniform_below(p.seed, i, pair_dim(kDimAmount, j), 8));
    if (flip) {
      e.link(x.b, x.a, amount, valence);
    } else {
      e.link(x.a, x.b, amount, valence);
    }
  }
  const std::vector<std::uint32_t> node_of = e.node_of_particle();
  R1_ASSIGN(Snapshot s, e.finish(std::move(card), progress));
  s.titles.resize(node_of.size());
  s.crystal.resize(node_of.size());
  for (std::size_t k = 0; k < node_of.size(); ++k) {
    const NodeInfo& x = nodes[node_of[k]];
    s.titles[k] = capitalised(kCrystalDomains[x.tag.domain]) + " " + std::string(kCrystalTypes[x.tag.type]) + " " +
                  std::to_string(x.k);
    s.crystal[k] = x.tag;
  }
  return s;
}

}  // namespace r1::gen
