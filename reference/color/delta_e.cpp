// sRGB -> XYZ -> CIELAB and the CIE76 / CIEDE2000 colour differences (spec/render.md
// R1-RND-110..111).
#include "r1/color/delta_e.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace r1::color {

namespace {

using Mat3 = std::array<std::array<double, 3>, 3>;

// The inverse of a 3x3 matrix by cofactors (constexpr: the sRGB matrix is built at compile time).
constexpr Mat3 inverse(const Mat3& m) {
  const double c00 = m[1][1] * m[2][2] - m[1][2] * m[2][1];
  const double c01 = m[1][2] * m[2][0] - m[1][0] * m[2][2];
  const double c02 = m[1][0] * m[2][1] - m[1][1] * m[2][0];
  const double det = m[0][0] * c00 + m[0][1] * c01 + m[0][2] * c02;
  Mat3 r{};
  r[0] = {c00 / det, (m[0][2] * m[2][1] - m[0][1] * m[2][2]) / det, (m[0][1] * m[1][2] - m[0][2] * m[1][1]) / det};
  r[1] = {c01 / det, (m[0][0] * m[2][2] - m[0][2] * m[2][0]) / det, (m[0][2] * m[1][0] - m[0][0] * m[1][2]) / det};
  r[2] = {c02 / det, (m[0][1] * m[2][0] - m[0][0] * m[2][1]) / det, (m[0][0] * m[1][1] - m[0][1] * m[1][0]) / det};
  return r;
}

// The normalized primary matrix (SMPTE RP 177): columns are the primaries' XYZ (x/y, 1, z/y)
// scaled so that RGB (1, 1, 1) lands on the white. Primaries: ITU-R BT.709 / IEC 61966-2-1,
// R (0.64, 0.33), G (0.30, 0.60), B (0.15, 0.06); white: kD65White. The result agrees with the
// matrix IEC 61966-2-1 prints (0.4124 0.3576 0.1805 / 0.2126 0.7152 0.0722 / 0.0193 0.1192 0.9505)
// to its four decimals.
constexpr Mat3 srgb_to_xyz_matrix() {
  constexpr double x[3] = {0.64, 0.30, 0.15};
  constexpr double y[3] = {0.33, 0.60, 0.06};
  Mat3 p{};
  for (int k = 0; k < 3; ++k) {
    p[0][k] = x[k] / y[k];
    p[1][k] = 1.0;
    p[2][k] = (1.0 - x[k] - y[k]) / y[k];
  }
  const Mat3 inv = inverse(p);
  const double w[3] = {kD65White.X, kD65White.Y, kD65White.Z};
  Mat3 m{};
  for (int k = 0; k < 3; ++k) {
    const double s = inv[k][0] * w[0] + inv[k][1] * w[1] + inv[k][2] * w[2];
    for (int i = 0; i < 3; ++i) m[i][k] = p[i][k] * s;
  }
  return m;
}

constexpr Mat3 kSrgbToXyz = srgb_to_xyz_matrix();

// CIE 15's CIELAB constants, exact: delta = 6/29 separates the cube root from the linear segment
// near black (the two meet with equal value and slope at t = delta^3).
constexpr double kDelta = 6.0 / 29.0;
constexpr double kDelta3 = kDelta * kDelta * kDelta;
constexpr double kLinearSlope = 1.0 / (3.0 * kDelta * kDelta);  // 841/108
constexpr double kLinearOffset = 4.0 / 29.0;

double lab_f(double t) { return t > kDelta3 ? std::cbrt(t) : t * kLinearSlope + kLinearOffset; }

// 25^7, CIEDE2000's chroma constant in G and R_C (chroma ~25 is where the a* rescaling fades).
constexpr double k25Pow7 = 6103515625.0;

double pow7(double v) {
  const double v2 = v * v;
  return v2 * v2 * v2 * v;
}

constexpr double kDegPerRad = 180.0 / std::numbers::pi;
constexpr double kRadPerDeg = std::numbers::pi / 180.0;

double cos_deg(double d) { return std::cos(d * kRadPerDeg); }
double sin_deg(double d) { return std::sin(d * kRadPerDeg); }

// The hue angle of (a', b) in degrees, [0, 360); 0 where a' = b = 0 (Sharma et al., eq. 4).
double hue_deg(double a_prime, double b) {
  if (a_prime == 0.0 && b == 0.0) return 0.0;
  const double h = std::atan2(b, a_prime) * kDegPerRad;
  return h < 0.0 ? h + 360.0 : h;
}

}  // namespace

double srgb_decode(double v) {
  // Clamp: display code values live in [0, 1]; outside it the curve is undefined (NaN -> 0).
  const double c = v > 0.0 ? std::min(v, 1.0) : 0.0;
  // IEC 61966-2-1's breakpoint and linear slope; the power segment has exponent 2.4 and offset
  // 0.055 (the standard's constants; they meet the linear segment at 0.04045 within 1e-7).
  if (c <= 0.04045) return c / 12.92;
  return std::pow((c + 0.055) / 1.055, 2.4);
}

Xyz linear_srgb_to_xyz(double r, double g, double b) {
  const Mat3& m = kSrgbToXyz;
  return {m[0][0] * r + m[0][1] * g + m[0][2] * b, m[1][0] * r + m[1][1] * g + m[1][2] * b,
          m[2][0] * r + m[2][1] * g + m[2][2] * b};
}

Lab xyz_to_lab(const Xyz& xyz, const Xyz& white) {
  const double fx = lab_f(xyz.X / white.X);
  const double fy = lab_f(xyz.Y / white.Y);
  const double fz = lab_f(xyz.Z / white.Z);
  return {116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)};
}

Lab linear_srgb_to_lab(double r, double g, double b) { return xyz_to_lab(linear_srgb_to_xyz(r, g, b)); }

Lab srgb8_to_lab(std::uint8_t r, std::uint8_t g, std::uint8_t b) {
  // The 256 decoded values, computed once (thread-safe static initialisation): image comparison
  // converts millions of pixels, and a table keeps pow out of the per-pixel path.
  static const std::array<double, 256> kLinear = [] {
    std::array<double, 256> t{};
    for (int c = 0; c < 256; ++c) t[static_cast<std::size_t>(c)] = srgb_decode(c / 255.0);
    return t;
  }();
  return linear_srgb_to_lab(kLinear[r], kLinear[g], kLinear[b]);
}

double delta_e_76(const Lab& x, const Lab& y) {
  const double dl = x.L - y.L, da = x.a - y.a, db = x.b - y.b;
  return std::sqrt(dl * dl + da * da + db * db);
}

// CIE 142-2001 in the notation of Sharma, Wu and Dalal (2005), equations 2-22, kL = kC = kH = 1.
// Every step is symmetric in (x, y) or flips sign with the swap in the terms that are squared or
// multiplied pairwise, so the result is exactly symmetric.
double delta_e_2000(const Lab& x, const Lab& y) {
  // a* rescaling by G, which depends on the mean chroma.
  const double c1 = std::sqrt(x.a * x.a + x.b * x.b);
  const double c2 = std::sqrt(y.a * y.a + y.b * y.b);
  const double c7 = pow7((c1 + c2) / 2.0);
  const double g = 0.5 * (1.0 - std::sqrt(c7 / (c7 + k25Pow7)));
  const double a1 = (1.0 + g) * x.a;
  const double a2 = (1.0 + g) * y.a;
  const double cp1 = std::sqrt(a1 * a1 + x.b * x.b);
  const double cp2 = std::sqrt(a2 * a2 + y.b * y.b);
  const double h1 = hue_deg(a1, x.b);
  const double h2 = hue_deg(a2, y.b);

  // Hue difference and mean hue, with the published branches. Where either chroma is 0 the hue
  // is undefined: delta-h' = 0 and h-bar = h1 + h2 (eqs. 10 and 14).
  double dh = 0.0;
  double h_bar = h1 + h2;
  if (cp1 * cp2 != 0.0) {
    const double diff = h2 - h1;
    // Tie-break: two hues exactly opposite (|h2 - h1| = 180, the formula's discontinuity) take
    // the |h2 - h1| <= 180 branch, as the formula says. Decided on the exact geometry (the cross
    // product of (a', b) is exactly 0 for exact opposites, and the dot product negative) rather
    // than on the rounded angles, where atan2's rounding could land either side of 180 (Sharma
    // et al. pairs 10 and 14).
    const bool opposite = a1 * y.b == x.b * a2 && a1 * a2 + x.b * y.b < 0.0;
    if (opposite) {
      dh = diff >= 0.0 ? 180.0 : -180.0;
      h_bar = (h1 + h2) / 2.0;
    } else if (std::fabs(diff) <= 180.0) {
      dh = diff;
      h_bar = (h1 + h2) / 2.0;
    } else {
      dh = diff > 180.0 ? diff - 360.0 : diff + 360.0;
      h_bar = (h1 + h2 < 360.0) ? (h1 + h2 + 360.0) / 2.0 : (h1 + h2 - 360.0) / 2.0;
    }
  }
  const double d_l = y.L - x.L;
  const double d_c = cp2 - cp1;
  const double d_h = 2.0 * std::sqrt(cp1 * cp2) * sin_deg(dh / 2.0);

  // Weighting functions and the rotation term (eqs. 15-22; CIE 142-2001's constants).
  const double l_bar = (x.L + y.L) / 2.0;
  const double c_bar = (cp1 + cp2) / 2.0;
  const double t = 1.0 - 0.17 * cos_deg(h_bar - 30.0) + 0.24 * cos_deg(2.0 * h_bar) +
                   0.32 * cos_deg(3.0 * h_bar + 6.0) - 0.20 * cos_deg(4.0 * h_bar - 63.0);
  const double hz = (h_bar - 275.0) / 25.0;
  const double d_theta = 30.0 * std::exp(-hz * hz);
  const double cb7 = pow7(c_bar);
  const double r_c = 2.0 * std::sqrt(cb7 / (cb7 + k25Pow7));
  const double l50 = (l_bar - 50.0) * (l_bar - 50.0);
  const double s_l = 1.0 + 0.015 * l50 / std::sqrt(20.0 + l50);
  const double s_c = 1.0 + 0.045 * c_bar;
  const double s_h = 1.0 + 0.015 * c_bar * t;
  const double r_t = -sin_deg(2.0 * d_theta) * r_c;

  const double tl = d_l / s_l, tc = d_c / s_c, th = d_h / s_h;
  // The rotation term can make the sum a rounding below 0 for nearly identical colours; clamp
  // so that sqrt never sees a negative.
  return std::sqrt(std::max(0.0, tl * tl + tc * tc + th * th + r_t * tc * th));
}

}  // namespace r1::color
