// Colour difference for image comparison (spec/render.md R1-RND-110..111): display sRGB and
// linear Rec.709 RGB to CIELAB (D65), CIE76 and CIEDE2000. Plain fp64 with libm; not canonical.
#pragma once

#include <cstdint>

namespace r1::color {

// CIELAB: L* in [0, 100] for colours inside the white's gamut, a* and b* unbounded.
struct Lab {
  double L, a, b;
};

// CIE 1931 tristimulus values, scaled so that the reference white has Y = 1.
struct Xyz {
  double X, Y, Z;
};

// The D65 white point as IEC 61966-2-1 (sRGB) and ITU-R BT.709 state it: chromaticity
// x = 0.3127, y = 0.3290 (CIE 1931 2-degree observer). The sRGB matrix below is derived from the
// same chromaticity, so display white (255, 255, 255) maps to L* = 100, a* = b* = 0 up to
// rounding; the CIE 15 tabulated D65 (0.95047, 1, 1.08883) would leave a* ~ 0.005 there instead.
inline constexpr double kD65WhiteX = 0.3127;
inline constexpr double kD65WhiteY = 0.3290;
// The D65 white in XYZ, Y = 1: (x / y, 1, (1 - x - y) / y) = (0.950456, 1, 1.089058).
inline constexpr Xyz kD65White{kD65WhiteX / kD65WhiteY, 1.0, (1.0 - kD65WhiteX - kD65WhiteY) / kD65WhiteY};

// The IEC 61966-2-1 decode of one display-encoded value v in [0, 1]: v <= 0.04045 ? v / 12.92 :
// ((v + 0.055) / 1.055)^2.4. Values outside [0, 1] are clamped first.
double srgb_decode(double v);

// Linear-light RGB with Rec.709/sRGB primaries -> XYZ (D65, Y of white = 1), by the normalized
// primary matrix of the BT.709 primaries R (0.64, 0.33), G (0.30, 0.60), B (0.15, 0.06) and the
// white above (SMPTE RP 177 derivation; IEC 61966-2-1 prints the same matrix to four decimals).
Xyz linear_srgb_to_xyz(double r, double g, double b);

// XYZ -> CIELAB relative to `white` (CIE 15: f(t) = cbrt(t) above (6/29)^3, the linear segment
// t / (3 (6/29)^2) + 4/29 below).
Lab xyz_to_lab(const Xyz& xyz, const Xyz& white = kD65White);

// Display sRGB 8-bit code values (IEC 61966-2-1) -> XYZ (D65) -> CIELAB with the D65 white.
Lab srgb8_to_lab(std::uint8_t r, std::uint8_t g, std::uint8_t b);

// Linear-light Rec.709/sRGB RGB (1 = display white) -> CIELAB with the D65 white.
Lab linear_srgb_to_lab(double r, double g, double b);

// CIE76: the Euclidean distance in CIELAB.
double delta_e_76(const Lab& x, const Lab& y);

// CIEDE2000 (CIE 142-2001) with the parametric factors kL = kC = kH = 1, following the
// implementation notes of Sharma, Wu and Dalal (2005): a hue is 0 where C' = 0, and h-bar and
// delta-h' take the published branches. Symmetric in its arguments, 0 for identical colours.
double delta_e_2000(const Lab& x, const Lab& y);

}  // namespace r1::color
