// The Clifford primitives of the 13.1 backend trait in fp64: deterministic exp, roll, shifted products, the Clifford block and the graph context (R1-RND-100..107).
#include "r1/reference/clifford.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <string>

#include "r1/fixedpoint/counter_rng.hpp"

namespace r1::clifford {

namespace {

// ---- deterministic exp ----------------------------------------------------------------------

using detail::kLog2e;
// e^710 > DBL_MAX (e^709.78...): every larger argument overflows, and clamping before the
// reduction keeps k inside int range for any finite or infinite x.
constexpr double kExpOverflow = 710.0;
// e^-746 < 2^-1075, half the least subnormal: every smaller argument rounds to +0.
constexpr double kExpUnderflow = -746.0;
// The smallest and largest exponents of a normal double: 2^k is a plain bit pattern between them.
constexpr int kMinNormalExp = -1022;
constexpr int kMaxNormalExp = 1023;
// The IEEE-754 binary64 exponent bias and the width of its fraction field.
constexpr int kExpBias = 1023;
constexpr int kFractionBits = 52;

// 1/n! for n = 0..kExpDegree, each from the previous by one correctly rounded division at compile
// time (the coefficient errors, a few ulps of 1/n!, are scaled by |r|^n <= 0.35^n in the result).
constexpr std::array<double, detail::kExpDegree + 1> taylor_coefficients() {
  std::array<double, detail::kExpDegree + 1> c{};
  c[0] = 1.0;
  for (int n = 1; n <= detail::kExpDegree; ++n) c[n] = c[n - 1] / n;
  return c;
}
constexpr auto kTaylor = taylor_coefficients();

// 2^k for a normal exponent, built from its bit pattern.
double pow2(int k) {
  return std::bit_cast<double>(static_cast<std::uint64_t>(k + kExpBias) << kFractionBits);
}

// ---- validation -----------------------------------------------------------------------------

std::string shape(const Rows& x) { return std::to_string(x.n) + " x " + std::to_string(x.d); }

Status check_rows(const Rows& x, const char* what) {
  if (x.d == 0) return Status::input(std::string("clifford: ") + what + " has no channels (d = 0)");
  if (x.v.size() != std::uint64_t{x.n} * x.d)
    return Status::input(std::string("clifford: ") + what + " holds " + std::to_string(x.v.size()) +
                         " values, not the " + shape(x) + " its shape says");
  return Status::ok();
}

Status check_pair(const Rows& h, const Rows& c, std::span<const std::int32_t> shifts) {
  R1_TRY(check_rows(h, "H"));
  R1_TRY(check_rows(c, "C"));
  if (h.n != c.n || h.d != c.d)
    return Status::input("clifford: H is " + shape(h) + " but C is " + shape(c) + "; they must match");
  if (shifts.empty()) return Status::input("clifford: the shift set is empty");
  return Status::ok();
}

// s mod m in [0, m) for any 32-bit s (64-bit arithmetic, so INT32_MIN is fine).
std::uint32_t mod(std::int64_t s, std::uint32_t m) {
  const std::int64_t r = s % static_cast<std::int64_t>(m);
  return static_cast<std::uint32_t>(r < 0 ? r + m : r);
}

// The two shifted products at (i, ch) with partner channel j = (ch + s) mod d.
double inner_at(const Rows& h, const Rows& c, std::uint32_t i, std::uint32_t ch, std::uint32_t j) {
  return silu(h.at(i, ch) * c.at(i, j));
}
double wedge_at(const Rows& h, const Rows& c, std::uint32_t i, std::uint32_t ch, std::uint32_t j) {
  return h.at(i, ch) * c.at(i, j) - h.at(i, j) * c.at(i, ch);
}

// Writes Inner (inner = true) or Wedge of every shift into out, the block of shifts[k] at columns
// [offset + k * stride, offset + k * stride + d).
void shifted(const Rows& h, const Rows& c, std::span<const std::int32_t> shifts, bool inner, Rows& out,
             std::uint32_t offset, std::uint32_t stride) {
  for (std::uint32_t i = 0; i < h.n; ++i)
    for (std::size_t k = 0; k < shifts.size(); ++k) {
      const std::uint32_t s = mod(shifts[k], h.d);
      const auto base = static_cast<std::uint32_t>(offset + k * stride);
      for (std::uint32_t ch = 0; ch < h.d; ++ch) {
        const std::uint32_t j = ch + s < h.d ? ch + s : ch + s - h.d;
        out.at(i, base + ch) = inner ? inner_at(h, c, i, ch, j) : wedge_at(h, c, i, ch, j);
      }
    }
}

// |S| d and 2 |S| d as 32-bit widths, or an input error when they do not fit.
Result<std::uint32_t> width(std::uint32_t d, std::size_t shift_count, std::uint32_t factor) {
  const std::uint64_t w = std::uint64_t{d} * shift_count * factor;
  if (shift_count > std::numeric_limits<std::uint32_t>::max() || w > std::numeric_limits<std::uint32_t>::max())
    return Status::input("clifford: " + std::to_string(shift_count) + " shifts of " + std::to_string(d) +
                         " channels are too many columns");
  return static_cast<std::uint32_t>(w);
}

Status check_vector(std::span<const double> b, std::uint32_t d, const char* what) {
  if (b.size() != d)
    return Status::input(std::string("clifford: ") + what + " has " + std::to_string(b.size()) +
                         " entries, not " + std::to_string(d));
  return Status::ok();
}

}  // namespace

std::array<double, detail::kExpDegree + 1> detail::exp_taylor() { return kTaylor; }

Rows zeros(std::uint32_t n, std::uint32_t d) { return Rows{n, d, std::vector<double>(std::size_t{n} * d, 0.0)}; }

double det_exp(double x) {
  if (x != x) return x;  // NaN
  if (x > kExpOverflow) return std::numeric_limits<double>::infinity();
  if (x < kExpUnderflow) return 0.0;
  // k = round(x / ln 2), halves away from zero; |t| < 1077, so the conversion is exact.
  const double t = x * kLog2e;
  const int k = static_cast<int>(t >= 0 ? t + 0.5 : t - 0.5);
  const double kd = k;
  const double r = (x - kd * detail::kLn2Hi) - kd * detail::kLn2Lo;
  double p = kTaylor[detail::kExpDegree];
  for (int n = detail::kExpDegree - 1; n >= 0; --n) p = p * r + kTaylor[static_cast<std::size_t>(n)];
  if (k >= kMinNormalExp && k <= kMaxNormalExp) return p * pow2(k);  // exact scaling
  // Past the normal exponents: two factors, each normal; the first product is exact, so the
  // result is rounded once (to a subnormal, or to +inf).
  const int k1 = k / 2;
  return p * pow2(k1) * pow2(k - k1);
}

double silu(double x) { return x / (1.0 + det_exp(-x)); }
double sigmoid(double x) { return 1.0 / (1.0 + det_exp(-x)); }

Result<Rows> roll(const Rows& x, std::int32_t shift, std::uint32_t axis) {
  R1_TRY(check_rows(x, "the tensor"));
  if (axis > 1) return Status::input("clifford: roll axis must be 0 (rows) or 1 (channels), got " + std::to_string(axis));
  Rows out = zeros(x.n, x.d);
  if (x.n == 0) return out;
  if (axis == 1) {
    const std::uint32_t s = mod(shift, x.d);
    for (std::uint32_t i = 0; i < x.n; ++i)
      for (std::uint32_t c = 0; c < x.d; ++c) out.at(i, c + s < x.d ? c + s : c + s - x.d) = x.at(i, c);
  } else {
    const std::uint32_t s = mod(shift, x.n);
    for (std::uint32_t i = 0; i < x.n; ++i) {
      const std::uint32_t to = i + s < x.n ? i + s : i + s - x.n;
      for (std::uint32_t c = 0; c < x.d; ++c) out.at(to, c) = x.at(i, c);
    }
  }
  return out;
}

Result<Rows> shifted_inner(const Rows& h, const Rows& c, std::span<const std::int32_t> shifts) {
  R1_TRY(check_pair(h, c, shifts));
  R1_ASSIGN(const std::uint32_t cols, width(h.d, shifts.size(), 1));
  Rows out = zeros(h.n, cols);
  shifted(h, c, shifts, true, out, 0, h.d);
  return out;
}

Result<Rows> shifted_wedge(const Rows& h, const Rows& c, std::span<const std::int32_t> shifts) {
  R1_TRY(check_pair(h, c, shifts));
  R1_ASSIGN(const std::uint32_t cols, width(h.d, shifts.size(), 1));
  Rows out = zeros(h.n, cols);
  shifted(h, c, shifts, false, out, 0, h.d);
  return out;
}

Result<Rows> linear(const Rows& x, const Rows& w, std::span<const double> bias) {
  R1_TRY(check_rows(x, "the linear input"));
  R1_TRY(check_rows(w, "the weight matrix"));
  if (w.n != x.d)
    return Status::input("clifford: a linear map of " + shape(w) + " cannot take rows of " + std::to_string(x.d) +
                         " features");
  R1_TRY(check_vector(bias, w.d, "the bias"));
  Rows y = zeros(x.n, w.d);
  for (std::uint32_t i = 0; i < x.n; ++i) {
    // Row by row of w, so each y(i, o) sums x(i, f) w(f, o) over ascending f from +0.
    for (std::uint32_t f = 0; f < x.d; ++f) {
      const double xf = x.at(i, f);
      for (std::uint32_t o = 0; o < w.d; ++o) y.at(i, o) += xf * w.at(f, o);
    }
    for (std::uint32_t o = 0; o < w.d; ++o) y.at(i, o) += bias[o];
  }
  return y;
}

Result<Rows> clifford(const Rows& h, const Rows& c, std::span<const std::int32_t> shifts, const Rows& w,
                      std::span<const double> bias) {
  R1_TRY(check_pair(h, c, shifts));
  R1_ASSIGN(const std::uint32_t cols, width(h.d, shifts.size(), 2));
  R1_TRY(check_rows(w, "the Clifford weight matrix"));
  if (w.n != cols || w.d != h.d)
    return Status::input("clifford: the Clifford weight matrix is " + shape(w) + ", expected " + std::to_string(cols) +
                         " x " + std::to_string(h.d) + " (2 |S| d x d)");
  Rows features = zeros(h.n, cols);
  shifted(h, c, shifts, true, features, 0, 2 * h.d);
  shifted(h, c, shifts, false, features, h.d, 2 * h.d);
  return linear(features, w, bias);
}

Result<BlockParams> init_block_params(std::uint32_t d, std::size_t shift_count, std::uint64_t seed) {
  if (d == 0) return Status::input("clifford: a block needs at least one channel (d = 0)");
  if (shift_count == 0) return Status::input("clifford: the shift set is empty");
  R1_ASSIGN(const std::uint32_t cols, width(d, shift_count, 2));
  BlockParams p;
  // Uniform in [-1/sqrt(fan_in), 1/sqrt(fan_in)): the usual scale that keeps a fresh linear map's
  // outputs of the order of its inputs; dimension 0 draws w, dimension 1 draws wg.
  const auto draw = [&](std::uint32_t fan_in, std::uint64_t dim) {
    Rows m = zeros(fan_in, d);
    const double bound = 1.0 / std::sqrt(static_cast<double>(fan_in));  // sqrt: correctly rounded
    for (std::size_t e = 0; e < m.v.size(); ++e) m.v[e] = (2.0 * rng::uniform_double(seed, e, dim) - 1.0) * bound;
    return m;
  };
  p.w = draw(cols, 0);
  p.wg = draw(2 * d, 1);
  p.bias.assign(d, 0.0);
  p.bg.assign(d, 0.0);
  p.gamma.assign(d, kInitialGamma);
  return p;
}

Result<Rows> block_residual(const Rows& h, const Rows& g, const BlockParams& params) {
  R1_TRY(check_rows(h, "H"));
  R1_TRY(check_rows(g, "G"));
  if (h.n != g.n || h.d != g.d)
    return Status::input("clifford: H is " + shape(h) + " but G is " + shape(g) + "; they must match");
  R1_TRY(check_vector(params.gamma, h.d, "gamma"));
  if (params.wg.n != 2 * std::uint64_t{h.d} || params.wg.d != h.d)
    return Status::input("clifford: the gate weight matrix is " + shape(params.wg) + ", expected " +
                         std::to_string(2 * std::uint64_t{h.d}) + " x " + std::to_string(h.d) + " (2 d x d)");
  Rows hg = zeros(h.n, 2 * h.d);
  for (std::uint32_t i = 0; i < h.n; ++i)
    for (std::uint32_t ch = 0; ch < h.d; ++ch) {
      hg.at(i, ch) = h.at(i, ch);
      hg.at(i, h.d + ch) = g.at(i, ch);
    }
  R1_ASSIGN(Rows gate, linear(hg, params.wg, params.bg));
  Rows out = zeros(h.n, h.d);
  for (std::uint32_t i = 0; i < h.n; ++i)
    for (std::uint32_t ch = 0; ch < h.d; ++ch) {
      const double x = h.at(i, ch);
      out.at(i, ch) = x + params.gamma[ch] * (silu(x) + sigmoid(gate.at(i, ch)) * g.at(i, ch));
    }
  return out;
}

Result<Rows> clifford_block(const Rows& h, const Rows& c, std::span<const std::int32_t> shifts,
                            const BlockParams& params) {
  R1_ASSIGN(const Rows g, clifford(h, c, shifts, params.w, params.bias));
  return block_residual(h, g, params);
}

Result<Rows> normalized_laplacian_action(const Graph& g, const Rows& h) {
  R1_TRY(check_rows(h, "H"));
  if (h.n != g.n)
    return Status::input("clifford: H has " + std::to_string(h.n) + " rows but the graph " + std::to_string(g.n) +
                         " particles");
  if (g.row_ptr.size() != std::size_t{g.n} + 1 || g.degree.size() != g.n || g.w.size() != g.col.size() ||
      g.row_ptr.front() != 0 || g.row_ptr.back() != g.col.size())
    return Status::input("clifford: malformed layout graph (CSR sizes)");
  Rows out = zeros(h.n, h.d);
  std::vector<double> acc(h.d);
  for (std::uint32_t i = 0; i < g.n; ++i) {
    if (g.row_ptr[i] > g.row_ptr[i + 1]) return Status::input("clifford: malformed layout graph (row pointers)");
    std::fill(acc.begin(), acc.end(), 0.0);
    const auto di = static_cast<double>(g.degree[i]);
    for (std::uint64_t e = g.row_ptr[i]; e < g.row_ptr[i + 1]; ++e) {
      const std::uint32_t j = g.col[e];
      if (j >= g.n || g.degree[i] == 0 || g.degree[j] == 0)
        return Status::input("clifford: malformed layout graph (link " + std::to_string(i) + " -> " +
                             std::to_string(j) + ")");
      const double coef = static_cast<double>(g.w[e]) / std::sqrt(di * static_cast<double>(g.degree[j]));
      for (std::uint32_t ch = 0; ch < h.d; ++ch) acc[ch] += coef * h.at(j, ch);
    }
    for (std::uint32_t ch = 0; ch < h.d; ++ch) out.at(i, ch) = h.at(i, ch) - acc[ch];
  }
  return out;
}

Result<Rows> graph_context(const Rows& h, const LaplacianAction& action, double lambda) {
  R1_TRY(check_rows(h, "H"));
  if (!action) return Status::input("clifford: no Laplacian action given");
  R1_ASSIGN(Rows lh, action(h));
  if (lh.n != h.n || lh.d != h.d || lh.v.size() != h.v.size())
    return Status::input("clifford: the Laplacian action returned " + shape(lh) + " for H of " + shape(h));
  for (std::size_t e = 0; e < lh.v.size(); ++e) lh.v[e] = lh.v[e] - lambda * h.v[e];
  return lh;
}

Result<Rows> graph_context(const Graph& g, const Rows& h, double lambda) {
  return graph_context(h, [&g](const Rows& x) { return normalized_laplacian_action(g, x); }, lambda);
}

}  // namespace r1::clifford
