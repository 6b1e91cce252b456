// Overlays and colour: exact HSL against rationals, the crystal-v5 values as listed, the custom TOML format, its errors and round trip (R1-ENC-006, R1-ENC-030..043).
#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <boost/multiprecision/cpp_int.hpp>

#include "r1/reference/encoding.hpp"
#include "test_support.hpp"

namespace {

using r1::Q32;
using r1::Rgb8;
using r1::Shape;
using Rat = boost::multiprecision::cpp_rational;

// CSS HSL in exact rationals, each channel rounded half to even: an independent reference.
Rgb8 reference_hsl(const Rat& h6, const Rat& s, const Rat& l) {
  const Rat two_l_1 = 2 * l - 1;
  const Rat c = (1 - (two_l_1 < 0 ? Rat(-two_l_1) : two_l_1)) * s;
  const auto sector = static_cast<int>(boost::multiprecision::numerator(h6) / boost::multiprecision::denominator(h6));
  Rat hm2 = h6 - 2 * (sector / 2);
  const Rat dist = hm2 - 1 < 0 ? Rat(1 - hm2) : Rat(hm2 - 1);
  const Rat x = c * (1 - dist);
  const Rat m = l - c / 2;
  Rat r = 0, g = 0, b = 0;
  switch (sector) {
    case 0: r = c, g = x; break;
    case 1: r = x, g = c; break;
    case 2: g = c, b = x; break;
    case 3: g = x, b = c; break;
    case 4: r = x, b = c; break;
    default: r = c, b = x; break;
  }
  Rgb8 out{};
  const Rat vals[3] = {r + m, g + m, b + m};
  for (int k = 0; k < 3; ++k) {
    const Rat v = vals[k] * 255;
    boost::multiprecision::cpp_int fl = boost::multiprecision::numerator(v) / boost::multiprecision::denominator(v);
    const Rat frac = v - Rat(fl);
    if (frac > Rat(1, 2) || (frac == Rat(1, 2) && fl % 2 == 1)) ++fl;
    out[k] = static_cast<std::uint8_t>(static_cast<int>(fl));
  }
  return out;
}

Rat rat_q32(Q32 q) { return Rat(q.raw) / Rat(boost::multiprecision::cpp_int(1) << 32); }

TEST(Color, KnownValues) {
  // L = 0.55, S = 1, hue 0: (1.0, 0.1, 0.1) x 255 = (255, 25.5, 25.5); ties go to even 26.
  EXPECT_EQ(r1::hsl_to_srgb8(Q32::zero(), Q32::one(), 550), (Rgb8{255, 26, 26}));
  EXPECT_EQ(r1::hsl_to_srgb8(Q32::from_int(2), Q32::one(), 500), (Rgb8{0, 255, 0}));
  EXPECT_EQ(r1::hsl_to_srgb8(Q32::from_int(4), Q32::zero(), 500), (Rgb8{128, 128, 128}));  // 127.5 -> 128
  EXPECT_EQ(r1::hsl_to_srgb8(Q32::from_int(3), Q32::one(), 1000), (Rgb8{255, 255, 255}));
  EXPECT_EQ(r1::hsl_to_srgb8(Q32::from_int(1), Q32::one(), 0), (Rgb8{0, 0, 0}));
}

RC_GTEST_PROP(Color, MatchesExactRationals, ()) {
  const auto h = Q32::from_raw(*rc::gen::inRange<std::int64_t>(0, 6 * Q32::kOneRaw));
  const auto s = Q32::from_raw(*rc::gen::inRange<std::int64_t>(0, Q32::kOneRaw + 1));
  const auto l = *rc::gen::inRange<std::uint32_t>(0, 1001);
  RC_ASSERT(r1::hsl_to_srgb8(h, s, l) == reference_hsl(rat_q32(h), rat_q32(s), Rat(l, 1000)));
}

TEST(CrystalV5, ValuesExactlyAsListed) {
  const auto& o = r1::crystal_v5_overlay();
  EXPECT_EQ(o.type_shape[0], Shape::kSphere);       // entity
  EXPECT_EQ(o.type_shape[1], Shape::kTorus);        // process
  EXPECT_EQ(o.type_shape[2], Shape::kTetrahedron);  // property
  EXPECT_EQ(o.type_shape[3], Shape::kCube);         // relation
  EXPECT_EQ(o.type_shape[4], Shape::kOctahedron);   // measure
  EXPECT_EQ(o.type_shape[5], Shape::kCylinder);     // pattern
  const int hues[7] = {0, 30, 120, 150, 210, 270, 330};
  const int light[3] = {400, 550, 700};
  for (std::size_t d = 0; d < 21; ++d) {
    SCOPED_TRACE(r1::kCrystalDomains[d]);
    ASSERT_TRUE(o.domain_color[d].has_value());
    EXPECT_EQ(*o.domain_color[d], reference_hsl(Rat(hues[d / 3], 60), Rat(3, 4), Rat(light[d % 3], 1000)));
  }
  // Spot values: FORM math = HSL(0, 0.75, 0.40) = (0.7, 0.1, 0.1) -> (178.5, 25.5, 25.5) -> ties to even.
  EXPECT_EQ(*o.domain_color[0], (Rgb8{178, 26, 26}));
  // SPACE geo = HSL(120, 0.75, 0.55): C = 0.675, m = 0.2125 -> (54.1875, 226.3125, 54.1875).
  EXPECT_EQ(*o.domain_color[7], (Rgb8{54, 226, 54}));
  EXPECT_EQ(o.size_multiplier[0], Q32::from_decimal("0.5"));
  EXPECT_EQ(o.size_multiplier[1], Q32::from_decimal("0.75"));
  EXPECT_EQ(o.size_multiplier[2], Q32::one());
  EXPECT_EQ(o.size_multiplier[3], Q32::from_decimal("1.4"));
  EXPECT_EQ(o.size_multiplier[4], Q32::from_int(2));
  EXPECT_TRUE(o.particles.empty());
}

constexpr const char* kExample = R"(# a custom overlay
[overlay]
version = 1

[type]
Entity = "CUBE"
pattern = "torus"

[domain]
math = "#3366cc"
GEO = "#A0b0C0"

[size]
deep = "2.5"
atom = 1

[particle]
"alice" = { shape = "octahedron", color = "#ff0000", size = 2 }
'b"ob' = { size = "0.125" }

[particle."car ol"]
color = "#000000"
)";

TEST(CustomOverlay, ParsesEveryTable) {
  auto r = r1::parse_custom_overlay(kExample, "o.toml");
  ASSERT_TRUE(r.is_ok()) << r.status().message();
  const auto& o = *r;
  EXPECT_EQ(o.type_shape[0], Shape::kCube);
  EXPECT_EQ(o.type_shape[5], Shape::kTorus);
  EXPECT_FALSE(o.type_shape[1].has_value());
  EXPECT_EQ(o.domain_color[0], (Rgb8{0x33, 0x66, 0xcc}));
  EXPECT_EQ(o.domain_color[7], (Rgb8{0xa0, 0xb0, 0xc0}));
  EXPECT_EQ(o.size_multiplier[4], Q32::from_decimal("2.5"));
  EXPECT_EQ(o.size_multiplier[0], Q32::one());
  ASSERT_EQ(o.particles.size(), 3u);
  // Sorted by key bytes.
  EXPECT_EQ(o.particles[0].key, "alice");
  EXPECT_EQ(o.particles[1].key, "b\"ob");
  EXPECT_EQ(o.particles[2].key, "car ol");
  EXPECT_EQ(o.particles[0].style.shape, Shape::kOctahedron);
  EXPECT_EQ(o.particles[0].style.size, Q32::from_int(2));
  EXPECT_EQ(o.particles[0].line, 18u);
  EXPECT_EQ(o.particles[1].style.size, Q32::from_decimal("0.125"));
  EXPECT_FALSE(o.particles[1].style.color.has_value());
  EXPECT_EQ(o.particles[2].style.color, (Rgb8{0, 0, 0}));
}

TEST(CustomOverlay, CanonicalTextRoundTrips) {
  for (const auto* o : {&r1::crystal_v5_overlay()}) {
    const auto text = r1::custom_overlay_text(*o);
    auto back = r1::parse_custom_overlay(text, "c.toml");
    ASSERT_TRUE(back.is_ok()) << back.status().message() << "\n" << text;
    EXPECT_EQ(*back, *o);
  }
  auto r = r1::parse_custom_overlay(kExample, "o.toml");
  ASSERT_TRUE(r.is_ok());
  const auto text = r1::custom_overlay_text(*r);
  auto back = r1::parse_custom_overlay(text, "c.toml");
  ASSERT_TRUE(back.is_ok()) << back.status().message() << "\n" << text;
  EXPECT_EQ(*back, *r);
  EXPECT_EQ(r1::custom_overlay_text(*back), text);
  // Keys needing escapes survive too.
  r1::CustomOverlay odd;
  odd.particles.push_back({"tab\there 'q' \"dq\" back\\slash\nnewline \x01", {Shape::kCube, {}, {}}, 0});
  auto odd_back = r1::parse_custom_overlay(r1::custom_overlay_text(odd), "odd.toml");
  ASSERT_TRUE(odd_back.is_ok()) << odd_back.status().message();
  EXPECT_EQ(*odd_back, odd);
}

// The error of one malformed overlay: "o.toml:LINE: ..." containing `what`.
void expect_error(const std::string& text, int line, const std::string& what) {
  auto r = r1::parse_custom_overlay(text, "o.toml");
  ASSERT_FALSE(r.is_ok()) << text;
  EXPECT_EQ(r.status().kind(), r1::ErrorKind::kInput);
  const auto& m = r.status().message();
  EXPECT_EQ(m.rfind("o.toml:" + std::to_string(line) + ": ", 0), 0u) << m;
  EXPECT_NE(m.find(what), std::string::npos) << m;
  EXPECT_EQ(m.find('\n'), std::string::npos) << m;
}

TEST(CustomOverlay, MalformedFilesNameTheLine) {
  expect_error("[type]\nentity = \"blob\"\n", 2, "shape must be one of");
  expect_error("[type]\nbeing = \"cube\"\n", 2, "unknown crystal type 'being'");
  expect_error("[type]\nentity = \"cube\"\nENTITY = \"torus\"\n", 3, "given twice");
  expect_error("[domain]\nmath = \"#12345\"\n", 2, "colour must be");
  expect_error("[domain]\nmath = \"#12345g\"\n", 2, "colour must be");
  expect_error("[domain]\nmath = 7\n", 2, "colour must be");
  expect_error("[size]\ndeep = 0\n", 2, "size multiplier");
  expect_error("[size]\ndeep = 17\n", 2, "size multiplier");
  expect_error("[size]\ndeep = \"16.0000000001\"\n", 2, "size multiplier");
  expect_error("[size]\ndeep = \"1e-30\"\n", 2, "size multiplier");
  expect_error("[size]\ndeep = \"abc\"\n", 2, "size multiplier");
  expect_error("[size]\nhuge = 2\n", 2, "unknown crystal size");
  expect_error("\n[colors]\nmath = \"#000000\"\n", 2, "unknown key 'colors'");
  expect_error("[overlay]\nversion = 2\n", 2, "version must be the integer 1");
  expect_error("[overlay]\nname = \"x\"\n", 2, "unknown field 'name'");
  expect_error("[particle]\nalice = \"cube\"\n", 2, "must be a table");
  expect_error("[particle]\nalice = {}\n", 2, "sets nothing");
  expect_error("[particle]\nalice = { shape = \"cube\", glow = 1 }\n", 2, "unknown field 'glow'");
  expect_error("[particle]\nalice = { color = \"red\" }\n", 2, "colour must be");
  expect_error("[particle]\n'" + std::string(513, 'k') + "' = { size = 1 }\n", 2, "1 to 512 bytes");
  expect_error("[size]\ndeep = 2.5\n", 2, "only decimal integers");  // floats are outside the subset
  expect_error("[type]\nentity = \"cube\"\n[type]\n", 3, "");        // toml++: table defined twice
  expect_error("[[type]]\n", 1, "must be a table");
}

TEST(CustomOverlay, SizeBoundIsOnTheExactDecimal) {
  // R1-ENC-040: the decimal itself must lie in (0, 16], and its Q32 rounding must be positive.
  // Texts equal to 16 in any spelling, or below it yet rounding to 16, are accepted.
  for (const char* ok : {"16", "16.000", "1.6e1", "160e-1", "0.16E+2", "+16", "15.99999999999", "0.0000000003"}) {
    auto r = r1::parse_custom_overlay(std::string("[size]\ndeep = \"") + ok + "\"\n", "o.toml");
    ASSERT_TRUE(r.is_ok()) << ok << ": " << r.status().message();
    EXPECT_LE(r->size_multiplier[4]->raw, 16 * Q32::kOneRaw) << ok;
  }
  for (const char* bad : {"16.00000000001", "1.60000000000001e1", "16000000000001e-12", "0.00000000001", "-0.00000000001"}) {
    auto r = r1::parse_custom_overlay(std::string("[size]\ndeep = \"") + bad + "\"\n", "o.toml");
    ASSERT_FALSE(r.is_ok()) << bad;
    EXPECT_EQ(r.status().message().rfind("o.toml:2: size multiplier", 0), 0u) << r.status().message();
  }
}

TEST(CustomOverlay, StylePrecedence) {
  const auto& v5 = r1::crystal_v5_overlay();
  const r1::CrystalTag tag{1, 7, 4};  // process, geo, deep
  auto s = r1::overlay_style(v5, tag);
  EXPECT_EQ(s.shape, Shape::kTorus);
  EXPECT_EQ(s.color, v5.domain_color[7]);
  EXPECT_EQ(s.size, Q32::from_int(2));
  EXPECT_EQ(r1::overlay_style(v5, r1::CrystalTag{}), r1::OverlayStyle{});
  const r1::OverlayStyle own{Shape::kCube, {}, Q32::from_int(3)};
  s = r1::overlay_style(v5, tag, &own);
  EXPECT_EQ(s.shape, Shape::kCube);
  EXPECT_EQ(s.color, v5.domain_color[7]);
  EXPECT_EQ(s.size, Q32::from_int(3));
}

TEST(CustomOverlay, ReadsFiles) {
  r1::test::TempDir dir;
  r1::test::write_file(dir / "o.toml", kExample);
  auto r = r1::read_custom_overlay((dir / "o.toml").string());
  ASSERT_TRUE(r.is_ok()) << r.status().message();
  EXPECT_EQ(r->particles.size(), 3u);
  r1::test::write_file(dir / "bad.toml", "[type]\n\nentity = 1\n");
  auto bad = r1::read_custom_overlay((dir / "bad.toml").string());
  ASSERT_FALSE(bad.is_ok());
  EXPECT_EQ(bad.status().message().rfind((dir / "bad.toml").string() + ":3: ", 0), 0u) << bad.status().message();
}

}  // namespace
