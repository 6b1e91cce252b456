// The T-infinity neural field: hash-grid encoding, MLP, deterministic training on the analytic far
// field, and its file (spec/neural.md R1-NRF-001..041).
#include "neural_field.hpp"

#include <tbb/global_control.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <Eigen/Core>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <memory>

#include "r1/fixedpoint/counter_rng.hpp"
#include "r1/fixedpoint/hemera.hpp"
#include "r1/format/bytes.hpp"
#include "r1/reference/clifford.hpp"

namespace r1::render {

namespace {

constexpr std::uint32_t kPrime1 = 2654435761u, kPrime2 = 805459861u;  // Mueller et al.'s hash
constexpr std::uint32_t kChunk = 64;  // samples per gradient chunk: the fixed reduction order
constexpr double kPointMass = 1.0;  // sigma_hi / the scene's extent about its centroid (R1-NRF-001)
// The prior's exp limit (R1-NRF-007): a part with q above it adds 0 (it weighs under 1e-217 of its
// mass). libm's exp takes a slower path from |x| = 512 on (scaling near the underflow).
constexpr double kPriorExpLimit = 500.0;
constexpr double kCellsPerSigma = 0.5;  // finest level: a cell per two sigma_min (R1-NRF-002)
constexpr std::uint32_t kPriorCells = 4;  // the prior's grid: cells per side of the particles' box (R1-NRF-007)
constexpr std::uint64_t kDataSeed = 0x6e72662d64617461u;  // "nrf-data": the training set's draws (R1-NRF-010)
constexpr double kLrFinal = 0.1;  // the Adam steps decay geometrically to this fraction of the first (R1-NRF-011)

// The entry of grid corner (x, y, z) at a level of `res` cells per side (R1-NRF-002): dense when
// the (res + 1)^3 corners fit the table, else the spatial hash.
std::uint32_t corner_index(std::uint32_t x, std::uint32_t y, std::uint32_t z, std::uint32_t res, std::uint32_t table) {
  const std::uint64_t side = std::uint64_t{res} + 1;
  if (side * side * side <= table) return static_cast<std::uint32_t>(x + side * (y + side * z));
  return (x ^ (y * kPrime1) ^ (z * kPrime2)) & (table - 1);
}

// Where a point falls at every level (R1-NRF-002), in arrays the caller owns: `index` levels x 8
// absolute offsets into the grid (entry * 2), `weight` levels x 8 trilinear weights, `mask`
// levels fades of the levels finer than the kernel. It depends on the query only, so training
// locates each sample once.
struct Location {
  std::uint32_t* index;
  float* weight;
  float* mask;
};

double sigmoid(double x) { return 1.0 / (1.0 + std::exp(-x)); }

// The network's input: the cube coordinates of x and the tau feature (R1-NRF-003).
struct Query {
  double u[3];
  double t;      // log2(tau / tau_lo) / log2(tau_hi / tau_lo), clamped to [0, 1]
  double sigma;  // sqrt(tau) after the clamp, in cube units (size 1)
};

Query make_query(const NeuralField& f, const Vec3& x_in, double sigma) {
  Query q;
  // Kernels wider than the trained range see the scene as one mass at its centroid: the field at
  // (x, sigma) is the field at (c + (x - c) sigma_hi / sigma, sigma_hi), an exact similarity for a
  // point mass (R1-NRF-005).
  Vec3 x = x_in;
  if (sigma * sigma > f.tau_hi) x = f.centroid + (x_in - f.centroid) * (std::sqrt(f.tau_hi) / sigma);
  const double p[3] = {x.x, x.y, x.z}, l[3] = {f.lo.x, f.lo.y, f.lo.z};
  for (int k = 0; k < 3; ++k) q.u[k] = std::clamp((p[k] - l[k]) / f.size, 0.0, 1.0);
  const double tau = std::clamp(sigma * sigma, f.tau_lo, f.tau_hi);
  q.t = f.tau_hi > f.tau_lo ? std::log2(tau / f.tau_lo) / std::log2(f.tau_hi / f.tau_lo) : 0.0;
  q.sigma = std::sqrt(tau) / f.size;
  return q;
}

void locate(const NeuralField& f, const Query& q, const Location& e) {
  const std::uint32_t L = f.config.levels, table = 1u << f.config.log2_table;
  for (std::uint32_t l = 0; l < L; ++l) {
    const std::uint32_t res = f.resolution[l];
    std::uint32_t i0[3];
    double fr[3];
    for (int k = 0; k < 3; ++k) {
      const double p = q.u[k] * res;
      const double fl = std::min(std::floor(p), static_cast<double>(res - 1));
      i0[k] = static_cast<std::uint32_t>(fl);
      fr[k] = p - fl;
    }
    for (std::uint32_t c = 0; c < 8; ++c) {
      const std::uint32_t dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
      const double w = (dx ? fr[0] : 1 - fr[0]) * (dy ? fr[1] : 1 - fr[1]) * (dz ? fr[2] : 1 - fr[2]);
      e.index[l * 8 + c] = (l * table + corner_index(i0[0] + dx, i0[1] + dy, i0[2] + dz, res, table)) * kNeuralFeatures;
      e.weight[l * 8 + c] = static_cast<float>(w);
    }
    // Levels finer than the kernel fade out (R1-NRF-002): weight min(1, (2 h / sigma)^4) for cells
    // of side h, so a wide kernel reads only the coarse levels that can hold its smooth field.
    const double fade = 2.0 / (res * q.sigma);
    const double fade2 = fade * fade;
    e.mask[l] = static_cast<float>(std::min(1.0, f.fade_power == 2 ? fade2 : fade2 * fade2));
  }
}

// The network's input row: each level's two features, trilinear over its corners and faded, then
// the tau feature.
void gather(const NeuralField& f, const Location& e, double t, float* features) {
  const std::uint32_t L = f.config.levels;
  for (std::uint32_t l = 0; l < L; ++l) {
    float a = 0, b = 0;
    for (std::uint32_t c = 0; c < 8; ++c) {
      const float w = e.weight[l * 8 + c];
      const std::uint32_t idx = e.index[l * 8 + c];
      a += w * f.grid[idx];
      b += w * f.grid[idx + 1];
    }
    features[2 * l] = e.mask[l] * a;
    features[2 * l + 1] = e.mask[l] * b;
  }
  features[2 * L] = static_cast<float>(t);
}

using Mat = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using Row = Eigen::Matrix<float, 1, Eigen::Dynamic>;

// The Clifford render block's nonlinearities (R1-NRF-003): r1's SiLU and sigmoid (R1-RND-101, on
// det_exp) in double, rounded to float, so a device that repeats det_exp gets the same bits.
float silu_f(float x) { return static_cast<float>(clifford::silu(static_cast<double>(x))); }
float sigmoid_f(float x) { return static_cast<float>(clifford::sigmoid(static_cast<double>(x))); }

// The block's features of one row (R1-NRF-003; clifford::shifted_inner and shifted_wedge): for
// the k-th shift s of kNeuralShifts, Inner_s at [2 k d, 2 k d + d) and Wedge_s at [2 k d + d,
// 2 k d + 2 d), with j = (ch + s) mod d: Inner_s(ch) = SiLU(h[ch] c[j]) and
// Wedge_s(ch) = h[ch] c[j] - h[j] c[ch], each product rounded to float. `sig`, when given, gets
// sigmoid(h[ch] c[j]) at [k d + ch] (what training's backward pass needs).
void clifford_features(const float* h, const float* c, std::uint32_t d, float* F, float* sig = nullptr) {
  for (std::size_t k = 0; k < kNeuralShifts.size(); ++k) {
    const auto s = static_cast<std::uint32_t>(kNeuralShifts[k]) % d;
    float* inner = F + 2 * k * d;
    float* wedge = inner + d;
    for (std::uint32_t ch = 0; ch < d; ++ch) {
      const std::uint32_t j = ch + s < d ? ch + s : ch + s - d;
      const float p = h[ch] * c[j];
      const float q = h[j] * c[ch];
      const double e = clifford::det_exp(-static_cast<double>(p));
      inner[ch] = static_cast<float>(static_cast<double>(p) / (1.0 + e));
      if (sig != nullptr) sig[k * d + ch] = static_cast<float>(1.0 / (1.0 + e));
      wedge[ch] = p - q;
    }
  }
}

// The block's output from H, G and the gate's pre-activation a (R1-NRF-003; clifford::block_residual):
// B(ch) = h(ch) + gamma(ch) (SiLU(h(ch)) + sigmoid(a(ch)) g(ch)), in float.
float clifford_out(float h, float g, float a, float gamma) { return h + gamma * (silu_f(h) + sigmoid_f(a) * g); }

// The activations of the network on the rows of X (one point a row), those the backward pass
// needs: Z1 after the first ReLU (H and C without a block), with a block its features F, the
// sigmoids of its inner products SP, G, the gate's pre-activation A, and X2 = [B | C] the second
// layer's input; H2 after the second ReLU, O the raw outputs.
struct Activations {
  Mat Z1, F, SP, G, A, X2, H2, O;
};

void forward(const NeuralField& f, const Mat& X, Activations& a) {
  const auto ni = static_cast<Eigen::Index>(f.inputs()), nh = static_cast<Eigen::Index>(f.config.hidden);
  const Eigen::Map<const Mat> W1(f.w1.data(), nh, ni), W2(f.w2.data(), nh, nh), W3(f.w3.data(), kNeuralOutputs, nh);
  const Eigen::Map<const Row> B1(f.b1.data(), nh), B2(f.b2.data(), nh), B3(f.b3.data(), kNeuralOutputs);
  a.Z1 = ((X * W1.transpose()).rowwise() + B1).cwiseMax(0.0f);
  const std::uint32_t d = f.config.block;
  if (d == 0) {
    a.H2 = ((a.Z1 * W2.transpose()).rowwise() + B2).cwiseMax(0.0f);
  } else {
    const auto D = static_cast<Eigen::Index>(d), nf = static_cast<Eigen::Index>(2 * kNeuralShifts.size() * d);
    const Eigen::Index rows = X.rows();
    const Eigen::Map<const Mat> WC(f.wc.data(), D, nf), WG(f.wg.data(), D, 2 * D);
    const Eigen::Map<const Row> BC(f.bc.data(), D), BG(f.bg.data(), D);
    a.F.resize(rows, nf);
    a.SP.resize(rows, static_cast<Eigen::Index>(kNeuralShifts.size()) * D);
    for (Eigen::Index r = 0; r < rows; ++r) clifford_features(&a.Z1(r, 0), &a.Z1(r, D), d, &a.F(r, 0), &a.SP(r, 0));
    a.G = (a.F * WC.transpose()).rowwise() + BC;
    Mat HG(rows, 2 * D);
    HG << a.Z1.leftCols(D), a.G;
    a.A = (HG * WG.transpose()).rowwise() + BG;
    a.X2.resize(rows, nh);
    for (Eigen::Index r = 0; r < rows; ++r)
      for (Eigen::Index ch = 0; ch < D; ++ch) {
        a.X2(r, ch) = clifford_out(a.Z1(r, ch), a.G(r, ch), a.A(r, ch), f.gamma[static_cast<std::size_t>(ch)]);
        a.X2(r, D + ch) = a.Z1(r, D + ch);
      }
    a.H2 = ((a.X2 * W2.transpose()).rowwise() + B2).cwiseMax(0.0f);
  }
  a.O = (a.H2 * W3.transpose()).rowwise() + B3;
}

}  // namespace

// What the heads mean (R1-NRF-004, 007, 008): the kernel sum exp(o0) times the Gaussian prior at
// (x, sigma), colour 3 sigmoid(o1..3 + logit(the prior's colour / 3)) (linear light times
// brightness, at most 3), flow sigma o4..6; a field without a prior: expm1(softplus(o0)) and
// 3 sigmoid(o1..3).
FieldValue decode_neural_outputs(const NeuralField& f, const float* o, const Vec3& x, double sigma) {
  FieldValue v;
  const double o0 = static_cast<double>(o[0]);
  if (!f.prior_parts.empty()) {
    const NeuralField::PriorValue pv = f.prior_at(x, sigma);
    v.weight = std::exp(o0) * pv.weight;
    // 3 sigmoid(o + logit(q)) for the prior's colour q (R1-NRF-008), as 3 q / (q + (1 - q) e^-o).
    const double qs[3] = {pv.colour.x, pv.colour.y, pv.colour.z};
    double c[3];
    for (int k = 0; k < 3; ++k) c[k] = 3 * qs[k] / (qs[k] + (1 - qs[k]) * std::exp(-static_cast<double>(o[1 + k])));
    v.color = Vec3{c[0], c[1], c[2]};
  } else {
    // expm1(softplus(o0)) is exp(o0) where softplus is log1p(exp(o0)) (the one rounding a device
    // repeats), and expm1(o0) where softplus is o0.
    v.weight = o0 > 30 ? std::expm1(o0) : std::exp(o0);
    v.color = Vec3{3 * sigmoid(static_cast<double>(o[1])), 3 * sigmoid(static_cast<double>(o[2])), 3 * sigmoid(static_cast<double>(o[3]))};
  }
  v.density = f.kappa / sigma * v.weight;
  v.flow = Vec3{static_cast<double>(o[4]) * sigma, static_cast<double>(o[5]) * sigma, static_cast<double>(o[6]) * sigma};
  return v;
}

namespace {

// A training point: the query and the analytic field's targets in the heads' units.
struct Sample {
  Query q;
  float target[kNeuralOutputs];  // log1p(kernel sum), colour, flow / sigma
  float weight_cf = 0;           // weight of the colour and flow terms: min(1, kernel sum)
  double prior = 1;              // the prior's kernel sum at the point (R1-NRF-007)
  double colour_logit[3] = {};   // logit of the prior's colour over 3 (R1-NRF-008)
};

double gaussian(std::uint64_t seed, std::uint64_t item, std::uint64_t dim) {
  // Box-Muller on two counter draws (the first kept away from 0).
  const double u1 = std::max(rng::uniform_double(seed, item, dim), 0x1p-53);
  const double u2 = rng::uniform_double(seed, item, dim + 1);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
}

// The architecture a field may have (training refuses others, reading rejects them).
bool architecture_in_range(const NeuralConfig& c) {
  return c.levels >= 1 && c.levels <= 32 && c.log2_table >= 4 && c.log2_table <= 24 && c.hidden >= 1 && c.hidden <= 1024 &&
         (c.block == 0 || (c.block >= 2 && c.hidden == 2 * c.block));
}

template <class Body>
void parallel_chunks(std::uint32_t count, Body&& body) {
  tbb::parallel_for(std::uint32_t{0}, count, [&](std::uint32_t c) { body(c); });
}

struct Adam {
  std::vector<float> m, v;
  void resize(std::size_t n) {
    m.assign(n, 0.0f);
    v.assign(n, 0.0f);
  }
  static constexpr float b1 = 0.9f, b2 = 0.99f, eps = 1e-15f;
  float step_size = 0, inv_c2 = 1;  // lr / (1 - b1^t), 1 / (1 - b2^t)
  void begin_step(std::uint32_t t, double lr) {
    step_size = static_cast<float>(lr / (1 - std::pow(static_cast<double>(b1), t)));
    inv_c2 = static_cast<float>(1 / (1 - std::pow(static_cast<double>(b2), t)));
  }
  // One step on entry k with gradient g (after begin_step of this step), in float.
  void step(float& p, std::size_t k, float g) {
    m[k] = b1 * m[k] + (1 - b1) * g;
    v[k] = b2 * v[k] + (1 - b2) * g * g;
    p -= step_size * m[k] / (std::sqrt(v[k] * inv_c2) + eps);
  }
};

float init_uniform(std::uint64_t seed, std::uint64_t item, std::uint64_t dim, double bound) {
  return static_cast<float>((2 * rng::uniform_double(seed, item, dim) - 1) * bound);
}

}  // namespace

namespace {

// One layer of inference (R1-NRF-006): out[j] = max(0, (sum_i in[i] w[j][i], i ascending from 0)
// + b[j]) in float, each product and sum rounded (no contraction), ReLU unless `linear`. A device
// that sums in the same order gets the same bits. `wt` holds w input-major (w[j][i] at
// wt[i * no + j]), so the outputs' independent sums share vector lanes without changing any
// sum's order.
void infer_layer(const float* in, std::uint32_t ni, const float* wt, const float* b, std::uint32_t no, bool linear, float* out) {
  // Blocks of 8 outputs held in a fixed-size accumulator the compiler keeps in vector registers
  // (SSE2 at -O2); the outputs past the last full block one by one.
  constexpr std::uint32_t kBlock = 8;
  std::uint32_t j0 = 0;
  for (; j0 + kBlock <= no; j0 += kBlock) {
    float acc[kBlock] = {};
    for (std::uint32_t i = 0; i < ni; ++i) {
      const float xi = in[i];
      const float* row = wt + std::size_t{i} * no + j0;
      for (std::uint32_t k = 0; k < kBlock; ++k) acc[k] += xi * row[k];
    }
    std::copy(acc, acc + kBlock, out + j0);
  }
  for (std::uint32_t j = j0; j < no; ++j) {
    float acc = 0.0f;
    for (std::uint32_t i = 0; i < ni; ++i) acc += in[i] * wt[std::size_t{i} * no + j];
    out[j] = acc;
  }
  for (std::uint32_t j = 0; j < no; ++j) {
    out[j] += b[j];
    if (!linear) out[j] = std::max(out[j], 0.0f);
  }
}

// w (no x ni, row-major) input-major.
std::vector<float> input_major(const std::vector<float>& w, std::uint32_t no, std::uint32_t ni) {
  std::vector<float> t(w.size());
  for (std::uint32_t j = 0; j < no; ++j)
    for (std::uint32_t i = 0; i < ni; ++i) t[std::size_t{i} * no + j] = w[std::size_t{j} * ni + i];
  return t;
}

// The Clifford render block on one row (R1-NRF-003): H and C the halves of h1, G = Wc F + bc, the
// gate's pre-activation Wg [H | G] + bg, and the second layer's input x2 = [B | C]; wct and wgt
// are wc and wg input-major.
void block_row(const NeuralField& f, const float* h1, const float* wct, const float* wgt, float* x2) {
  const std::uint32_t d = f.config.block, nf = static_cast<std::uint32_t>(2 * kNeuralShifts.size()) * d;
  thread_local std::vector<float> F, hg, a;
  F.resize(nf);
  hg.resize(2 * d);
  a.resize(d);
  clifford_features(h1, h1 + d, d, F.data());
  infer_layer(F.data(), nf, wct, f.bc.data(), d, true, hg.data() + d);
  std::copy(h1, h1 + d, hg.begin());
  infer_layer(hg.data(), 2 * d, wgt, f.bg.data(), d, true, a.data());
  for (std::uint32_t ch = 0; ch < d; ++ch) {
    x2[ch] = clifford_out(h1[ch], hg[d + ch], a[ch], f.gamma[ch]);
    x2[d + ch] = h1[d + ch];
  }
}

}  // namespace

void detail::neural_block(const NeuralField& f, const float* h1, float* x2) {
  const std::uint32_t d = f.config.block;
  if (d == 0) {
    std::copy(h1, h1 + f.config.hidden, x2);
    return;
  }
  const std::vector<float> wct = input_major(f.wc, d, static_cast<std::uint32_t>(2 * kNeuralShifts.size()) * d),
                           wgt = input_major(f.wg, d, 2 * d);
  block_row(f, h1, wct.data(), wgt.data(), x2);
}

// The order of operations a device repeats (R1-NRF-007, 008): one pass over the parts, one exp
// each.
NeuralField::PriorValue NeuralField::prior_at(const Vec3& x, double sigma) const {
  PriorValue out;
  if (prior_parts.empty()) return out;
  const double s2 = sigma * sigma;
  double sum = 0, num[3] = {0, 0, 0}, nearest[3] = {0, 0, 0};
  double q_min = std::numeric_limits<double>::infinity();
  for (const PriorPart& p : prior_parts) {
    const double v = s2 + p.s2;
    const double r = s2 / v;
    const double d[3] = {x.x - p.centroid.x, x.y - p.centroid.y, x.z - p.centroid.z};
    const double q = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) / (2.0 * v);
    // exp(-q) for every part on the same path: q clamped at kPriorExpLimit and the term 0 beyond
    // it. Near and far parts then cost the same, so a sample's cost does not follow the scene
    // (R1-NRF-033: skipping far parts, or exp's slower path for them, made a frame up to 15%
    // cheaper where the scene is far from most samples).
    const double keep = q <= kPriorExpLimit ? 1.0 : 0.0;
    const double e = p.mass * r * std::sqrt(r) * (std::exp(-std::min(q, kPriorExpLimit)) * keep);
    sum += e;
    const double mean[3] = {p.colour.x, p.colour.y, p.colour.z};
    double c[3];
    for (int k = 0; k < 3; ++k) {
      const double g = (p.gradient[3 * k] * d[0] + p.gradient[3 * k + 1] * d[1]) + p.gradient[3 * k + 2] * d[2];
      c[k] = mean[k] + g / v;
      num[k] += e * c[k];
    }
    if (q < q_min) {
      q_min = q;
      std::copy(c, c + 3, nearest);
    }
  }
  out.weight = sum;
  // Where every part's kernel sum underflows, the nearest part's colour.
  double q3[3];
  for (int k = 0; k < 3; ++k) q3[k] = std::clamp((sum > 0 ? num[k] / sum : nearest[k]) / 3.0, 1e-3, 1 - 1e-3);
  out.colour = Vec3{q3[0], q3[1], q3[2]};
  return out;
}

bool NeuralField::may_reach(const Vec3& x, double reach) const {
  if (prior_parts.empty()) return true;
  const Vec3 cell = prior_cells > 0 ? (prior_hi - prior_lo) * (1.0 / prior_cells) : Vec3{size, size, size};
  const double r = reach + length(cell);
  // Every part tested, no early end: the same work for a sample near the scene or far from it.
  bool hit = false;
  for (const PriorPart& p : prior_parts) {
    const Vec3 d = x - p.centroid;
    hit |= dot(d, d) <= r * r;
  }
  return hit;
}

NeuralInference::NeuralInference(const NeuralField& f)
    : f_(f),
      w1t_(input_major(f.w1, f.config.hidden, f.inputs())),
      w2t_(input_major(f.w2, f.config.hidden, f.config.hidden)),
      w3t_(input_major(f.w3, kNeuralOutputs, f.config.hidden)),
      wct_(input_major(f.wc, f.config.block, static_cast<std::uint32_t>(2 * kNeuralShifts.size()) * f.config.block)),
      wgt_(input_major(f.wg, f.config.block, 2 * f.config.block)) {}

FieldValue NeuralInference::evaluate(const Vec3& x, double sigma) const {
  const NeuralField& f = f_;
  const std::uint32_t d = f.config.block;
  thread_local std::vector<std::uint32_t> index;
  thread_local std::vector<float> weight, mask, features, h1, h2, x2;
  index.resize(f.config.levels * 8);
  weight.resize(f.config.levels * 8);
  mask.resize(f.config.levels);
  features.resize(f.inputs());
  h1.resize(f.config.hidden);
  h2.resize(f.config.hidden);
  const Location e{index.data(), weight.data(), mask.data()};
  const Query q = make_query(f, x, sigma);
  locate(f, q, e);
  gather(f, e, q.t, features.data());
  float o[kNeuralOutputs];
  infer_layer(features.data(), f.inputs(), w1t_.data(), f.b1.data(), f.config.hidden, false, h1.data());
  const float* in2 = h1.data();
  if (d > 0) {
    x2.resize(f.config.hidden);
    block_row(f, h1.data(), wct_.data(), wgt_.data(), x2.data());
    in2 = x2.data();
  }
  infer_layer(in2, f.config.hidden, w2t_.data(), f.b2.data(), f.config.hidden, false, h2.data());
  infer_layer(h2.data(), f.config.hidden, w3t_.data(), f.b3.data(), kNeuralOutputs, true, o);
  return decode_neural_outputs(f, o, x, sigma);
}

FieldValue NeuralField::evaluate(const Vec3& x, double sigma) const { return NeuralInference(*this).evaluate(x, sigma); }

std::uint64_t neural_seed(std::span<const std::uint8_t> snapshot_digest) {
  std::vector<std::uint8_t> m(snapshot_digest.begin(), snapshot_digest.end());
  for (const char c : std::string_view("nrf")) m.push_back(static_cast<std::uint8_t>(c));
  return format::load_u64(hemera::hash(m).data());  // the digest's first 8 bytes, little-endian
}

namespace {

// Bits 0, 3, 6, .. of the result are v's bits 0, 1, 2, .. (v < 2^21).
std::uint64_t spread_bits(std::uint64_t v) {
  v = (v | v << 32) & 0x1f00000000ffffULL;
  v = (v | v << 16) & 0x1f0000ff0000ffULL;
  v = (v | v << 8) & 0x100f00f00f00f00fULL;
  v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
  v = (v | v << 2) & 0x1249249249249249ULL;
  return v;
}

// The spatial octree (R1-NRF-014): the particles with weight n phi > 0 in Morton order of their
// positions (21 bits per axis over their box; ties by particle index), split by octant from the
// top, a run of one octant passed down without a node, a run of at most kOctreeLeaf particles a
// leaf. Nodes in breadth-first order, so a node's children are one run; each node's weight,
// centroid, colour and extent summed over its particles in that order. No colour spreads: the
// targets' aggregates carry their mean colour (R1-NRF-014).
constexpr std::uint32_t kOctreeLeaf = 8;
void octree(const Scene& s, FieldFrame::FarTree& tree) {
  const double n = s.n;
  std::vector<std::uint32_t> live;
  for (std::uint32_t p = 0; p < s.n; ++p)
    if (n * s.phi[p] > 0) live.push_back(p);
  if (live.empty()) return;
  Vec3 lo = s.position[live[0]], hi = lo;
  for (const std::uint32_t p : live) {
    const Vec3& x = s.position[p];
    lo = Vec3{std::min(lo.x, x.x), std::min(lo.y, x.y), std::min(lo.z, x.z)};
    hi = Vec3{std::max(hi.x, x.x), std::max(hi.y, x.y), std::max(hi.z, x.z)};
  }
  const double side = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
  const double scale = side > 0 ? 2097151.0 / side : 0.0;
  const auto m = static_cast<std::uint32_t>(live.size());
  std::vector<std::pair<std::uint64_t, std::uint32_t>> key(m);
  tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, m, 4096), [&](const tbb::blocked_range<std::uint32_t>& r) {
    for (std::uint32_t i = r.begin(); i != r.end(); ++i) {
      const Vec3 u = (s.position[live[i]] - lo) * scale;
      const auto cell = [](double v) { return static_cast<std::uint64_t>(std::clamp(v, 0.0, 2097151.0)); };
      key[i] = {spread_bits(cell(u.x)) | spread_bits(cell(u.y)) << 1 | spread_bits(cell(u.z)) << 2, live[i]};
    }
  });
  tbb::parallel_sort(key.begin(), key.end());
  struct Span {
    std::uint32_t begin, end;
    int shift;  // the lowest bit of the octant digit the run splits at (the digits above are shared)
  };
  std::vector<Span> span{{0, m, 60}};
  tree.roots = 1;
  tree.nodes.emplace_back();
  for (std::size_t i = 0; i < span.size(); ++i) {
    const std::uint32_t b = span[i].begin, e = span[i].end;
    int shift = span[i].shift;
    // Pass down while the whole run lies in one octant (the codes are sorted: first and last).
    while (shift >= 0 && (key[b].first >> shift & 7) == (key[e - 1].first >> shift & 7)) shift -= 3;
    FieldFrame::FarTree::Node& nd = tree.nodes[i];
    if (e - b <= kOctreeLeaf || shift < 0) {
      nd.first = b;
      nd.count = e - b;
      nd.leaf = 1;
      continue;
    }
    nd.first = static_cast<std::uint32_t>(span.size());
    std::uint32_t count = 0;
    for (std::uint32_t at = b; at < e;) {
      const std::uint64_t octant = key[at].first >> shift & 7;
      const auto stop = static_cast<std::uint32_t>(
          std::partition_point(key.begin() + at, key.begin() + e, [&](const auto& k) { return (k.first >> shift & 7) == octant; }) -
          key.begin());
      span.push_back({at, stop, shift - 3});
      tree.nodes.emplace_back();
      ++count;
      at = stop;
    }
    tree.nodes[i].count = count;
  }
  tree.color.resize(tree.nodes.size());
  tree.members.resize(m);
  tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, m, 4096), [&](const tbb::blocked_range<std::uint32_t>& r) {
    for (std::uint32_t i = r.begin(); i != r.end(); ++i) {
      const std::uint32_t p = key[i].second;
      tree.members[i] = {s.position[p], s.color[p], n * s.phi[p]};
    }
  });
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tree.nodes.size(), 64), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      FieldFrame::FarTree::Node& nd = tree.nodes[i];
      double w = 0;
      Vec3 c, col;
      for (std::uint32_t k = span[i].begin; k < span[i].end; ++k) {
        const FieldFrame::Member& mb = tree.members[k];
        w += mb.weight;
        c += mb.position * mb.weight;
        col += mb.color * mb.weight;
      }
      nd.weight = w;
      nd.centroid = c / w;
      tree.color[i] = col / w;
      double extent = 0;
      for (std::uint32_t k = span[i].begin; k < span[i].end; ++k)
        extent = std::max(extent, length(tree.members[k].position - nd.centroid));
      nd.extent = extent;
    }
  });
}

}  // namespace

FieldFrame far_field_frame(const Scene& s, const FieldParams& p, FarLayout layout) {
  FieldFrame ff;
  ff.scene = &s;
  ff.params = p;  // every slot empty: every node is its scene aggregate (weight n phi)
  ff.params.cutoff = field_cutoff(p.cutoff, s.n);  // as a view's frame has it (R1-RND-054)
  if (layout == FarLayout::kOctree) {
    auto tree = std::make_shared<FieldFrame::FarTree>();
    octree(s, *tree);
    ff.far_tree = std::move(tree);
  }
  return ff;
}

namespace {

// The Gaussian prior's parts (R1-NRF-007, 008): the particles grouped by the cell of a grid of g
// cells per side over the box [lo, hi] (positions outside it in its border cells); per occupied
// cell, in cell order, its far-field mass (every particle at weight n phi), weighted centroid and
// spread per axis, mean colour and the colour's covariance with position, each summed in particle
// order.
std::vector<NeuralField::PriorPart> prior_parts_of(const Scene& s, std::uint32_t g, const Vec3& lo, const Vec3& hi) {
  auto cell_of = [&](const Vec3& x) {
    const double u[3] = {x.x - lo.x, x.y - lo.y, x.z - lo.z}, w[3] = {hi.x - lo.x, hi.y - lo.y, hi.z - lo.z};
    std::uint32_t i[3];
    for (int k = 0; k < 3; ++k)
      i[k] = w[k] > 0 ? std::min(g - 1, static_cast<std::uint32_t>(std::floor(std::clamp(u[k] / w[k], 0.0, 1.0) * g))) : 0;
    return i[0] + g * (i[1] + g * i[2]);
  };
  std::vector<NeuralField::PriorPart> cells(std::size_t{g} * g * g);
  std::vector<Vec3> weighted(cells.size());
  std::vector<std::uint32_t> cell(s.n);
  for (std::uint32_t p = 0; p < s.n; ++p) {
    const double wp = static_cast<double>(s.n) * s.phi[p];
    cell[p] = cell_of(s.position[p]);
    cells[cell[p]].mass += wp;
    weighted[cell[p]] += s.position[p] * wp;
  }
  for (std::size_t c = 0; c < cells.size(); ++c)
    if (cells[c].mass > 0) cells[c].centroid = weighted[c] * (1.0 / cells[c].mass);
  for (std::uint32_t p = 0; p < s.n; ++p) {
    NeuralField::PriorPart& part = cells[cell[p]];
    if (!(part.mass > 0)) continue;
    const double wp = static_cast<double>(s.n) * s.phi[p];
    const Vec3 d = s.position[p] - part.centroid;
    part.s2 += wp * (d.x * d.x + d.y * d.y + d.z * d.z);
    part.colour += s.color[p] * (wp / part.mass);
  }
  for (std::uint32_t p = 0; p < s.n; ++p) {
    NeuralField::PriorPart& part = cells[cell[p]];
    if (!(part.mass > 0)) continue;
    const double wp = static_cast<double>(s.n) * s.phi[p];
    ColourSpread::add_moment(part.gradient, wp / part.mass, s.color[p] - part.colour, s.position[p] - part.centroid);
  }
  std::vector<NeuralField::PriorPart> parts;
  for (NeuralField::PriorPart& part : cells) {
    if (!(part.mass > 0)) continue;
    part.s2 /= 3 * part.mass;
    parts.push_back(part);
  }
  return parts;
}

// A new field for scene s: its cube, tau range and resolutions, and the parameters' initial values.
NeuralField init_field(const Scene& s, const NeuralConfig& c, std::uint64_t seed) {
  NeuralField f;
  f.config = c;
  f.seed = seed;
  // The cube: the positions' box grown by three widest kernels, made cubic (R1-NRF-001).
  f.tau_lo = s.tau0;
  f.centroid = s.centroid;
  double extent = 0;
  Vec3 lo = s.position[0], hi = s.position[0];
  for (const Vec3& p : s.position) {
    extent = std::max(extent, length(p - s.centroid));
    lo = Vec3{std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = Vec3{std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  f.prior_cells = kPriorCells;
  f.prior_lo = lo;
  f.prior_hi = hi;
  f.prior_parts = prior_parts_of(s, f.prior_cells, lo, hi);
  f.tau_hi = std::max(16.0 * f.tau_lo, (kPointMass * extent) * (kPointMass * extent));
  const double margin = 3 * std::sqrt(f.tau_hi);
  f.size = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z}) + 2 * margin;
  const Vec3 mid = (lo + hi) * 0.5;
  f.lo = mid - Vec3{f.size / 2, f.size / 2, f.size / 2};
  // Resolutions: geometric from base_resolution to the finest kernel's (a cell per 2 sqrt(tau_lo)).
  const double finest = std::clamp(kCellsPerSigma * f.size / std::sqrt(f.tau_lo), static_cast<double>(c.base_resolution), 4096.0);
  f.resolution.resize(c.levels);
  for (std::uint32_t l = 0; l < c.levels; ++l) {
    const double t = c.levels > 1 ? static_cast<double>(l) / (c.levels - 1) : 0.0;
    f.resolution[l] = static_cast<std::uint32_t>(std::floor(c.base_resolution * std::pow(finest / c.base_resolution, t)));
  }
  // Parameters from the counter-based generator (R1-NRF-020): grid entries uniform in +-1e-4,
  // layers uniform in +-sqrt(6 / (fan_in + fan_out)).
  const std::uint32_t table = 1u << c.log2_table, ni = f.inputs(), nh = c.hidden;
  f.grid.resize(static_cast<std::size_t>(c.levels) * table * kNeuralFeatures);
  for (std::size_t k = 0; k < f.grid.size(); ++k) f.grid[k] = init_uniform(seed, k, 0, 1e-4);
  auto layer = [&](std::vector<float>& w, std::vector<float>& b, std::uint32_t out, std::uint32_t in, std::uint64_t dim) {
    w.resize(static_cast<std::size_t>(out) * in);
    b.assign(out, 0.0f);
    const double bound = std::sqrt(6.0 / (in + out));
    for (std::size_t k = 0; k < w.size(); ++k) w[k] = init_uniform(seed, k, dim, bound);
  };
  layer(f.w1, f.b1, nh, ni, 1);
  layer(f.w2, f.b2, nh, nh, 2);
  layer(f.w3, f.b3, kNeuralOutputs, nh, 3);
  if (c.block > 0) {
    // The Clifford block as R1-RND-105 initialises one (bounds 1 / sqrt(fan in), gamma 1e-5: a
    // near-identity residual at the start), from this field's seed.
    const std::uint32_t d = c.block, nf = static_cast<std::uint32_t>(2 * kNeuralShifts.size()) * d;
    f.wc.resize(std::size_t{d} * nf);
    f.wg.resize(std::size_t{d} * 2 * d);
    for (std::size_t k = 0; k < f.wc.size(); ++k) f.wc[k] = init_uniform(seed, k, 4, 1.0 / std::sqrt(static_cast<double>(nf)));
    for (std::size_t k = 0; k < f.wg.size(); ++k) f.wg[k] = init_uniform(seed, k, 5, 1.0 / std::sqrt(2.0 * d));
    f.bc.assign(d, 0.0f);
    f.bg.assign(d, 0.0f);
    f.gamma.assign(d, static_cast<float>(clifford::kInitialGamma));
  }
  return f;
}

// The training targets' acceptance (R1-NRF-010): a node no wider than this many sigma is one
// Gaussian, twice the frames' theta; the network's frames are held to the frames' field.
constexpr double kTargetTheta = 0.5;

// The training set (R1-NRF-010): `count` points with the analytic far field's targets.
std::vector<Sample> make_set(const Scene& s, const NeuralField& f, std::uint32_t count, std::uint64_t data_seed,
                             std::span<const std::uint32_t> pool, const std::pair<Vec3, Vec3>* box,
                             const ProgressFn& progress) {
  // The training set (R1-NRF-010): even points uniform in the cube, odd points a Gaussian step of
  // width sigma from a particle drawn uniformly; tau log-uniform in [tau_lo, tau_hi]. Targets from
  // the analytic far field.
  // Of a local update (R1-NRF-050): positions in `box` (lo, size per axis) and particles from
  // `pool` (the particles in the box) instead of the cube and every particle.
  // The targets' walk takes nodes whole up to kTargetTheta sigma (R1-NRF-010; frames: 0.25).
  FieldParams target_params;
  target_params.theta = kTargetTheta;
  const FieldFrame ff = far_field_frame(s, target_params, FarLayout::kOctree);
  std::vector<Sample> set(count);
  constexpr std::uint32_t kTruthChunk = 1024;
  const std::uint32_t truth_chunks = (count + kTruthChunk - 1) / kTruthChunk;
  report(progress, "train-field: samples of the analytic field", 0, count);
  // The points first, then their targets in Morton order of the points: neighbours in that order
  // read the same nodes and members, from the caches (each target is its point's alone, so the
  // order changes no byte).
  std::vector<Vec3> point(count);
  std::vector<double> width(count);
  std::vector<std::uint64_t> key(count);
  parallel_chunks(truth_chunks, [&](std::uint32_t chunk) {
    const std::uint32_t end = std::min(count, (chunk + 1) * kTruthChunk);
    for (std::uint32_t k = chunk * kTruthChunk; k < end; ++k) {
      const double tau = f.tau_lo * std::pow(f.tau_hi / f.tau_lo, rng::uniform_double(data_seed, k, 0));
      const double sigma = std::sqrt(tau);
      Vec3 x;
      if (k % 2 == 0 || pool.empty()) {
        const Vec3 u{rng::uniform_double(data_seed, k, 1), rng::uniform_double(data_seed, k, 2),
                     rng::uniform_double(data_seed, k, 3)};
        x = box ? box->first + Vec3{u.x * box->second.x, u.y * box->second.y, u.z * box->second.z} : f.lo + u * f.size;
      } else {
        const auto i = std::min<std::size_t>(
            pool.size() - 1, static_cast<std::size_t>(rng::uniform_double(data_seed, k, 1) * static_cast<double>(pool.size())));
        x = s.position[pool[i]] + Vec3{gaussian(data_seed, k, 4), gaussian(data_seed, k, 6), gaussian(data_seed, k, 8)} * sigma;
        if (box) {
          const Vec3 top = box->first + box->second;
          x = Vec3{std::clamp(x.x, box->first.x, top.x), std::clamp(x.y, box->first.y, top.y), std::clamp(x.z, box->first.z, top.z)};
        }
      }
      point[k] = x;
      width[k] = sigma;
      std::uint64_t code = 0;
      const double u[3] = {(x.x - f.lo.x) / f.size, (x.y - f.lo.y) / f.size, (x.z - f.lo.z) / f.size};
      for (int a = 0; a < 3; ++a) {
        const auto cell = static_cast<std::uint64_t>(std::clamp(u[a], 0.0, 1.0) * 1023.0);
        for (int b = 0; b < 10; ++b) code |= ((cell >> b) & 1u) << (3 * b + a);
      }
      key[k] = code << 32 | k;
    }
  });
  std::sort(key.begin(), key.end());
  parallel_chunks(truth_chunks, [&](std::uint32_t chunk) {
    const std::uint32_t end = std::min(count, (chunk + 1) * kTruthChunk);
    for (std::uint32_t j = chunk * kTruthChunk; j < end; ++j) {
      const auto k = static_cast<std::uint32_t>(key[j]);
      const Vec3 x = point[k];
      const double sigma = width[k];
      const FieldValue v = field_graded(ff, x, sigma);
      Sample& smp = set[k];
      smp.q = make_query(f, x, sigma);
      const NeuralField::PriorValue pv = f.prior_at(x, sigma);
      smp.prior = pv.weight;
      if (!f.prior_parts.empty()) {
        const Vec3& q = pv.colour;
        smp.colour_logit[0] = std::log(q.x / (1 - q.x));
        smp.colour_logit[1] = std::log(q.y / (1 - q.y));
        smp.colour_logit[2] = std::log(q.z / (1 - q.z));
      }
      smp.target[0] = static_cast<float>(std::log1p(v.weight));
      smp.target[1] = static_cast<float>(v.color.x / 3);
      smp.target[2] = static_cast<float>(v.color.y / 3);
      smp.target[3] = static_cast<float>(v.color.z / 3);
      smp.target[4] = static_cast<float>(v.flow.x / sigma);
      smp.target[5] = static_cast<float>(v.flow.y / sigma);
      smp.target[6] = static_cast<float>(v.flow.z / sigma);
      smp.weight_cf = static_cast<float>(std::min(1.0, v.weight));
    }
  });
  report(progress, "train-field: samples of the analytic field", count, count);
  return set;
}

// The training set's target means and the heads' loss weights (R1-NRF-011), in set order: each
// head's squared error is divided by its targets' variance over the set, so the colour (a few
// hundredths) weighs as much as the density (a few units) in the loss.
struct SetMoments {
  double mean[kNeuralOutputs] = {};
  double head_weight[kNeuralOutputs] = {};
};
SetMoments moments(const std::vector<Sample>& set) {
  SetMoments mo;
  double* mean = mo.mean;
  double cw = 0;
  for (const Sample& smp : set) {
    mean[0] += static_cast<double>(smp.target[0]);
    for (std::uint32_t k = 1; k < kNeuralOutputs; ++k) mean[k] += static_cast<double>(smp.weight_cf) * static_cast<double>(smp.target[k]);
    cw += static_cast<double>(smp.weight_cf);
  }
  mean[0] /= static_cast<double>(set.size());
  for (std::uint32_t k = 1; k < kNeuralOutputs; ++k) mean[k] = cw > 0 ? mean[k] / cw : 0.0;
  double var[kNeuralOutputs] = {};
  for (const Sample& smp : set) {
    const double d0 = static_cast<double>(smp.target[0]) - mean[0];
    var[0] += d0 * d0;
    for (std::uint32_t k = 1; k < kNeuralOutputs; ++k) {
      const double d = static_cast<double>(smp.target[k]) - mean[k];
      var[k] += static_cast<double>(smp.weight_cf) * d * d;
    }
  }
  var[0] /= static_cast<double>(set.size());
  for (std::uint32_t k = 1; k < kNeuralOutputs; ++k) var[k] = cw > 0 ? var[k] / cw : 0.0;
  for (std::uint32_t k = 0; k < kNeuralOutputs; ++k) mo.head_weight[k] = 1.0 / std::max(var[k], 1e-6);
  return mo;
}

// The parameters Adam trains besides the grid, in gradient order: w1, b1, w2, b2, w3, b3, then the
// block's wc, bc, wg, bg, gamma (empty without one). Field is NeuralField or const NeuralField.
template <class Field>
auto mlp_parts(Field& f) -> std::array<decltype(&f.w1), 11> {
  return {&f.w1, &f.b1, &f.w2, &f.b2, &f.w3, &f.b3, &f.wc, &f.bc, &f.wg, &f.bg, &f.gamma};
}

// One chunk's loss (R1-NRF-011, the points' terms summed in row order) and its gradients (the
// terms times `scale`): the parameters' into `gmlp` (in mlp_parts order; skipped when null) and the input
// rows' into dX (what the grid's entries get). The rows of X are the points' network inputs.
double backward(const NeuralField& f, const Mat& X, const Sample* const* points, const double* head_weight, double scale,
                float* gmlp, Mat& dX) {
  const auto ni = static_cast<Eigen::Index>(f.inputs()), nh = static_cast<Eigen::Index>(f.config.hidden);
  const Eigen::Index rows = X.rows();
  Activations a;
  forward(f, X, a);
  // Loss and its gradient at the outputs.
  Mat dO(rows, kNeuralOutputs);
  double total = 0;
  for (Eigen::Index r = 0; r < rows; ++r) {
    const Sample& smp = *points[r];
    // The density head in log1p units of the kernel sum w = exp(o0) times the prior (1 for a
    // field without one, where log1p(w) is softplus(o0)); d log1p(w) / d o0 = w / (1 + w).
    const double wh = std::exp(static_cast<double>(a.O(r, 0))) * smp.prior;
    const double r0 = std::log1p(wh) - static_cast<double>(smp.target[0]);
    double loss = head_weight[0] * r0 * r0;
    dO(r, 0) = static_cast<float>(2 * head_weight[0] * r0 * (wh / (1 + wh)) * scale);
    for (int k = 1; k <= 3; ++k) {
      const double sg = sigmoid(static_cast<double>(a.O(r, k)) + smp.colour_logit[k - 1]);
      const double d = sg - static_cast<double>(smp.target[k]);
      const double wk = head_weight[k] * static_cast<double>(smp.weight_cf);
      loss += wk * d * d;
      dO(r, k) = static_cast<float>(2 * wk * d * sg * (1 - sg) * scale);
    }
    for (int k = 4; k <= 6; ++k) {
      const double d = static_cast<double>(a.O(r, k)) - static_cast<double>(smp.target[k]);
      const double wk = head_weight[k] * static_cast<double>(smp.weight_cf);
      loss += wk * d * d;
      dO(r, k) = static_cast<float>(2 * wk * d * scale);
    }
    total += loss;
  }
  // Backward: layer gradients as matrix products, ReLU masks from the activations.
  const Eigen::Map<const Mat> W1(f.w1.data(), nh, ni), W2(f.w2.data(), nh, nh), W3(f.w3.data(), kNeuralOutputs, nh);
  const std::uint32_t d = f.config.block;
  const auto D = static_cast<Eigen::Index>(d), nf = static_cast<Eigen::Index>(2 * kNeuralShifts.size() * d);
  std::array<float*, 11> g{};
  if (gmlp != nullptr) {
    float* at = gmlp;
    std::size_t k = 0;
    for (const std::vector<float>* part : mlp_parts(f)) {
      g[k++] = at;
      at += part->size();
    }
  }
  const Mat& in2 = d == 0 ? a.Z1 : a.X2;
  const Mat dH2 = ((dO * W3).array() * (a.H2.array() > 0.0f).cast<float>()).matrix();
  if (gmlp != nullptr) {
    Eigen::Map<Mat>(g[4], kNeuralOutputs, nh).noalias() = dO.transpose() * a.H2;
    Eigen::Map<Row>(g[5], kNeuralOutputs) = dO.colwise().sum();
    Eigen::Map<Mat>(g[2], nh, nh).noalias() = dH2.transpose() * in2;
    Eigen::Map<Row>(g[3], nh) = dH2.colwise().sum();
  }
  Mat dZ1 = dH2 * W2;  // the second layer's input's gradient, made the first layer's below
  if (d > 0) {
    // The Clifford block (R1-NRF-003) backwards: B = H + gamma (SiLU(H) + sigmoid(A) G),
    // A = Wg [H | G] + bg, G = Wc F + bc, F the shifted inner and wedge products of H and C.
    const Eigen::Map<const Mat> WC(f.wc.data(), D, nf), WG(f.wg.data(), D, 2 * D);
    Mat dG(rows, D), dA(rows, D);
    Row dgamma = Row::Zero(D);
    for (Eigen::Index r = 0; r < rows; ++r)
      for (Eigen::Index ch = 0; ch < D; ++ch) {
        const float h = a.Z1(r, ch), gv = a.G(r, ch), gm = f.gamma[static_cast<std::size_t>(ch)], db = dZ1(r, ch);
        // SiLU(h) and sigmoid(h) as silu_f and sigmoid_f round them, from one det_exp.
        const double eh = clifford::det_exp(-static_cast<double>(h));
        const auto sh = static_cast<float>(1.0 / (1.0 + eh)), silu_h = static_cast<float>(static_cast<double>(h) / (1.0 + eh));
        const float sa = sigmoid_f(a.A(r, ch));
        dgamma(ch) += db * (silu_h + sa * gv);
        const float dbg = db * gm;
        dZ1(r, ch) = db + dbg * (sh * (1.0f + h * (1.0f - sh)));  // SiLU'(h) = s (1 + h (1 - s))
        dG(r, ch) = dbg * sa;
        dA(r, ch) = dbg * gv * (sa * (1.0f - sa));
      }
    Mat HG(rows, 2 * D);
    HG << a.Z1.leftCols(D), a.G;
    const Mat dHG = dA * WG;
    dZ1.leftCols(D) += dHG.leftCols(D);
    dG += dHG.rightCols(D);
    const Mat dF = dG * WC;
    if (gmlp != nullptr) {
      Eigen::Map<Mat>(g[6], D, nf).noalias() = dG.transpose() * a.F;
      Eigen::Map<Row>(g[7], D) = dG.colwise().sum();
      Eigen::Map<Mat>(g[8], D, 2 * D).noalias() = dA.transpose() * HG;
      Eigen::Map<Row>(g[9], D) = dA.colwise().sum();
      Eigen::Map<Row>(g[10], D) = dgamma;
    }
    for (Eigen::Index r = 0; r < rows; ++r) {
      const float* h = &a.Z1(r, 0);
      const float* cv = h + D;
      for (std::size_t k = 0; k < kNeuralShifts.size(); ++k) {
        const auto s = static_cast<Eigen::Index>(static_cast<std::uint32_t>(kNeuralShifts[k]) % d);
        for (Eigen::Index ch = 0; ch < D; ++ch) {
          const Eigen::Index j = ch + s < D ? ch + s : ch + s - D;
          const float p = h[ch] * cv[j], sp = a.SP(r, static_cast<Eigen::Index>(k) * D + ch);
          const float di = dF(r, static_cast<Eigen::Index>(2 * k) * D + ch) * (sp * (1.0f + p * (1.0f - sp)));
          const float dw = dF(r, static_cast<Eigen::Index>(2 * k + 1) * D + ch);
          // Inner: SiLU(h[ch] c[j]); wedge: h[ch] c[j] - h[j] c[ch].
          dZ1(r, ch) += (di + dw) * cv[j];
          dZ1(r, D + j) += (di + dw) * h[ch];
          dZ1(r, j) -= dw * cv[ch];
          dZ1(r, D + ch) -= dw * h[j];
        }
      }
    }
  }
  dZ1 = (dZ1.array() * (a.Z1.array() > 0.0f).cast<float>()).matrix();
  if (gmlp != nullptr) {
    Eigen::Map<Mat>(g[0], nh, ni).noalias() = dZ1.transpose() * X;
    Eigen::Map<Row>(g[1], nh) = dZ1.colwise().sum();
  }
  dX = dZ1 * W1;
  return total;
}

// Adam on the set (R1-NRF-011): the MLP too when `mlp` (a local update keeps it, R1-NRF-050),
// its output biases first set to the set's means when `init_biases`.
void fit(NeuralField& f, const std::vector<Sample>& set, std::uint32_t batch, std::uint32_t steps, bool mlp, bool init_biases,
         const ProgressFn& progress) {
  NeuralConfig c = f.config;
  c.batch = batch;
  c.steps = steps;
  const std::uint32_t table = 1u << c.log2_table, ni = f.inputs();
  const auto samples = static_cast<std::uint32_t>(set.size());
  const SetMoments mo = moments(set);
  const double* head_weight = mo.head_weight;
  // The output biases start at the training set's means (R1-NRF-020): the heads then learn the
  // variation from the first step instead of spending steps on the offset.
  if (init_biases) {
    // With the prior the density head starts at the prior itself (o0 = 0).
    f.b3[0] = !f.prior_parts.empty() ? 0.0f
                                     : static_cast<float>(mo.mean[0] > 1e-6 ? std::log(std::expm1(mo.mean[0])) : std::log(1e-6));
    for (std::uint32_t k = 1; k <= 3; ++k) {
      const double m = std::clamp(mo.mean[k], 1e-3, 1 - 1e-3);
      f.b3[k] = !f.prior_parts.empty() ? 0.0f : static_cast<float>(std::log(m / (1 - m)));
    }
    for (std::uint32_t k = 4; k < kNeuralOutputs; ++k) f.b3[k] = static_cast<float>(mo.mean[k]);
  }

  // Where every sample falls in the grid, once: it depends on the sample only.
  const std::size_t corners = static_cast<std::size_t>(c.levels) * 8;
  std::vector<std::uint32_t> loc_index(samples * corners);
  std::vector<float> loc_weight(samples * corners), loc_mask(static_cast<std::size_t>(samples) * c.levels);
  auto location = [&](std::size_t k) {
    return Location{loc_index.data() + k * corners, loc_weight.data() + k * corners, loc_mask.data() + k * c.levels};
  };
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, samples, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t k = r.begin(); k != r.end(); ++k) locate(f, set[k].q, location(k));
  });

  // Training (R1-NRF-011): batches in set order; per chunk of kChunk points one pass of matrix
  // products forward and back, gradients reduced in chunk order; Adam on the MLP and on the grid
  // entries a batch touched.
  std::size_t n_mlp = 0;
  for (const std::vector<float>* v : mlp_parts(f)) n_mlp += v->size();
  Adam adam_mlp, adam_grid;
  adam_mlp.resize(n_mlp);
  adam_grid.resize(f.grid.size());
  std::vector<float> grid_grad(f.grid.size(), 0.0f);
  std::vector<std::uint8_t> touched(f.grid.size() / kNeuralFeatures, 0);
  const std::uint32_t chunks = (c.batch + kChunk - 1) / kChunk;
  // The grid is stepped level by level (each level's entries its own slice of the table): a level
  // adds the chunks' contributions to it in chunk order, each chunk's in point and corner order,
  // then steps the entries it touched. A chunk stores its contributions by level as it makes them.
  struct Contribution {
    std::uint32_t idx;
    float g[2];
  };
  struct ChunkGrad {
    std::vector<float> mlp;
    std::vector<Contribution> grid;  // levels x (kChunk points x 8 corners)
    double loss = 0;
  };
  std::vector<ChunkGrad> cg(chunks);
  for (ChunkGrad& g : cg) {
    g.mlp.resize(n_mlp);
    g.grid.resize(static_cast<std::size_t>(c.levels) * kChunk * 8);
  }
  // The MLP's parameters in gradient order (mlp_parts, as ChunkGrad::mlp holds them).
  std::vector<float*> params;
  params.reserve(n_mlp);
  for (std::vector<float>* v : mlp_parts(f))
    for (float& p : *v) params.push_back(&p);
  for (std::uint32_t step = 1; step <= c.steps; ++step) {
    const std::uint64_t first = static_cast<std::uint64_t>(step - 1) * c.batch;
    parallel_chunks(chunks, [&](std::uint32_t chunk) {
      ChunkGrad& g = cg[chunk];
      g.loss = 0;
      const std::uint32_t begin = chunk * kChunk, end = std::min(c.batch, (chunk + 1) * kChunk);
      const Eigen::Index rows = end - begin;
      Mat X(rows, ni), dX;
      const Sample* points[kChunk];
      for (Eigen::Index r = 0; r < rows; ++r) {
        const std::size_t k = (first + begin + static_cast<std::uint64_t>(r)) % samples;
        gather(f, location(k), set[k].q.t, X.row(r).data());
        points[r] = &set[k];
      }
      g.loss = backward(f, X, points, head_weight, 1.0 / c.batch, mlp ? g.mlp.data() : nullptr, dX);
      for (Eigen::Index r = 0; r < rows; ++r) {
        const Location e = location((first + begin + static_cast<std::uint64_t>(r)) % samples);
        for (std::uint32_t l = 0; l < c.levels; ++l)
          for (std::uint32_t k = 0; k < 8; ++k) {
            const float w = e.weight[l * 8 + k] * e.mask[l];
            const std::uint32_t idx = e.index[l * 8 + k];
            g.grid[(l * kChunk + static_cast<std::size_t>(r)) * 8 + k] = {idx, {w * dX(r, 2 * l), w * dX(r, 2 * l + 1)}};
          }
      }
    });
    double loss = 0;
    for (const ChunkGrad& g : cg) loss += g.loss;
    loss /= c.batch;
    if (step == 1) f.loss_first = loss;
    f.loss_last = loss;
    // Step sizes decay geometrically from lr to kLrFinal lr over the steps (R1-NRF-011).
    const double lr_scale = std::pow(kLrFinal, static_cast<double>(step - 1) / std::max(1u, c.steps - 1));
    adam_mlp.begin_step(step, c.lr_mlp * lr_scale);
    adam_grid.begin_step(step, c.lr_grid * lr_scale);
    // The MLP: every parameter's gradient summed over the chunks in chunk order, then its step.
    if (mlp) {
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n_mlp, 512), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t k = range.begin(); k != range.end(); ++k) {
          float gsum = 0.0f;
          for (const ChunkGrad& g : cg) gsum += g.mlp[k];
          adam_mlp.step(*params[k], k, gsum);
        }
      });
    }
    // The grid: each level adds the chunks' contributions to it, in chunk order, then steps the
    // entries it touched.
    tbb::parallel_for(std::uint32_t{0}, c.levels, [&](std::uint32_t l) {
      for (std::uint32_t chunk = 0; chunk < chunks; ++chunk) {
        const std::size_t rows = std::min(c.batch, (chunk + 1) * kChunk) - chunk * kChunk;
        const Contribution* from = cg[chunk].grid.data() + static_cast<std::size_t>(l) * kChunk * 8;
        for (const Contribution* e = from; e != from + rows * 8; ++e) {
          const std::uint32_t idx = e->idx;
          touched[idx / kNeuralFeatures] = 1;
          grid_grad[idx] += e->g[0];
          grid_grad[idx + 1] += e->g[1];
        }
      }
      // The level's touched entries in index order (each step is independent of the others): a
      // linear sweep over the part of the level's slice it can use.
      const std::size_t res1 = std::size_t{f.resolution[l]} + 1;
      const std::size_t first_entry = static_cast<std::size_t>(l) * table;
      const std::size_t end_entry = first_entry + std::min<std::size_t>(table, res1 * res1 * res1);
      for (std::size_t entry = first_entry; entry < end_entry; ++entry) {
        if (!touched[entry]) continue;
        touched[entry] = 0;
        for (std::size_t q = entry * kNeuralFeatures; q < (entry + 1) * kNeuralFeatures; ++q) {
          adam_grid.step(f.grid[q], q, grid_grad[q]);
          grid_grad[q] = 0.0f;
        }
      }
    });
    report(progress, "train-field: Adam steps", step, c.steps);
  }
}

}  // namespace

detail::LossGradient detail::neural_loss_gradient(const Scene& s, const NeuralField& f, std::uint32_t points, std::uint64_t seed) {
  std::vector<std::uint32_t> every(s.n);
  for (std::uint32_t p = 0; p < s.n; ++p) every[p] = p;
  const std::vector<Sample> set = make_set(s, f, points, seed ^ kDataSeed, every, nullptr, {});
  const SetMoments mo = moments(set);
  std::size_t n_mlp = 0;
  for (const std::vector<float>* v : mlp_parts(f)) n_mlp += v->size();
  LossGradient out;
  out.gradient.assign(n_mlp, 0.0f);
  std::vector<float> chunk(n_mlp);
  const std::size_t corners = std::size_t{f.config.levels} * 8;
  std::vector<std::uint32_t> index(corners);
  std::vector<float> weight(corners), mask(f.config.levels);
  for (std::uint32_t begin = 0; begin < points; begin += kChunk) {
    const std::uint32_t rows = std::min(kChunk, points - begin);
    Mat X(rows, f.inputs()), dX;
    const Sample* pts[kChunk];
    for (std::uint32_t r = 0; r < rows; ++r) {
      const Location e{index.data(), weight.data(), mask.data()};
      locate(f, set[begin + r].q, e);
      gather(f, e, set[begin + r].q.t, X.row(r).data());
      pts[r] = &set[begin + r];
    }
    out.loss += backward(f, X, pts, mo.head_weight, 1.0 / points, chunk.data(), dX);
    for (std::size_t k = 0; k < n_mlp; ++k) out.gradient[k] += chunk[k];
  }
  out.loss /= points;
  return out;
}

Result<NeuralField> train_neural_field(const Scene& s, const NeuralConfig& c, std::uint64_t seed,
                                       const ProgressFn& progress) {
  if (s.n == 0) return Status::input("train-field: the epoch has no particles");
  if (!architecture_in_range(c) || c.samples < 1 || c.batch < 1 || c.base_resolution < 1)
    return Status::input("train-field: configuration out of range");
  std::unique_ptr<tbb::global_control> limit;
  if (c.threads > 0)
    limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, c.threads);
  NeuralField f = init_field(s, c, seed);
  std::vector<std::uint32_t> every(s.n);
  for (std::uint32_t p = 0; p < s.n; ++p) every[p] = p;
  const std::vector<Sample> set = make_set(s, f, c.samples, seed ^ kDataSeed, every, nullptr, progress);
  fit(f, set, c.batch, c.steps, true, true, progress);
  return f;
}

SceneChange scene_change(std::span<const hemera::Digest> prev_ids, const Scene& prev, std::span<const hemera::Digest> next_ids,
                         const Scene& next) {
  SceneChange c;
  if (prev_ids.size() != next_ids.size() || prev.n != next.n || next.n != next_ids.size()) {
    c.reason = "particles were added or dropped (every field weight n phi moves)";
    return c;
  }
  if (!std::equal(prev_ids.begin(), prev_ids.end(), next_ids.begin())) {
    c.reason = "the particles are in another order";
    return c;
  }
  c.comparable = true;
  for (std::uint32_t p = 0; p < next.n; ++p) {
    const Vec3 &a = prev.position[p], &b = next.position[p], &ca = prev.color[p], &cb = next.color[p];
    if (a.x == b.x && a.y == b.y && a.z == b.z && prev.phi[p] == next.phi[p] && ca.x == cb.x && ca.y == cb.y && ca.z == cb.z)
      continue;
    if (c.changed++ == 0) c.lo = c.hi = a;
    for (const Vec3& x : {a, b}) {
      c.lo = Vec3{std::min(c.lo.x, x.x), std::min(c.lo.y, x.y), std::min(c.lo.z, x.z)};
      c.hi = Vec3{std::max(c.hi.x, x.x), std::max(c.hi.y, x.y), std::max(c.hi.z, x.z)};
    }
  }
  return c;
}

Result<NeuralField> update_neural_field(const Scene& s, const NeuralField& prev, const Vec3& lo, const Vec3& hi,
                                        std::uint64_t seed, std::uint32_t samples, std::uint32_t steps,
                                        const ProgressFn& progress) {
  if (s.n == 0) return Status::input("train-field: the epoch has no particles");
  if (samples < 1 || steps < 1) return Status::input("train-field: configuration out of range");
  NeuralField f = prev;
  f.seed = seed;
  ++f.local_updates;
  // The box: the changed particles' box grown by the finest kernel's reach, inside the cube.
  const double grow = 3 * std::sqrt(f.tau_lo);
  const Vec3 cube_hi = f.lo + Vec3{f.size, f.size, f.size};
  const Vec3 b_lo{std::max(lo.x - grow, f.lo.x), std::max(lo.y - grow, f.lo.y), std::max(lo.z - grow, f.lo.z)};
  const Vec3 b_hi{std::min(hi.x + grow, cube_hi.x), std::min(hi.y + grow, cube_hi.y), std::min(hi.z + grow, cube_hi.z)};
  if (!(b_lo.x < b_hi.x && b_lo.y < b_hi.y && b_lo.z < b_hi.z)) return Status::input("train-field: the update box is empty");
  f.update_lo = b_lo;
  f.update_hi = b_hi;
  // The prior is the new scene's moments on the field's grid (parts whose particles did not change
  // keep their bits); a field before version 4 keeps its one part.
  if (f.prior_cells > 0) f.prior_parts = prior_parts_of(s, f.prior_cells, f.prior_lo, f.prior_hi);
  const std::pair<Vec3, Vec3> box{b_lo, b_hi - b_lo};
  std::vector<std::uint32_t> pool;
  for (std::uint32_t p = 0; p < s.n; ++p) {
    const Vec3& x = s.position[p];
    if (x.x >= b_lo.x && x.x <= b_hi.x && x.y >= b_lo.y && x.y <= b_hi.y && x.z >= b_lo.z && x.z <= b_hi.z) pool.push_back(p);
  }
  std::vector<Sample> set = make_set(s, f, samples, seed ^ kDataSeed, pool, &box, progress);
  fit(f, set, std::min(f.config.batch, samples), steps, false, false, progress);
  return f;
}

// ---- file (R1-NRF-030) ------------------------------------------------------------------------

namespace {
constexpr char kMagic[8] = {'r', '1', '-', 'n', 'r', 'f', '\0', '\5'};
constexpr char kMagicV4[8] = {'r', '1', '-', 'n', 'r', 'f', '\0', '\4'};
constexpr char kMagicV3[8] = {'r', '1', '-', 'n', 'r', 'f', '\0', '\3'};
constexpr char kMagicV2[8] = {'r', '1', '-', 'n', 'r', 'f', '\0', '\2'};
constexpr char kMagicV1[8] = {'r', '1', '-', 'n', 'r', 'f', '\0', '\1'};
void put_floats(std::string& out, const std::vector<float>& v) {
  for (const float x : v) format::put_f32(out, x);
}
}  // namespace

std::string encode_neural_field(const NeuralField& f, std::span<const std::uint8_t> snapshot) {
  std::string out(kMagic, sizeof kMagic);
  format::put_bytes(out, snapshot);
  const NeuralConfig& c = f.config;
  for (const std::uint32_t v : {c.levels, c.log2_table, c.base_resolution, c.hidden, c.samples, c.batch, c.steps})
    format::put_u32(out, v);
  format::put_f64(out, c.lr_grid);
  format::put_f64(out, c.lr_mlp);
  for (const std::uint32_t r : f.resolution) format::put_u32(out, r);
  for (const double v : {f.lo.x, f.lo.y, f.lo.z, f.size, f.centroid.x, f.centroid.y, f.centroid.z, f.tau_lo, f.tau_hi, f.kappa,
                         f.loss_first, f.loss_last})
    format::put_f64(out, v);
  format::put_u64(out, f.seed);
  format::put_u32(out, f.local_updates);
  for (const double v : {f.update_lo.x, f.update_lo.y, f.update_lo.z, f.update_hi.x, f.update_hi.y, f.update_hi.z})
    format::put_f64(out, v);
  format::put_u32(out, f.prior_cells);
  for (const double v : {f.prior_lo.x, f.prior_lo.y, f.prior_lo.z, f.prior_hi.x, f.prior_hi.y, f.prior_hi.z}) format::put_f64(out, v);
  format::put_u32(out, static_cast<std::uint32_t>(f.prior_parts.size()));
  for (const NeuralField::PriorPart& p : f.prior_parts) {
    for (const double v : {p.mass, p.s2, p.centroid.x, p.centroid.y, p.centroid.z, p.colour.x, p.colour.y, p.colour.z})
      format::put_f64(out, v);
    for (const double v : p.gradient) format::put_f64(out, v);
  }
  format::put_u32(out, f.fade_power);
  format::put_u32(out, c.block);
  for (const auto* v : {&f.grid, &f.w1, &f.b1, &f.w2, &f.b2, &f.w3, &f.b3, &f.wc, &f.bc, &f.wg, &f.bg, &f.gamma}) put_floats(out, *v);
  const hemera::Digest d = hemera::hash(std::span(reinterpret_cast<const std::uint8_t*>(out.data()), out.size()));
  format::put_bytes(out, d);
  return out;
}

Result<NeuralField> decode_neural_field(std::string_view bytes, const std::string& name,
                                        std::span<const std::uint8_t> snapshot) {
  const std::size_t kDigest = sizeof(hemera::Digest);
  if (bytes.size() < sizeof kMagic + kDigest) return Status::input(name + ": not an r1 neural field (r1-nrf version 1 to 5)");
  const std::string_view magic = bytes.substr(0, sizeof kMagic);
  const bool v1 = magic == std::string_view(kMagicV1, sizeof kMagicV1), v2 = magic == std::string_view(kMagicV2, sizeof kMagicV2),
             v3 = magic == std::string_view(kMagicV3, sizeof kMagicV3), v4 = magic == std::string_view(kMagicV4, sizeof kMagicV4);
  if (!v1 && !v2 && !v3 && !v4 && magic != std::string_view(kMagic, sizeof kMagic))
    return Status::input(name + ": not an r1 neural field (r1-nrf version 1 to 5)");
  const std::string_view body = bytes.substr(0, bytes.size() - kDigest);
  const hemera::Digest d = hemera::hash(std::span(reinterpret_cast<const std::uint8_t*>(body.data()), body.size()));
  if (!std::equal(d.begin(), d.end(), reinterpret_cast<const std::uint8_t*>(bytes.data() + body.size())))
    return Status::input(name + ": digest mismatch (truncated or altered)");
  format::ByteReader r(body, name);
  r.skip(sizeof kMagic);
  hemera::Digest snap{};
  if (!r.bytes(snap)) return r.error("truncated");
  if (snapshot.size() != snap.size() || !std::equal(snap.begin(), snap.end(), snapshot.begin()))
    return r.error("trained for another snapshot");
  NeuralField f;
  NeuralConfig& c = f.config;
  for (std::uint32_t* v : {&c.levels, &c.log2_table, &c.base_resolution, &c.hidden, &c.samples, &c.batch, &c.steps})
    if (!r.u32(*v)) return r.error("truncated");
  if (!r.f64(c.lr_grid) || !r.f64(c.lr_mlp)) return r.error("truncated");
  if (!architecture_in_range(c)) return r.error("architecture out of range");
  f.resolution.resize(c.levels);
  for (std::uint32_t& v : f.resolution)
    if (!r.u32(v) || v < 1 || v > 65536) return r.error("bad resolution");
  for (double* v : {&f.lo.x, &f.lo.y, &f.lo.z, &f.size, &f.centroid.x, &f.centroid.y, &f.centroid.z, &f.tau_lo, &f.tau_hi,
                    &f.kappa, &f.loss_first, &f.loss_last})
    if (!r.f64(*v)) return r.error("truncated");
  if (!(f.size > 0) || !(f.tau_lo > 0) || !(f.tau_hi >= f.tau_lo) || !std::isfinite(f.size) || !std::isfinite(f.tau_hi) ||
      !std::isfinite(f.centroid.x) || !std::isfinite(f.centroid.y) || !std::isfinite(f.centroid.z))
    return r.error("bad cube or tau range");
  if (!r.u64(f.seed)) return r.error("truncated");
  if (!v1) {
    if (!r.u32(f.local_updates)) return r.error("truncated");
    for (double* v : {&f.update_lo.x, &f.update_lo.y, &f.update_lo.z, &f.update_hi.x, &f.update_hi.y, &f.update_hi.z})
      if (!r.f64(*v) || !std::isfinite(*v)) return r.error("bad update box");
  }
  f.fade_power = 2;
  if (!v1 && !v2) {
    // Version 3: one part about the field's centroid, its mass 0 when there is none; version 4: a
    // count of parts, each of positive mass.
    std::uint32_t parts = 1;
    if (!v3) {
      if (!r.u32(f.prior_cells) || f.prior_cells < 1 || f.prior_cells > 16) return r.error("bad prior grid");
      for (double* v : {&f.prior_lo.x, &f.prior_lo.y, &f.prior_lo.z, &f.prior_hi.x, &f.prior_hi.y, &f.prior_hi.z})
        if (!r.f64(*v) || !std::isfinite(*v)) return r.error("bad prior grid");
      if (!r.u32(parts) || parts > std::uint64_t{f.prior_cells} * f.prior_cells * f.prior_cells) return r.error("bad prior part count");
    }
    for (std::uint32_t k = 0; k < parts; ++k) {
      NeuralField::PriorPart p;
      p.centroid = f.centroid;
      if (!r.f64(p.mass) || !r.f64(p.s2)) return r.error("truncated");
      if (!(p.mass >= 0) || !(p.s2 >= 0) || !std::isfinite(p.mass) || !std::isfinite(p.s2) || (!v3 && !(p.mass > 0)))
        return r.error("bad prior");
      std::vector<double*> rest;
      if (!v3) rest = {&p.centroid.x, &p.centroid.y, &p.centroid.z};
      for (double* v : {&p.colour.x, &p.colour.y, &p.colour.z}) rest.push_back(v);
      for (double& v : p.gradient) rest.push_back(&v);
      for (double* v : rest)
        if (!r.f64(*v) || !std::isfinite(*v)) return r.error("bad prior");
      if (p.mass > 0) f.prior_parts.push_back(p);
    }
    if (!r.u32(f.fade_power)) return r.error("truncated");
    if (f.fade_power != 2 && f.fade_power != 4) return r.error("bad fade power (2 or 4)");
  }
  // Version 5: the Clifford block's width (0: none).
  if (!v1 && !v2 && !v3 && !v4) {
    if (!r.u32(c.block)) return r.error("truncated");
    if (!architecture_in_range(c)) return r.error("bad Clifford block width (0, or half the hidden width)");
  }
  const std::uint32_t ni = f.inputs(), nh = c.hidden;
  const std::size_t bw = c.block, nf = 2 * kNeuralShifts.size() * bw;
  const std::size_t sizes[12] = {static_cast<std::size_t>(c.levels) << c.log2_table << 1,
                                 static_cast<std::size_t>(nh) * ni, nh,
                                 static_cast<std::size_t>(nh) * nh, nh,
                                 static_cast<std::size_t>(kNeuralOutputs) * nh, kNeuralOutputs,
                                 bw * nf, bw, bw * 2 * bw, bw, bw};
  std::vector<float>* dst[12] = {&f.grid, &f.w1, &f.b1, &f.w2, &f.b2, &f.w3, &f.b3, &f.wc, &f.bc, &f.wg, &f.bg, &f.gamma};
  for (int k = 0; k < 12; ++k) {
    if (r.left() < sizes[k] * 4) return r.error("truncated");
    dst[k]->resize(sizes[k]);
    for (float& x : *dst[k]) {
      std::uint32_t bits = 0;
      r.u32(bits);  // the length was checked above
      x = std::bit_cast<float>(bits);
      if (!std::isfinite(x)) return r.error("non-finite parameter");
    }
  }
  if (r.left() != 0) return r.error("trailing bytes");
  return f;
}

}  // namespace r1::render
