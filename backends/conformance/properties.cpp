// The property library for backend authors (R1-TEST-050..053; 12, 15): six RapidCheck
// properties of a candidate backend against the reference on random small graphs and views.
#include "r1/conformance/properties.hpp"

#include <rapidcheck.h>
#include <rapidcheck/detail/Configuration.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <map>
#include <memory>
#include <sstream>
#include <unordered_map>
#include <utility>

#include "r1/backends/registry.hpp"
#include "r1/conformance/compare.hpp"
#include "r1/reference/generate.hpp"
#include "r1/reference/graph_build.hpp"
#include "r1/reference/hierarchy.hpp"
#include "render/image.hpp"
#include "render/image_diff.hpp"
#include "render/view.hpp"

namespace r1::conformance {

namespace {

using rc::detail::CaseResult;

// The seed when neither the options nor RC_PARAMS name one: fixed, so that a backend author's
// test sees the same graphs on every run and a failure reproduces ("R1PROP" in ASCII, then 1).
constexpr std::uint64_t kDefaultSeed = 0x5231'5052'4F50'0001;

// names no tolerance for focus between backends. A backend that does not promise
// deterministic FixedQ32 may differ from the reference's phi by at most this total variation
// distance (half the L1 distance of two distributions): the 0.1 % of 12.2's position bound,
// far above the ~2^-32 per particle by which an fp64 focus rounds differently from the Q32 one.
constexpr double kFocusBound = 1e-3;

// The generated views (R-1.0 15.3's viewpoints, drawn at random instead of a fixed set):
// eye 1500..6000 scene units from a target within 300 of the origin, so the whole R_scene = 1000
// layout or a good part of it is in the frame; elevation within 80 degrees of the horizon, so the
// up vector +y is never parallel to the view direction; fov 40..70 degrees.
constexpr int kEyeDistanceMin = 1500, kEyeDistanceMax = 6000;
constexpr int kTargetRadiusMax = 300;
constexpr int kElevationMaxDeg = 80;
constexpr int kFovMinTenths = 400, kFovMaxTenths = 700;
// The largest image side a view may have (render::validate_view).
constexpr int kMaxImageSide = 16384;

// Smallest graph the generators are asked for: a ring needs 3 nodes, an sbm or rgg of 4 usually
// keeps a link. A torus needs sides of at least 3 (27 nodes); below that it becomes a ring.
constexpr std::int64_t kMinParticles = 4;
constexpr std::int64_t kTorusMinNodes = 27;

// ---- generated inputs ------------------------------------------------------------------------

// One generated graph: the `r1 gen` parameters (shown as the command that reproduces it).
struct GraphCase {
  GenParams params;
};

void showValue(const GraphCase& c, std::ostream& os) {
  auto line = gen_command_line(c.params);
  os << (line.is_ok() ? *line : "invalid gen parameters: " + line.status().message());
}

// One generated view: the camera and its description.
struct ViewCase {
  render::View view;
  render::Vec3 eye, target;
};

void showValue(const ViewCase& c, std::ostream& os) {
  // + 0.0 turns a -0 (from rounding a zero radius or angle) into 0 for display.
  const auto xyz = [&os](const render::Vec3& v) {
    os << "(" << v.x + 0.0 << ", " << v.y + 0.0 << ", " << v.z + 0.0 << ")";
  };
  os << "eye ";
  xyz(c.eye);
  os << " looking at ";
  xyz(c.target);
  os << ", fov " << c.view.camera.fov_deg << " deg, " << c.view.width << "x" << c.view.height;
}

}  // namespace
}  // namespace r1::conformance

// RapidCheck titles each value of a counterexample with its type: "graph" and "view" read
// better than the C++ names.
namespace rc {
template <>
struct ShowType<r1::conformance::GraphCase> {
  static void showType(std::ostream& os) { os << "graph"; }
};
template <>
struct ShowType<r1::conformance::ViewCase> {
  static void showType(std::ostream& os) { os << "view"; }
};
}  // namespace rc

namespace r1::conformance {
namespace {

// A random small graph of one of the kinds ring, path, star, grid, torus, sbm, ba, rgg, with at
// most `max_n` nodes and a random generator seed. Sizes grow with RapidCheck's size parameter.
rc::Gen<GraphCase> gen_graph_case(std::int64_t max_n) {
  return rc::gen::exec([max_n] {
    GraphCase c;
    GenParams& p = c.params;
    p.kind = *rc::gen::element(GenKind::kRing, GenKind::kPath, GenKind::kStar, GenKind::kGrid, GenKind::kTorus,
                               GenKind::kSbm, GenKind::kBa, GenKind::kRgg);
    p.seed = *rc::gen::inRange<std::uint64_t>(1, std::uint64_t{1} << 32);
    const auto upto = [](std::int64_t lo, std::int64_t hi) { return *rc::gen::inRange<std::int64_t>(lo, hi + 1); };
    if (p.kind == GenKind::kTorus && max_n < kTorusMinNodes) p.kind = GenKind::kRing;
    switch (p.kind) {
      case GenKind::kRing: p.n = upto(3, max_n); break;
      case GenKind::kPath:
      case GenKind::kStar: p.n = upto(2, max_n); break;
      case GenKind::kGrid: {
        const std::int64_t w = upto(1, max_n / 2);
        p.dims = {w, upto(w == 1 ? 2 : 1, max_n / w)};
        break;
      }
      case GenKind::kTorus: {
        const std::int64_t a = upto(3, max_n / 9);
        const std::int64_t b = upto(3, max_n / (3 * a));
        p.dims = {a, b, upto(3, max_n / (a * b))};
        break;
      }
      case GenKind::kSbm:
        p.n = upto(kMinParticles, max_n);
        p.k = upto(1, 4);
        p.p_in = static_cast<double>(upto(30, 90)) / 100.0;
        p.p_out = static_cast<double>(upto(0, 10)) / 100.0;
        break;
      case GenKind::kBa:
        p.n = upto(3, max_n);
        p.m = upto(1, std::min<std::int64_t>(4, *p.n - 1));
        break;
      case GenKind::kRgg:
        p.n = upto(kMinParticles, max_n);
        p.radius = static_cast<double>(upto(20, 80)) / 100.0;
        break;
      default: break;
    }
    return c;
  });
}

rc::Gen<ViewCase> gen_view_case(int width, int height) {
  return rc::gen::exec([width, height] {
    const auto deg = [](int tenths) { return static_cast<double>(tenths) / 10.0 * render::kPi / 180.0; };
    const auto unit = [](double az, double el) {
      return render::Vec3{std::cos(el) * std::cos(az), std::sin(el), std::cos(el) * std::sin(az)};
    };
    ViewCase c;
    const double target_r = *rc::gen::inRange(0, kTargetRadiusMax + 1);
    const double target_az = deg(*rc::gen::inRange(0, 3600)), target_el = deg(*rc::gen::inRange(-900, 901));
    c.target = unit(target_az, target_el) * target_r;
    const double dist = *rc::gen::inRange(kEyeDistanceMin, kEyeDistanceMax + 1);
    const double eye_az = deg(*rc::gen::inRange(0, 3600));
    const double eye_el = deg(*rc::gen::inRange(-10 * kElevationMaxDeg, 10 * kElevationMaxDeg + 1));
    c.eye = c.target + unit(eye_az, eye_el) * dist;
    c.view.width = width;
    c.view.height = height;
    c.view.camera.position = c.eye;
    c.view.camera.fov_deg = static_cast<double>(*rc::gen::inRange(kFovMinTenths, kFovMaxTenths + 1)) / 10.0;
    auto q = render::look_at(c.eye, c.target, {0, 1, 0});
    if (!q.is_ok()) throw CaseResult(CaseResult::Type::Discard, "look_at: " + q.status().message());
    c.view.camera.orientation = *q;
    return c;
  });
}

// ---- the cases' epochs, computed once per check_backend call ---------------------------------

struct CaseData {
  Status input;  // generate or build_graph failed: the case is discarded
  Result<Epoch> got = Status::internal("not run");
  Result<Epoch> want = Status::internal("not run");
};

class CaseCache {
 public:
  CaseCache(backends::Backend& candidate, backends::Backend& reference)
      : candidate_(candidate), reference_(reference) {}

  // The case of `params`, its epochs run through both backends on first use.
  const CaseData& get(const GenParams& params) {
    auto key = gen_command_line(params);
    const std::string k = key.is_ok() ? *key : "invalid: " + key.status().message();
    if (auto it = cases_.find(k); it != cases_.end()) return *it->second;
    auto c = std::make_unique<CaseData>();
    c->input = run(params, *c);
    return *cases_.emplace(k, std::move(c)).first->second;
  }

 private:
  backends::Backend& candidate_;
  backends::Backend& reference_;
  std::map<std::string, std::unique_ptr<CaseData>> cases_;

  // Generates the graph and runs both epochs; the error when there is no graph.
  Status run(const GenParams& params, CaseData& c) {
    R1_ASSIGN(const Snapshot snapshot, generate(params));
    R1_ASSIGN(const Graph graph, build_graph(snapshot));
    c.got = backends::run_epoch(candidate_, snapshot, graph, {});
    c.want = backends::run_epoch(reference_, snapshot, graph, {});
    return Status::ok();
  }
};

[[noreturn]] void fail_case(std::string why) { throw CaseResult(CaseResult::Type::Failure, std::move(why)); }

// The case's epochs (candidate, reference). Ends the case when they cannot be compared: a
// generator or graph error discards it, both epochs failing is agreement (success), one failing
// is a failure that says which.
std::pair<const Epoch*, const Epoch*> epochs_of(const CaseData& c) {
  if (!c.input.is_ok()) throw CaseResult(CaseResult::Type::Discard, "no graph: " + c.input.message());
  const bool got = c.got.is_ok(), want = c.want.is_ok();
  if (got && want) return {&*c.got, &*c.want};
  if (!got && !want) throw CaseResult(CaseResult::Type::Success, "both epochs failed");
  if (!got) fail_case("the candidate's epoch failed where the reference's succeeded: " + c.got.status().message());
  fail_case("the candidate's epoch succeeded where the reference's failed: " + c.want.status().message());
}

// The backend promises the reference's bits (R-1.0 13.1: deterministic mode in the canonical
// domain), so positions and focus must match exactly rather than within their bounds.
bool promises_bits(const backends::Backend& b) {
  return b.deterministic_mode() && b.numeric_domain() == backends::Domain::kFixedQ32;
}

std::string num(double v) {
  std::ostringstream os;
  os.precision(3);
  os << v;
  return os.str();
}

// ---- the six properties ----------------------------------------------------------------------

void check_topology(const Epoch& got, const Epoch& want) {
  if (topology_bytes(got.hierarchy) == topology_bytes(want.hierarchy)) return;
  const std::string why = topology_difference(got.hierarchy, want.hierarchy);
  fail_case("topology differs from the reference (R-1.0 15.1): " + (why.empty() ? "topology bytes differ" : why));
}

void check_positions(const Epoch& got, const Epoch& want, bool exact, double& max_dev) {
  auto dev = position_deviation(got.frame.position, want.frame.position);
  if (!dev.is_ok()) fail_case("positions: " + dev.status().message());
  max_dev = std::max(max_dev, dev->max_over_r);
  const std::string where =
      "max deviation " + num(dev->max_over_r) + " R_scene at particle " + std::to_string(dev->worst);
  if (exact && got.frame.position != want.frame.position)
    fail_case("positions are not bit-exact although the backend promises deterministic FixedQ32: " + where);
  if (dev->max_over_r > kPositionBound)
    fail_case("positions: " + where + ", above the bound " + num(kPositionBound) + " R_scene (R-1.0 15.2)");
}

void check_focus(const Epoch& got, const Epoch& want, bool exact, double& max_tv) {
  const auto& phi = got.focus.phi;
  if (phi.size() != want.focus.phi.size())
    fail_case("focus: " + std::to_string(phi.size()) + " values, expected " + std::to_string(want.focus.phi.size()));
  constexpr std::int64_t kOne = std::int64_t{1} << 32;
  std::int64_t sum = 0;
  for (std::size_t p = 0; p < phi.size(); ++p) {
    // Each raw in (0, 2^32] keeps the running sum of at most 2^31 of them inside int64.
    if (phi[p].raw <= 0 || phi[p].raw > kOne)
      fail_case("focus: particle " + std::to_string(p) + " has phi raw " + std::to_string(phi[p].raw) +
                ", outside (0, 2^32]");
    sum += phi[p].raw;
  }
  if (sum != kOne) fail_case("focus: phi raws sum to " + std::to_string(sum) + ", not exactly 2^32");
  double tv = 0;
  std::size_t worst = 0;
  std::int64_t worst_diff = 0;
  for (std::size_t p = 0; p < phi.size(); ++p) {
    const std::int64_t d = phi[p].raw - want.focus.phi[p].raw;
    tv += std::fabs(static_cast<double>(d)) / static_cast<double>(kOne) / 2.0;
    if (std::abs(d) > std::abs(worst_diff)) worst = p, worst_diff = d;
  }
  max_tv = std::max(max_tv, tv);
  const std::string where = "total variation " + num(tv) + " from the reference's phi, largest at particle " +
                            std::to_string(worst) + " (" + std::to_string(worst_diff) + " raw)";
  if (exact && tv > 0)
    fail_case("focus is not bit-exact although the backend promises deterministic FixedQ32: " + where);
  if (tv > kFocusBound) fail_case("focus: " + where + ", above " + num(kFocusBound));
}

void check_labels(const Epoch& got) {
  const Status s = check_hierarchy(got.hierarchy, got.frame.position, got.focus.phi, got.encoding.color, got.ids);
  if (!s.is_ok()) fail_case("canonical labels (R1-HIER-040..043): " + s.message());
}

// The candidate's tree nests (R1-HIER-002, R1-HIER-015) and its clusters, as sets of particles,
// are the reference's up to their ids.
void check_nesting(const Epoch& got, const Epoch& want) {
  // No owner yet (the value ClusterNode uses for "no parent").
  constexpr std::uint32_t kNone = 0xFFFFFFFFu;
  const Hierarchy& h = got.hierarchy;
  const std::size_t n = got.ids.size();
  const auto at = [](int l) { return "level " + std::to_string(l) + ": "; };
  const auto item = [](int l, std::size_t k) { return (l == 0 ? "particle " : "cluster ") + std::to_string(k); };
  for (int l = 0; l < kLevels; ++l)
    if (h.cluster_of[l].size() != n)
      fail_case(at(l) + "cluster_of names " + std::to_string(h.cluster_of[l].size()) + " particles, expected " +
                std::to_string(n));
  for (int l = 0; l < kLevels; ++l) {
    const auto& nodes = h.levels[l];
    const std::size_t below = l == 0 ? n : h.levels[l - 1].size();
    // Every item below (particle or level l-1 cluster) is the child of exactly one node.
    std::vector<std::uint32_t> owner(below, kNone);
    for (std::size_t c = 0; c < nodes.size(); ++c) {
      const std::string node = at(l) + "cluster " + std::to_string(c);
      if (nodes[c].children.size() > static_cast<std::size_t>(kMaxChildren))
        fail_case(node + " has " + std::to_string(nodes[c].children.size()) + " children, more than " +
                  std::to_string(kMaxChildren));
      for (std::uint32_t k : nodes[c].children) {
        if (k >= below) fail_case(node + " names child " + std::to_string(k) + " of " + std::to_string(below));
        if (owner[k] != kNone)
          fail_case(at(l) + item(l, k) + " is a child of clusters " + std::to_string(owner[k]) + " and " +
                    std::to_string(c));
        owner[k] = static_cast<std::uint32_t>(c);
      }
    }
    for (std::size_t k = 0; k < below; ++k) {
      if (owner[k] == kNone) fail_case(at(l) + item(l, k) + " is in no cluster");
      const std::uint32_t listed = l == 0 ? h.cluster_of[0][k] : h.levels[l - 1][k].parent;
      if (listed != owner[k])
        fail_case(at(l) + item(l, k) + " is a child of cluster " + std::to_string(owner[k]) + " but names " +
                  std::to_string(listed));
    }
    for (std::size_t p = 0; p < n; ++p) {
      const std::uint32_t c = h.cluster_of[l][p];
      if (c >= nodes.size())
        fail_case(at(l) + item(0, p) + " is in cluster " + std::to_string(c) + " of " + std::to_string(nodes.size()));
      if (l + 1 < kLevels && nodes[c].parent != h.cluster_of[l + 1][p])
        fail_case(at(l) + item(0, p) + ": the parent of its cluster " + std::to_string(c) + " is " +
                  std::to_string(nodes[c].parent) + ", its level " + std::to_string(l + 1) + " cluster is " +
                  std::to_string(h.cluster_of[l + 1][p]));
    }
  }
  // The same nested partitions as the reference: cluster ids correspond one to one.
  if (want.hierarchy.cluster_of[0].size() != n) fail_case("the reference's hierarchy has other particles");
  for (int l = 0; l < kLevels; ++l) {
    std::map<std::uint32_t, std::size_t> first_in_got, first_in_want;  // cluster -> its first particle
    for (std::size_t p = 0; p < n; ++p) {
      const auto a = first_in_got.emplace(h.cluster_of[l][p], p).first->second;
      const auto b = first_in_want.emplace(want.hierarchy.cluster_of[l][p], p).first->second;
      if (a != b) {
        const std::size_t q = std::min(a, b);
        fail_case(at(l) + "particles " + std::to_string(q) + " and " + std::to_string(p) +
                  (a == q ? " share a cluster, the reference's clusters part them"
                          : " are in different clusters, the reference's share one"));
      }
    }
  }
}

// Renders `epoch` through `b` and returns its display bytes over the view's background.
Result<std::vector<std::uint8_t>> display_bytes(backends::Backend& b, const Epoch& epoch, const render::View& view) {
  render::RenderOptions options;
  options.timings = false;
  R1_ASSIGN(const render::Image image, b.render(epoch, view, options, nullptr, {}));
  if (image.width != view.width || image.height != view.height ||
      image.rgba.size() != static_cast<std::size_t>(view.width) * static_cast<std::size_t>(view.height) * 4)
    return Status::internal("rendered a " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                            " image, expected " + std::to_string(view.width) + "x" + std::to_string(view.height));
  std::array<float, 3> background{};
  for (int i = 0; i < 3; ++i) background[i] = render::srgb8_to_linear(view.background[i]);
  return render::display_srgb8(image, background);
}

void check_pixels(backends::Backend& candidate, backends::Backend& reference, const Epoch& got, const Epoch& want,
                  const render::View& view, double& max_mean) {
  auto a = display_bytes(candidate, got, view);
  if (!a.is_ok()) fail_case("pixels: the candidate's frame: " + a.status().message());
  auto b = display_bytes(reference, want, view);
  if (!b.is_ok()) fail_case("pixels: the reference's frame: " + b.status().message());
  const render::DiffStats d = render::diff_srgb8(*a, *b, view.width, view.height, render::DiffOptions{}, nullptr);
  max_mean = std::max(max_mean, d.mean_2000);
  if (d.mean_2000 > kPixelBound)
    fail_case("pixels: mean CIEDE2000 " + num(d.mean_2000) + " against the reference's frame, above " +
              num(kPixelBound) + " (R-1.0 15.3); max " + num(d.max_2000) + " at (" + std::to_string(d.max_x) + ", " +
              std::to_string(d.max_y) + ")");
}

// ---- running a property ----------------------------------------------------------------------

// Receives RapidCheck's events and prints nothing: the outcome goes into PropertyResult.
class SilentListener final : public rc::detail::TestListener {
 public:
  void onTestCaseFinished(const rc::detail::CaseDescription&) override {}
  void onShrinkTried(const rc::detail::CaseDescription&, bool) override {}
  void onTestFinished(const rc::detail::TestMetadata&, const rc::detail::TestResult&) override {}
};

// The seed of this run: the options', else RC_PARAMS's, else kDefaultSeed. A malformed RC_PARAMS
// is an input error.
Result<std::uint64_t> choose_seed(std::uint64_t requested) {
  if (requested != 0) return requested;
  const char* env = std::getenv("RC_PARAMS");
  if (env == nullptr || *env == '\0') return kDefaultSeed;
  rc::detail::Configuration defaults;
  defaults.testParams.seed = kDefaultSeed;
  try {
    return rc::detail::configFromString(env, defaults).testParams.seed;
  } catch (const rc::detail::ConfigurationException& e) {
    return Status::input(std::string("RC_PARAMS: ") + e.what());
  }
}

// Runs one property; `summary` describes a pass (cases run, the largest deviation seen).
template <class Fn, class Summary>
PropertyResult run_property(std::string_view name, const rc::detail::TestParams& params, Fn&& fn,
                            const Summary& summary) {
  PropertyResult r;
  r.name = std::string(name);
  rc::detail::TestMetadata metadata;
  metadata.id = r.name;
  metadata.description = r.name;
  SilentListener listener;
  // The overload with a reproduce map: the others read RapidCheck's global configuration, which
  // prints "Using configuration" to stderr on first use.
  const std::unordered_map<std::string, rc::detail::Reproduce> no_reproduce;
  const rc::detail::TestResult result = rc::detail::checkProperty(rc::detail::toProperty(std::forward<Fn>(fn)),
                                                                  metadata, params, listener, no_reproduce);
  r.passed = result.template is<rc::detail::SuccessResult>();
  std::ostringstream os;
  if (r.passed) {
    os << params.maxSuccess << " cases passed" << summary();
  } else {
    rc::detail::printResultMessage(result, os);
  }
  os << " (seed " << params.seed << ")";
  r.message = os.str();
  return r;
}

}  // namespace

std::vector<PropertyResult> check_backend(backends::Backend& candidate, const PropertyOptions& options) {
  std::vector<std::string_view> names{kTopologyProperty, kPositionsProperty, kFocusProperty, kLabelsProperty,
                                      kNestingProperty};
  if (options.pixels) names.push_back(kPixelProperty);
  const auto fail_all = [&names](const std::string& why) {
    std::vector<PropertyResult> out;
    for (auto n : names) out.push_back({std::string(n), false, why});
    return out;
  };
  if (options.tests < 1) return fail_all("PropertyOptions::tests must be at least 1");
  if (options.pixels && (options.image_width < 1 || options.image_height < 1 || options.image_width > kMaxImageSide ||
                         options.image_height > kMaxImageSide))
    return fail_all("PropertyOptions: the image must be 1.." + std::to_string(kMaxImageSide) + " pixels a side");
  auto seed = choose_seed(options.seed);
  if (!seed.is_ok()) return fail_all(seed.status().message());
  auto reference = backends::make_backend("reference");
  if (!reference.is_ok()) return fail_all(reference.status().message());
  backends::Backend& ref = **reference;

  rc::detail::TestParams params;
  params.seed = *seed;
  params.maxSuccess = options.tests;
  const std::int64_t max_n = std::max<std::int64_t>(options.max_particles, kMinParticles);
  CaseCache cache(candidate, ref);
  const bool exact = promises_bits(candidate);
  const auto nothing = [] { return std::string(); };

  std::vector<PropertyResult> out;
  out.push_back(run_property(kTopologyProperty, params, [&] {
    const auto [got, want] = epochs_of(cache.get((*gen_graph_case(max_n)).params));
    check_topology(*got, *want);
  }, nothing));

  double max_dev = 0;
  out.push_back(run_property(kPositionsProperty, params, [&] {
    const auto [got, want] = epochs_of(cache.get((*gen_graph_case(max_n)).params));
    check_positions(*got, *want, exact, max_dev);
  }, [&] {
    return std::string(exact ? ", bit-exact" : "") + "; max deviation " + num(max_dev) + " R_scene (bound " +
           num(kPositionBound) + ")";
  }));

  double max_tv = 0;
  out.push_back(run_property(kFocusProperty, params, [&] {
    const auto [got, want] = epochs_of(cache.get((*gen_graph_case(max_n)).params));
    check_focus(*got, *want, exact, max_tv);
  }, [&] { return "; max total variation from the reference's phi " + num(max_tv); }));

  out.push_back(run_property(kLabelsProperty, params, [&] {
    const auto [got, want] = epochs_of(cache.get((*gen_graph_case(max_n)).params));
    check_labels(*got);
  }, nothing));

  out.push_back(run_property(kNestingProperty, params, [&] {
    const auto [got, want] = epochs_of(cache.get((*gen_graph_case(max_n)).params));
    check_nesting(*got, *want);
  }, nothing));

  if (options.pixels) {
    double max_mean = 0;
    out.push_back(run_property(kPixelProperty, params, [&] {
      const auto [got, want] = epochs_of(cache.get((*gen_graph_case(max_n)).params));
      const ViewCase view = *gen_view_case(options.image_width, options.image_height);
      check_pixels(candidate, ref, *got, *want, view.view, max_mean);
    }, [&] { return "; max mean CIEDE2000 " + num(max_mean) + " (bound " + num(kPixelBound) + ")"; }));
  }
  return out;
}

}  // namespace r1::conformance
