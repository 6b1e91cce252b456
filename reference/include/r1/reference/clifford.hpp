// The Clifford primitives of the 13.1 backend trait in fp64 (roll, shifted_inner, shifted_wedge, clifford_block, graph context), R1-RND-100..107.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "r1/spec/graph.hpp"
#include "r1/spec/status.hpp"

namespace r1::clifford {

// A dense row-major n x d tensor of doubles: element (i, c) is v[i * d + c]. Rows are samples
// (particles, ray samples), columns are channels. Valid when d >= 1 and v.size() == n * d;
// n = 0 (no rows) is allowed (R1-RND-100).
struct Rows {
  std::uint32_t n = 0, d = 0;
  std::vector<double> v;

  double& at(std::uint32_t i, std::uint32_t c) { return v[std::size_t{i} * d + c]; }
  double at(std::uint32_t i, std::uint32_t c) const { return v[std::size_t{i} * d + c]; }
};

// A zero-filled n x d tensor.
Rows zeros(std::uint32_t n, std::uint32_t d);

// ---- deterministic scalar functions (R1-RND-101) ------------------------------------------------

// e^x from +, -, *, / and exact power-of-two scaling only (no libm), so the bytes are the same on
// every IEEE-754 machine built without FMA contraction: x = k ln2 + r (Cody-Waite, two-part ln2),
// |r| <= ln2/2, e^r as the degree-13 Taylor polynomial (Horner), times 2^k. Relative error below
// 1e-15 on normal results. x > 710 gives +inf, x < -746 gives +0, NaN gives NaN.
double det_exp(double x);

namespace detail {
// ln 2 split for the Cody-Waite reduction (|kLn2Hi + kLn2Lo - ln 2| < 2^-85): kLn2Hi has 33
// significant bits (its low 20 fraction bits are zero), so k * kLn2Hi is exact for every
// |k| < 2^20 (the reduction uses |k| <= 1077); kLn2Lo carries the next 53 bits.
inline constexpr double kLn2Hi = 0x1.62e42feep-1;
inline constexpr double kLn2Lo = 0x1.a39ef35793c76p-33;
// Why 13: the Taylor remainder of e^r at |r| = ln2/2 is r^14 / 14! < 5e-18, under 1/20 ulp.
inline constexpr int kExpDegree = 13;
// log2(e) rounded to double; it only picks k = round(x / ln 2), so its last bit does not matter.
inline constexpr double kLog2e = 0x1.71547652b82fep0;
// The Taylor coefficients 1/n!, n = 0..kExpDegree, that det_exp evaluates (for devices that run
// the same evaluation, R1-BKD-062).
std::array<double, kExpDegree + 1> exp_taylor();
}  // namespace detail
// SiLU(x) = x / (1 + det_exp(-x)) and sigmoid(x) = 1 / (1 + det_exp(-x)).
double silu(double x);
double sigmoid(double x);

// ---- the trait primitives (R1-RND-102..105) -----------------------------------------------------

// Cyclic shift with numpy.roll's direction: axis 1 (channels) gives
// out(i, c) = x(i, (c - shift) mod d); axis 0 (rows) gives out(i, c) = x((i - shift) mod n, c).
// Any shift is allowed (negative, >= the axis length). Input error for another axis or a
// malformed tensor.
Result<Rows> roll(const Rows& x, std::int32_t shift, std::uint32_t axis);

// Inner_s(h, c)(i, ch) = SiLU(h(i, ch) * c(i, (ch + s) mod d)) for every s in `shifts`, output
// n x (|S| d) with the block of shifts[k] at columns [k d, (k + 1) d). Input error for an empty
// shift set, a malformed tensor or h and c of different shapes.
Result<Rows> shifted_inner(const Rows& h, const Rows& c, std::span<const std::int32_t> shifts);
// Wedge_s(h, c)(i, ch) = h(i, ch) * c(i, ch + s) - h(i, ch + s) * c(i, ch) (indices mod d), same
// layout and errors as shifted_inner.
Result<Rows> shifted_wedge(const Rows& h, const Rows& c, std::span<const std::int32_t> shifts);

// y = x w + bias: x is n x k, w is k x m (rows are inputs, columns outputs), bias has m entries;
// y(i, o) = (sum over f = 0, 1, ..., k - 1 of x(i, f) w(f, o), accumulated left to right from
// +0) + bias(o). Input error on mismatched shapes.
Result<Rows> linear(const Rows& x, const Rows& w, std::span<const double> bias);

// Clifford(h, c; S) = linear(F, w, bias) with F the n x (2 |S| d) concatenation, shift by shift,
// of [Inner_s | Wedge_s]: the block of shifts[k] holds Inner at columns [2kd, 2kd + d) and Wedge
// at [2kd + d, 2kd + 2d). w must be (2 |S| d) x d and bias of size d.
Result<Rows> clifford(const Rows& h, const Rows& c, std::span<const std::int32_t> shifts, const Rows& w,
                      std::span<const double> bias);

// The parameters of one Clifford block for channel width d and |S| shifts.
struct BlockParams {
  Rows w;                      // (2 |S| d) x d, the Clifford linear map
  std::vector<double> bias;    // d
  Rows wg;                     // (2 d) x d, the gate's linear map over concat(H, G)
  std::vector<double> bg;      // d
  std::vector<double> gamma;   // d, the per-channel residual scale
};

// gamma's initial value: the layer scale CT-0 (REFERENCE.md section 3) initialises "near 1e-5",
// so a fresh block starts as a near-identity residual.
inline constexpr double kInitialGamma = 1e-5;

// Deterministic initial parameters from `seed` through the counter RNG (R1-RND-105):
// w(f, o) = (2 u - 1) / sqrt(2 |S| d) with u = rng::uniform_double(seed, f * d + o, 0), and
// wg(f, o) the same with dimension 1 and bound 1 / sqrt(2 d); bias = bg = 0; gamma = 1e-5.
// Input error for d = 0 or no shifts.
Result<BlockParams> init_block_params(std::uint32_t d, std::size_t shift_count, std::uint64_t seed);

// The residual half of the block for a given G (n x d like h):
// H_out(i, c) = h(i, c) + gamma(c) * (SiLU(h(i, c)) + gate(i, c) * g(i, c)),
// gate = sigmoid(linear(concat(h, g), wg, bg)) with concat(h, g)(i) = [h(i) | g(i)].
Result<Rows> block_residual(const Rows& h, const Rows& g, const BlockParams& params);

// The Clifford block of 7.1 item 3: block_residual(h, Clifford(h, c; S), params).
Result<Rows> clifford_block(const Rows& h, const Rows& c, std::span<const std::int32_t> shifts,
                            const BlockParams& params);

// ---- graph context (R1-RND-106) -----------------------------------------------------------------

// lambda of the graph context C = L H - lambda H (CT-0 on graphs, REFERENCE.md section 3: the
// Laplacian action replaces the image model's depthwise convolution, minus lambda = 1 times H).
inline constexpr double kGraphContextLambda = 1.0;

// Computes L H for an n x d H; must return an n x d tensor.
using LaplacianAction = std::function<Result<Rows>(const Rows&)>;

// The normalized Laplacian action on the layout graph's A_sym:
// (L H)(i, c) = H(i, c) - sum over stored j of row i, ascending, of (w_ij / sqrt(d_i d_j)) H(j, c),
// with w and the degrees d as Q32 raws converted to double (the 2^32 scale cancels). An isolated
// particle (empty row) gets (L H)(i) = H(i). Input error when h.n != g.n or the CSR is malformed.
Result<Rows> normalized_laplacian_action(const Graph& g, const Rows& h);

// C(i, c) = LH(i, c) - lambda * H(i, c), with LH = action(h) (its error is passed on; a result of
// another shape is an input error).
Result<Rows> graph_context(const Rows& h, const LaplacianAction& action, double lambda = kGraphContextLambda);
// The same with action = normalized_laplacian_action(g, .).
Result<Rows> graph_context(const Graph& g, const Rows& h, double lambda = kGraphContextLambda);

}  // namespace r1::clifford
