// `r1 gen` front end: the kinds table, option defaults and limits, validation, the reproducing
// command line and card, dispatch (R1-GEN-001..004).
#include "r1/reference/generate.hpp"

#include <charconv>
#include <cmath>

#include "gen_internal.hpp"

namespace r1 {

namespace {

// Help lines state every default and limit enforced in resolve() below.
constexpr GenKindInfo kKinds[] = {
    {GenKind::kRing, "ring", "cycle: node k links to node k+1 (mod n)", kGenOptN, "--n N (1000; 3..2^24)"},
    {GenKind::kPath, "path", "path: node k links to node k+1", kGenOptN, "--n N (1000; 2..2^24)"},
    {GenKind::kStar, "star", "star: node 0 links to every other node", kGenOptN, "--n N (1000; 2..2^24)"},
    {GenKind::kGrid, "grid", "2D grid, 4-neighbour", kGenOptDims, "--dims WxH (32x32; sides >= 1, 2 <= W*H <= 2^24)"},
    {GenKind::kTorus, "torus", "3D periodic lattice, 6-neighbour (degree 6 everywhere)", kGenOptDims,
     "--dims AxBxC (10x10x10; sides >= 3, A*B*C <= 2^25/3)"},
    {GenKind::kComplete, "complete", "complete graph: every pair linked", kGenOptN, "--n N (100; 2..8192)"},
    {GenKind::kSbm, "sbm", "stochastic block model", kGenOptN | kGenOptK | kGenOptSizes | kGenOptPIn | kGenOptPOut,
     "--n N (1000; 2..50000) --k K (4; blocks of n/k) or --sizes S1,S2,... ; --p-in P (0.1) --p-out P (0.005)"},
    {GenKind::kBa, "ba", "Barabasi-Albert preferential attachment", kGenOptN | kGenOptM,
     "--n N (1000; 2..2^24) --m M (3; 1..n-1 links per new node)"},
    {GenKind::kRgg, "rgg", "random geometric graph in the unit cube (3D)", kGenOptN | kGenOptRadius,
     "--n N (1000; 2..2^24) --radius R (0.15; 0 < R <= 2)"},
    {GenKind::kCrystal, "crystal", "crystal-genesis-like: 5040 particles, 21 domains in 7 triads",
     kGenOptPIn | kGenOptPTriad | kGenOptPOut, "--p-in P (0.05, same domain) --p-triad P (0.008) --p-out P (0.0005)"},
    {GenKind::kRmat, "rmat", "R-MAT (Graph500 a b c = 0.57 0.19 0.19): heavy-tailed, many low-degree nodes",
     kGenOptN | kGenOptM, "--n N (16384; 2..2^24 node ids) --m M (16; 1..1024 links drawn per node id)"},
};

struct OptionName {
  GenOption bit;
  std::string_view name;
};
constexpr OptionName kOptionNames[] = {{kGenOptN, "--n"},           {kGenOptM, "--m"},         {kGenOptK, "--k"},
                                       {kGenOptSizes, "--sizes"},   {kGenOptDims, "--dims"},   {kGenOptPIn, "--p-in"},
                                       {kGenOptPOut, "--p-out"},    {kGenOptPTriad, "--p-triad"},
                                       {kGenOptRadius, "--radius"}};

std::uint32_t options_set(const GenParams& g) {
  std::uint32_t s = 0;
  if (g.n) s |= kGenOptN;
  if (g.m) s |= kGenOptM;
  if (g.k) s |= kGenOptK;
  if (!g.sizes.empty()) s |= kGenOptSizes;
  if (!g.dims.empty()) s |= kGenOptDims;
  if (g.p_in) s |= kGenOptPIn;
  if (g.p_out) s |= kGenOptPOut;
  if (g.p_triad) s |= kGenOptPTriad;
  if (g.radius) s |= kGenOptRadius;
  return s;
}

std::string num(double v) {
  char buf[64];
  // Shortest text that reads back exactly, %g-style: 0.0005 rather than 5e-04.
  const auto r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general);
  return std::string(buf, r.ptr);
}

class Resolver {
 public:
  explicit Resolver(const GenKindInfo& info) : prefix_("gen " + std::string(info.name) + ": ") {}

  Result<std::uint32_t> integer(const std::optional<std::int64_t>& v, std::int64_t def, std::int64_t lo,
                                std::int64_t hi, std::string_view name) const {
    const std::int64_t x = v.value_or(def);
    if (x < lo || x > hi)
      return error(std::string(name) + " must be between " + std::to_string(lo) + " and " + std::to_string(hi) +
                   " (got " + std::to_string(x) + ")");
    return static_cast<std::uint32_t>(x);
  }
  Result<double> probability(const std::optional<double>& v, double def, std::string_view name) const {
    const double p = v.value_or(def);
    if (!(p >= 0.0 && p <= 1.0)) return error(std::string(name) + " must be a probability in [0, 1] (got " + num(p) + ")");
    return p;
  }
  Status error(const std::string& message) const { return Status::input(prefix_ + message); }

 private:
  std::string prefix_;
};

Result<gen::Resolved> resolve_sbm(const GenParams& g, const Resolver& r, gen::Resolved out) {
  if (!g.sizes.empty()) {
    std::int64_t sum = 0;
    for (std::int64_t s : g.sizes) {
      if (s < 1 || s > kGenMaxSbmNodes)
        return r.error("--sizes: every block size must be between 1 and " + std::to_string(kGenMaxSbmNodes) +
                       " (got " + std::to_string(s) + ")");
      sum += s;
      if (sum > kGenMaxSbmNodes)
        return r.error("--sizes add up to more than " + std::to_string(kGenMaxSbmNodes) + " nodes");
      out.sizes.push_back(static_cast<std::uint32_t>(s));
    }
    if (sum < 2) return r.error("--sizes must add up to at least 2 nodes");
    if (g.k && *g.k != static_cast<std::int64_t>(g.sizes.size()))
      return r.error("--k " + std::to_string(*g.k) + " disagrees with the " + std::to_string(g.sizes.size()) +
                     " --sizes given");
    if (g.n && *g.n != sum)
      return r.error("--n " + std::to_string(*g.n) + " disagrees with --sizes, which add up to " + std::to_string(sum));
    out.n = static_cast<std::uint32_t>(sum);
  } else {
    R1_ASSIGN(out.n, r.integer(g.n, 1000, 2, kGenMaxSbmNodes, "--n"));
    R1_ASSIGN(const std::uint32_t k, r.integer(g.k, 4, 1, out.n, "--k"));
    // n/k per block; the first n mod k blocks take one more node.
    for (std::uint32_t b = 0; b < k; ++b) out.sizes.push_back(out.n / k + (b < out.n % k ? 1 : 0));
  }
  R1_ASSIGN(out.p_in, r.probability(g.p_in, 0.1, "--p-in"));
  R1_ASSIGN(out.p_out, r.probability(g.p_out, 0.005, "--p-out"));
  double intra = 0;
  for (std::uint32_t s : out.sizes) intra += 0.5 * s * (s - 1.0);
  const double all = 0.5 * out.n * (out.n - 1.0);
  const double expected = out.p_in * intra + out.p_out * (all - intra);
  if (expected > static_cast<double>(kGenMaxLinks))
    return r.error("about " + std::to_string(static_cast<std::int64_t>(expected)) + " links expected, more than the " +
                   std::to_string(kGenMaxLinks) + " allowed");
  return out;
}

Result<gen::Resolved> resolve(const GenParams& g) {
  const GenKindInfo& info = gen_kind_info(g.kind);
  const Resolver r(info);
  const std::uint32_t stray = options_set(g) & ~info.options;
  for (const auto& o : kOptionNames)
    if (stray & o.bit) return r.error(std::string(o.name) + " does not apply (takes: " + std::string(info.defaults) + ")");
  gen::Resolved out;
  out.kind = g.kind;
  out.seed = g.seed;
  switch (g.kind) {
    case GenKind::kRing: {
      R1_ASSIGN(out.n, r.integer(g.n, 1000, 3, kGenMaxNodes, "--n"));
      break;
    }
    case GenKind::kPath:
    case GenKind::kStar: {
      R1_ASSIGN(out.n, r.integer(g.n, 1000, 2, kGenMaxNodes, "--n"));
      break;
    }
    case GenKind::kComplete: {
      // 8192 * 8191 / 2 is the largest complete graph within kGenMaxLinks.
      R1_ASSIGN(out.n, r.integer(g.n, 100, 2, 8192, "--n"));
      break;
    }
    case GenKind::kGrid:
    case GenKind::kTorus: {
      const bool grid = g.kind == GenKind::kGrid;
      const std::vector<std::int64_t> dims = g.dims.empty() ? std::vector<std::int64_t>(grid ? 2 : 3, grid ? 32 : 10) : g.dims;
      if (dims.size() != (grid ? 2u : 3u)) return r.error(grid ? "--dims must be WxH" : "--dims must be AxBxC");
      // Torus sides >= 3: a side of 2 would link a pair twice, a side of 1 would make self-loops.
      const std::int64_t lo = grid ? 1 : 3;
      // Torus: 3 links per node must stay within kGenMaxLinks.
      const std::int64_t hi = grid ? kGenMaxNodes : kGenMaxLinks / 3;
      std::int64_t product = 1;
      for (std::int64_t d : dims) {
        if (d < lo || d > hi)
          return r.error("--dims: every side must be between " + std::to_string(lo) + " and " + std::to_string(hi) +
                         " (got " + std::to_string(d) + ")");
        product *= d;  // product <= hi before and d <= hi <= 2^25: at most 2^50, no overflow
        if (product > hi) return r.error("--dims: more than " + std::to_string(hi) + " nodes");
        out.dims.push_back(static_cast<std::uint32_t>(d));
      }
      if (product < 2) return r.error("--dims: a grid needs at least 2 nodes");
      out.n = static_cast<std::uint32_t>(product);
      break;
    }
    case GenKind::kSbm:
      return resolve_sbm(g, r, std::move(out));
    case GenKind::kBa: {
      R1_ASSIGN(out.n, r.integer(g.n, 1000, 2, kGenMaxNodes, "--n"));
      R1_ASSIGN(out.m, r.integer(g.m, 3, 1, out.n - 1, "--m"));
      const std::uint64_t links = static_cast<std::uint64_t>(out.m) * (out.m + 1) / 2 +
                                  static_cast<std::uint64_t>(out.n - out.m - 1) * out.m;
      if (links > static_cast<std::uint64_t>(kGenMaxLinks))
        return r.error(std::to_string(links) + " links, more than the " + std::to_string(kGenMaxLinks) + " allowed");
      break;
    }
    case GenKind::kRgg: {
      R1_ASSIGN(out.n, r.integer(g.n, 1000, 2, kGenMaxNodes, "--n"));
      out.radius = g.radius.value_or(0.15);
      // Radius 2 exceeds the cube's diagonal (sqrt 3): every pair is linked; larger adds nothing.
      if (!(out.radius > 0.0 && out.radius <= 2.0))
        return r.error("--radius must be in (0, 2] (got " + num(out.radius) + ")");
      // Expected links ignoring the boundary (an overestimate): pairs * min(1, 4/3 pi r^3).
      const double ball = std::min(1.0, 4.0 / 3.0 * 3.141592653589793 * out.radius * out.radius * out.radius);
      const double expected = 0.5 * out.n * (out.n - 1.0) * ball;
      if (expected > static_cast<double>(kGenMaxLinks))
        return r.error("about " + std::to_string(static_cast<std::int64_t>(expected)) +
                       " links expected, more than the " + std::to_string(kGenMaxLinks) + " allowed");
      break;
    }
    case GenKind::kRmat: {
      R1_ASSIGN(out.n, r.integer(g.n, 16384, 2, kGenMaxNodes, "--n"));
      R1_ASSIGN(out.m, r.integer(g.m, 16, 1, 1024, "--m"));
      const std::uint64_t links = static_cast<std::uint64_t>(out.n) * out.m;
      if (links > static_cast<std::uint64_t>(kGenMaxLinks))
        return r.error(std::to_string(links) + " links, more than the " + std::to_string(kGenMaxLinks) + " allowed");
      break;
    }
    case GenKind::kCrystal: {
      out.n = 5040;
      R1_ASSIGN(out.p_in, r.probability(g.p_in, 0.05, "--p-in"));
      R1_ASSIGN(out.p_triad, r.probability(g.p_triad, 0.008, "--p-triad"));
      R1_ASSIGN(out.p_out, r.probability(g.p_out, 0.0005, "--p-out"));
      break;
    }
  }
  return out;
}

std::string command_line(const gen::Resolved& p) {
  std::string s = "r1 gen " + std::string(gen_kind_info(p.kind).name);
  const auto add = [&s](std::string_view opt, const std::string& v) { s += " " + std::string(opt) + " " + v; };
  const auto list = [](const std::vector<std::uint32_t>& v, char sep) {
    std::string t;
    for (std::size_t i = 0; i < v.size(); ++i) t += (i ? std::string(1, sep) : "") + std::to_string(v[i]);
    return t;
  };
  switch (p.kind) {
    case GenKind::kRing:
    case GenKind::kPath:
    case GenKind::kStar:
    case GenKind::kComplete:
      add("--n", std::to_string(p.n));
      break;
    case GenKind::kGrid:
    case GenKind::kTorus:
      add("--dims", list(p.dims, 'x'));
      break;
    case GenKind::kSbm:
      add("--sizes", list(p.sizes, ','));
      add("--p-in", num(p.p_in));
      add("--p-out", num(p.p_out));
      break;
    case GenKind::kBa:
    case GenKind::kRmat:
      add("--n", std::to_string(p.n));
      add("--m", std::to_string(p.m));
      break;
    case GenKind::kRgg:
      add("--n", std::to_string(p.n));
      add("--radius", num(p.radius));
      break;
    case GenKind::kCrystal:
      add("--p-in", num(p.p_in));
      add("--p-triad", num(p.p_triad));
      add("--p-out", num(p.p_out));
      break;
  }
  add("--seed", std::to_string(p.seed));
  return s;
}

Result<Snapshot> dispatch(const gen::Resolved& p, std::string card, const ProgressFn& progress) {
  switch (p.kind) {
    case GenKind::kRing: return gen::gen_ring(p, std::move(card), progress);
    case GenKind::kPath: return gen::gen_path(p, std::move(card), progress);
    case GenKind::kStar: return gen::gen_star(p, std::move(card), progress);
    case GenKind::kGrid: return gen::gen_grid(p, std::move(card), progress);
    case GenKind::kTorus: return gen::gen_torus(p, std::move(card), progress);
    case GenKind::kComplete: return gen::gen_complete(p, std::move(card), progress);
    case GenKind::kSbm: return gen::gen_sbm(p, std::move(card), progress);
    case GenKind::kBa: return gen::gen_ba(p, std::move(card), progress);
    case GenKind::kRgg: return gen::gen_rgg(p, std::move(card), progress);
    case GenKind::kCrystal: return gen::gen_crystal(p, std::move(card), progress);
    case GenKind::kRmat: return gen::gen_rmat(p, std::move(card), progress);
  }
  return Status::internal("gen: unhandled kind");
}

}  // namespace

std::span<const GenKindInfo> gen_kinds() { return kKinds; }

const GenKindInfo& gen_kind_info(GenKind kind) {
  for (const auto& k : kKinds)
    if (k.kind == kind) return k;
  return kKinds[0];  // unreachable: the table lists every enumerator
}

Result<GenKind> gen_kind_from_name(std::string_view name) {
  for (const auto& k : kKinds)
    if (k.name == name) return k.kind;
  std::string known;
  for (const auto& k : kKinds) known += (known.empty() ? "" : ", ") + std::string(k.name);
  return Status::input("gen: unknown kind '" + std::string(name) + "' (kinds: " + known + ")");
}

std::string gen_help_text() {
  std::string s = "Kinds (every kind also takes --seed S, default 1):\n";
  for (const auto& k : kKinds) {
    std::string name(k.name);
    name.resize(10, ' ');
    s += "  " + name + std::string(k.summary) + "\n" + std::string(12, ' ') + std::string(k.defaults) + "\n";
  }
  return s;
}

Result<std::vector<std::int64_t>> parse_dims(std::string_view text) {
  const Status bad = Status::input("gen: --dims must look like 32x32 or 10x10x10 (got '" + std::string(text) + "')");
  std::vector<std::int64_t> out;
  std::size_t pos = 0;
  while (true) {
    std::size_t end = text.find_first_of("xX,", pos);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view part = text.substr(pos, end - pos);
    if (part.empty() || part.find_first_not_of("0123456789") != std::string_view::npos) return bad;
    std::int64_t v = 0;
    const auto r = std::from_chars(part.data(), part.data() + part.size(), v);
    if (r.ec != std::errc()) return bad;  // out of range
    out.push_back(v);
    if (end == text.size()) break;
    pos = end + 1;
  }
  return out;
}

Result<std::string> gen_command_line(const GenParams& params) {
  R1_ASSIGN(const gen::Resolved p, resolve(params));
  return command_line(p);
}

Result<Snapshot> generate(const GenParams& params, const ProgressFn& progress) {
  R1_ASSIGN(const gen::Resolved p, resolve(params));
  const GenKindInfo& info = gen_kind_info(p.kind);
  std::string card = "# Generated graph: " + std::string(info.name) + "\n\n" + std::string(info.summary) +
                     ".\n\nReproduce with `" + command_line(p) +
                     "`; every generator is defined in r1's spec/generators.md (R1-GEN).\n";
  R1_ASSIGN(Snapshot s, dispatch(p, std::move(card), progress));
  // A snapshot needs at least one link (R1-IN): sbm and rgg can draw none.
  if (s.links.empty())
    return Status::input("gen " + std::string(info.name) + ": no links were generated; raise the probabilities or --radius");
  return s;
}

}  // namespace r1
