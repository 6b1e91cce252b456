// CIELAB conversion and colour differences (spec/render.md R1-RND-110..111): the published
// CIEDE2000 test data, symmetry, CIE76, and known sRGB -> Lab values.
#include "r1/color/delta_e.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>

namespace {

using r1::color::delta_e_2000;
using r1::color::delta_e_76;
using r1::color::Lab;

// Table 1 of G. Sharma, W. Wu, E. N. Dalal, "The CIEDE2000 color-difference formula:
// implementation notes, supplementary test data, and mathematical observations", Color Research
// and Application 30(1), 21-30, 2005: the 34 pairs (L1, a1, b1, L2, a2, b2) and their CIEDE2000
// difference, published to four decimals. Pairs 7-16 sit on the formula's hue discontinuities;
// pairs 10 and 14 have hues exactly 180 degrees apart.
struct SharmaPair {
  Lab x, y;
  double de;
};
constexpr std::array<SharmaPair, 34> kSharma = {{
    {{50.0000, 2.6772, -79.7751}, {50.0000, 0.0000, -82.7485}, 2.0425},
    {{50.0000, 3.1571, -77.2803}, {50.0000, 0.0000, -82.7485}, 2.8615},
    {{50.0000, 2.8361, -74.0200}, {50.0000, 0.0000, -82.7485}, 3.4412},
    {{50.0000, -1.3802, -84.2814}, {50.0000, 0.0000, -82.7485}, 1.0000},
    {{50.0000, -1.1848, -84.8006}, {50.0000, 0.0000, -82.7485}, 1.0000},
    {{50.0000, -0.9009, -85.5211}, {50.0000, 0.0000, -82.7485}, 1.0000},
    {{50.0000, 0.0000, 0.0000}, {50.0000, -1.0000, 2.0000}, 2.3669},
    {{50.0000, -1.0000, 2.0000}, {50.0000, 0.0000, 0.0000}, 2.3669},
    {{50.0000, 2.4900, -0.0010}, {50.0000, -2.4900, 0.0009}, 7.1792},
    {{50.0000, 2.4900, -0.0010}, {50.0000, -2.4900, 0.0010}, 7.1792},
    {{50.0000, 2.4900, -0.0010}, {50.0000, -2.4900, 0.0011}, 7.2195},
    {{50.0000, 2.4900, -0.0010}, {50.0000, -2.4900, 0.0012}, 7.2195},
    {{50.0000, -0.0010, 2.4900}, {50.0000, 0.0009, -2.4900}, 4.8045},
    {{50.0000, -0.0010, 2.4900}, {50.0000, 0.0010, -2.4900}, 4.8045},
    {{50.0000, -0.0010, 2.4900}, {50.0000, 0.0011, -2.4900}, 4.7461},
    {{50.0000, 2.5000, 0.0000}, {50.0000, 0.0000, -2.5000}, 4.3065},
    {{50.0000, 2.5000, 0.0000}, {73.0000, 25.0000, -18.0000}, 27.1492},
    {{50.0000, 2.5000, 0.0000}, {61.0000, -5.0000, 29.0000}, 22.8977},
    {{50.0000, 2.5000, 0.0000}, {56.0000, -27.0000, -3.0000}, 31.9030},
    {{50.0000, 2.5000, 0.0000}, {58.0000, 24.0000, 15.0000}, 19.4535},
    {{50.0000, 2.5000, 0.0000}, {50.0000, 3.1736, 0.5854}, 1.0000},
    {{50.0000, 2.5000, 0.0000}, {50.0000, 3.2972, 0.0000}, 1.0000},
    {{50.0000, 2.5000, 0.0000}, {50.0000, 1.8634, 0.5757}, 1.0000},
    {{50.0000, 2.5000, 0.0000}, {50.0000, 3.2592, 0.3350}, 1.0000},
    {{60.2574, -34.0099, 36.2677}, {60.4626, -34.1751, 39.4387}, 1.2644},
    {{63.0109, -31.0961, -5.8663}, {62.8187, -29.7946, -4.0864}, 1.2630},
    {{61.2901, 3.7196, -5.3901}, {61.4292, 2.2480, -4.9620}, 1.8731},
    {{35.0831, -44.1164, 3.7933}, {35.0232, -40.0716, 1.5901}, 1.8645},
    {{22.7233, 20.0904, -46.6940}, {23.0331, 14.9730, -42.5619}, 2.0373},
    {{36.4612, 47.8580, 18.3852}, {36.2715, 50.5065, 21.2231}, 1.4146},
    {{90.8027, -2.0831, 1.4410}, {91.1528, -1.6435, 0.0447}, 1.4441},
    {{90.9257, -0.5406, -0.9208}, {88.6381, -0.8985, -0.7239}, 1.5381},
    {{6.7747, -0.2908, -2.4247}, {5.8714, -0.0985, -2.2286}, 0.6377},
    {{2.0776, 0.0795, -1.1350}, {0.9033, -0.0636, -0.5514}, 0.9082},
}};

// The published values are rounded to four decimals: a correct implementation is within 0.5e-4;
// 1e-4 leaves room for the last digit of libm.
constexpr double kSharmaTolerance = 1e-4;

TEST(Color, Ciede2000MatchesSharmaWuDalalTable) {
  for (std::size_t i = 0; i < kSharma.size(); ++i) {
    const SharmaPair& p = kSharma[i];
    EXPECT_NEAR(delta_e_2000(p.x, p.y), p.de, kSharmaTolerance) << "pair " << i + 1;
    EXPECT_NEAR(delta_e_2000(p.y, p.x), p.de, kSharmaTolerance) << "pair " << i + 1 << " swapped";
  }
}

TEST(Color, Ciede2000IsSymmetricAndZeroOnIdenticalColours) {
  for (const SharmaPair& p : kSharma) {
    EXPECT_EQ(delta_e_2000(p.x, p.y), delta_e_2000(p.y, p.x));
    EXPECT_EQ(delta_e_2000(p.x, p.x), 0.0);
    EXPECT_EQ(delta_e_2000(p.y, p.y), 0.0);
  }
  // Every pair of a coarse grid of display colours, both orders.
  for (int i = 0; i < 27; ++i) {
    for (int j = 0; j < 27; ++j) {
      auto code = [](int k, int d) { return static_cast<std::uint8_t>(((k / d) % 3) * 127 + 1); };
      const Lab x = r1::color::srgb8_to_lab(code(i, 1), code(i, 3), code(i, 9));
      const Lab y = r1::color::srgb8_to_lab(code(j, 1), code(j, 3), code(j, 9));
      EXPECT_EQ(delta_e_2000(x, y), delta_e_2000(y, x)) << i << " " << j;
      if (i == j) {
        EXPECT_EQ(delta_e_2000(x, y), 0.0);
      }
    }
  }
}

// Hues exactly 180 degrees apart sit on the formula's discontinuity; they take the
// |h2' - h1'| <= 180 branch, so the value is the limit from the side where the hue difference is
// just below 180, and clearly not the limit from the other side.
TEST(Color, Ciede2000ExactlyOppositeHuesTakeTheLessOrEqual180Branch) {
  constexpr double kTiny = 1e-9;  // far below the inputs' scale, far above rounding of 25
  struct Case {
    Lab x, opposite, inside, outside;  // inside: rotated so |h2' - h1'| < 180; outside: > 180
  };
  const Case cases[] = {
      // h' = 90 and 270 (a' = 0 whatever G is).
      {{50, 0, 25}, {50, 0, -25}, {50, -kTiny, -25}, {50, kTiny, -25}},
      // h' = 0 and 180.
      {{50, 25, 0}, {50, -25, 0}, {50, -25, kTiny}, {50, -25, -kTiny}},
      // The published pairs 10 and 14 exactly.
      {{50, 2.49, -0.001}, {50, -2.49, 0.001}, {50, -2.49, 0.001 - kTiny}, {50, -2.49, 0.001 + kTiny}},
      {{50, -0.001, 2.49}, {50, 0.001, -2.49}, {50, 0.001 - kTiny, -2.49}, {50, 0.001 + kTiny, -2.49}},
  };
  for (const Case& c : cases) {
    const double at = delta_e_2000(c.x, c.opposite);
    EXPECT_NEAR(at, delta_e_2000(c.x, c.inside), 1e-6) << c.x.a << " " << c.x.b;
    EXPECT_GT(std::fabs(at - delta_e_2000(c.x, c.outside)), 1e-2) << c.x.a << " " << c.x.b;
    EXPECT_EQ(at, delta_e_2000(c.opposite, c.x));
  }
}

TEST(Color, Cie76IsTheEuclideanDistance) {
  EXPECT_EQ(delta_e_76({50, 0, 0}, {50, 0, 0}), 0.0);
  EXPECT_DOUBLE_EQ(delta_e_76({50, 3, 4}, {50, 0, 0}), 5.0);
  EXPECT_DOUBLE_EQ(delta_e_76({10, 2, 3}, {12, 5, 9}), 7.0);  // 2, 3, 6
  for (const SharmaPair& p : kSharma) {
    const double dl = p.x.L - p.y.L, da = p.x.a - p.y.a, db = p.x.b - p.y.b;
    EXPECT_DOUBLE_EQ(delta_e_76(p.x, p.y), std::sqrt(dl * dl + da * da + db * db));
    EXPECT_EQ(delta_e_76(p.x, p.y), delta_e_76(p.y, p.x));
  }
}

TEST(Color, SrgbWhiteAndBlackAreTheLabEnds) {
  const Lab white = r1::color::srgb8_to_lab(255, 255, 255);
  EXPECT_NEAR(white.L, 100.0, 1e-3);
  EXPECT_NEAR(white.a, 0.0, 1e-3);
  EXPECT_NEAR(white.b, 0.0, 1e-3);
  const Lab black = r1::color::srgb8_to_lab(0, 0, 0);
  EXPECT_NEAR(black.L, 0.0, 1e-9);
  EXPECT_NEAR(black.a, 0.0, 1e-9);
  EXPECT_NEAR(black.b, 0.0, 1e-9);
  // The white point of the matrix is the D65 white itself.
  const r1::color::Xyz w = r1::color::linear_srgb_to_xyz(1, 1, 1);
  EXPECT_NEAR(w.X, r1::color::kD65White.X, 1e-12);
  EXPECT_NEAR(w.Y, 1.0, 1e-12);
  EXPECT_NEAR(w.Z, r1::color::kD65White.Z, 1e-12);
}

TEST(Color, KnownSrgbToLabValues) {
  // Widely tabulated sRGB (D65) -> CIELAB values of the primaries and mid grey.
  const Lab red = r1::color::srgb8_to_lab(255, 0, 0);
  EXPECT_NEAR(red.L, 53.24, 0.01);
  EXPECT_NEAR(red.a, 80.09, 0.01);
  EXPECT_NEAR(red.b, 67.20, 0.01);
  const Lab blue = r1::color::srgb8_to_lab(0, 0, 255);
  EXPECT_NEAR(blue.L, 32.30, 0.01);
  EXPECT_NEAR(blue.a, 79.19, 0.01);
  EXPECT_NEAR(blue.b, -107.86, 0.01);
  const Lab grey = r1::color::srgb8_to_lab(128, 128, 128);
  EXPECT_NEAR(grey.L, 53.59, 0.01);
  EXPECT_NEAR(grey.a, 0.0, 1e-3);
  EXPECT_NEAR(grey.b, 0.0, 1e-3);
  // The IEC matrix to four decimals, as the standard prints it.
  const r1::color::Xyz r = r1::color::linear_srgb_to_xyz(1, 0, 0);
  EXPECT_NEAR(r.X, 0.4124, 5e-5);
  EXPECT_NEAR(r.Y, 0.2126, 5e-5);
  EXPECT_NEAR(r.Z, 0.0193, 5e-5);
}

TEST(Color, LinearAndDisplayPathsAgree) {
  for (int c = 0; c < 256; c += 15) {
    const auto u = static_cast<std::uint8_t>(c);
    const double l = r1::color::srgb_decode(c / 255.0);
    const Lab a = r1::color::srgb8_to_lab(u, 0, u);
    const Lab b = r1::color::linear_srgb_to_lab(l, 0, l);
    EXPECT_EQ(a.L, b.L);
    EXPECT_EQ(a.a, b.a);
    EXPECT_EQ(a.b, b.b);
  }
  EXPECT_EQ(r1::color::srgb_decode(-1.0), 0.0);
  EXPECT_EQ(r1::color::srgb_decode(2.0), 1.0);
  EXPECT_DOUBLE_EQ(r1::color::srgb_decode(0.04045), 0.04045 / 12.92);
}

}  // namespace
