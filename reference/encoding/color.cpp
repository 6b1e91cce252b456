// Exact HSL to 8-bit display sRGB, one rounding per channel (R1-ENC-005..006).
#include "r1/fixedpoint/int128.hpp"
#include "r1/reference/encoding.hpp"

namespace r1 {

Rgb8 hsl_to_srgb8(Q32 hue_sixths, Q32 saturation, std::uint32_t lightness_permille) {
  // Clamps keep the function total for any arguments (the fuzz target and custom callers); the
  // stage's own inputs are always in range, so for them the clamps change nothing.
  constexpr std::int64_t kSix = 6 * Q32::kOneRaw;
  std::int64_t h6 = hue_sixths.raw % kSix;
  if (h6 < 0) h6 += kSix;  // hue is periodic: reduce into [0, 6)
  const i128 s = saturation.raw < 0 ? 0 : (saturation.raw > Q32::kOneRaw ? Q32::kOneRaw : saturation.raw);
  const i128 l = lightness_permille > 1000 ? 1000 : lightness_permille;

  const std::int64_t sector = h6 >> 32;                // floor(H), 0..5
  const i128 frac = h6 & (Q32::kOneRaw - 1);           // H - floor(H), units 2^-32
  // 1 - |H mod 2 - 1| is frac for even sectors and 1 - frac for odd ones (units 2^-32).
  const i128 g = (sector % 2 == 0) ? frac : Q32::kOneRaw - frac;

  // Every value below is a numerator over D = 1000 x 2^64 (exact; the largest is D < 2^74).
  const i128 chroma_pm = 1000 - (2 * l > 1000 ? 2 * l - 1000 : 1000 - 2 * l);  // (1 - |2L - 1|) x 1000
  const i128 c = chroma_pm * s * Q32::kOneRaw;                                  // C
  const i128 x = chroma_pm * s * g;                                             // X = C (1 - |H mod 2 - 1|)
  const i128 m = l * (i128{1} << 64) - chroma_pm * s * (Q32::kOneRaw / 2);     // L - C / 2
  i128 rgb[3] = {0, 0, 0};
  switch (sector) {
    case 0: rgb[0] = c, rgb[1] = x; break;
    case 1: rgb[0] = x, rgb[1] = c; break;
    case 2: rgb[1] = c, rgb[2] = x; break;
    case 3: rgb[1] = x, rgb[2] = c; break;
    case 4: rgb[0] = x, rgb[2] = c; break;
    default: rgb[0] = c, rgb[2] = x; break;
  }
  const i128 d = i128{1000} << 64;
  Rgb8 out{};
  for (int k = 0; k < 3; ++k) {
    // One rounding, ties to even (R1-ENC-006); 255 x D < 2^82.
    const i128 byte = fx::detail::rne_div(255 * (rgb[k] + m), d);
    out[static_cast<std::size_t>(k)] = static_cast<std::uint8_t>(byte < 0 ? 0 : (byte > 255 ? 255 : byte));
  }
  return out;
}

}  // namespace r1
