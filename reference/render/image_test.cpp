// Frame buffer outputs and colour (spec/render.md R1-RND-080..086, R1-ERR-003): sRGB curve, tone
// map invariants, OCIO against the closed form, EXR/PNG round trips, atomic writes, labels.
#include "image.hpp"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <memory>

#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;
using r1::ErrorKind;
using r1::render::Image;

// The closed-form IEC 61966-2-1 encode in double precision: the yardstick OCIO is held to.
double srgb_encode(double l) {
  if (l <= 0.0031308) return 12.92 * l;
  return 1.055 * std::pow(l, 1.0 / 2.4) - 0.055;
}

double srgb_decode(double v) {
  if (v <= 0.04045) return v / 12.92;
  return std::pow((v + 0.055) / 1.055, 2.4);
}

int code_of(double v) { return static_cast<int>(std::floor(std::clamp(v, 0.0, 1.0) * 255.0 + 0.5)); }

std::size_t entries(const fs::path& dir) {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++n;
  return n;
}

// A small image with varied premultiplied pixels (some transparent, some above display white)
// and, optionally, a flow buffer.
Image test_image(int w, int h, bool with_flow) {
  Image im(w, h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const float a = static_cast<float>((x + 2 * y) % 5) / 4.0f;
      float* p = im.px(x, y);
      p[0] = a * (0.1f + 0.37f * static_cast<float>(x));
      p[1] = a * (0.05f + 0.11f * static_cast<float>(y));
      p[2] = a * 0.3f;
      p[3] = a;
    }
  }
  if (with_flow) {
    im.flow.resize(static_cast<std::size_t>(w) * h * 3);
    for (std::size_t i = 0; i < im.flow.size(); ++i) im.flow[i] = -1.5f + 0.013f * static_cast<float>(i);
  }
  return im;
}

struct ReadBack {
  OIIO::ImageSpec spec;
  std::vector<float> floats;
  std::vector<std::uint8_t> bytes;
};

ReadBack read_back(const fs::path& p, OIIO::TypeDesc type) {
  ReadBack r;
  auto in = OIIO::ImageInput::open(p.string());
  if (!in) {
    ADD_FAILURE() << "cannot open " << p << ": " << OIIO::geterror();
    return r;
  }
  r.spec = in->spec();
  const std::size_t n = static_cast<std::size_t>(r.spec.width) * r.spec.height * r.spec.nchannels;
  bool ok = false;
  if (type == OIIO::TypeDesc::FLOAT) {
    r.floats.resize(n);
    ok = in->read_image(0, 0, 0, r.spec.nchannels, type, r.floats.data());
  } else {
    r.bytes.resize(n);
    ok = in->read_image(0, 0, 0, r.spec.nchannels, type, r.bytes.data());
  }
  EXPECT_TRUE(ok) << in->geterror();
  in->close();
  return r;
}

// ---- sRGB curve (R1-RND-080) ----

TEST(Srgb, DecodeTableIsTheClosedFormCurve) {
  EXPECT_EQ(r1::render::srgb8_to_linear(0), 0.0f);
  EXPECT_EQ(r1::render::srgb8_to_linear(255), 1.0f);
  for (int c = 0; c < 256; ++c) {
    const double exact = srgb_decode(c / 255.0);
    const float got = r1::render::srgb8_to_linear(static_cast<std::uint8_t>(c));
    // The table is correctly rounded; libm's pow in double is far more precise than a float ulp.
    EXPECT_LE(std::abs(static_cast<double>(got) - exact), std::abs(exact) * 0x1p-24 * 1.0001) << "code " << c;
    if (c > 0) {
      EXPECT_GT(got, r1::render::srgb8_to_linear(static_cast<std::uint8_t>(c - 1))) << "code " << c;
    }
  }
}

TEST(Srgb, EveryCodeRoundTripsThroughLinear) {
  for (int c = 0; c < 256; ++c)
    EXPECT_EQ(code_of(srgb_encode(static_cast<double>(r1::render::srgb8_to_linear(static_cast<std::uint8_t>(c))))), c) << "code " << c;
}

// ---- tone map (R1-RND-082) ----

float max3(const std::array<float, 3>& c) { return std::max({c[0], c[1], c[2]}); }

TEST(ToneMap, IdentityUpToTheKnee) {
  const float knee = static_cast<float>(r1::render::kToneKnee);
  for (float m : {0.0f, 1e-30f, 0.001f, 0.18f, 0.5f, 0.79f, knee}) {
    for (float f : {0.0f, 0.25f, 1.0f}) {
      const std::array<float, 3> in{m, m * f, m * f * f};
      EXPECT_EQ(r1::render::tone_map(in), in) << m << " " << f;
      const std::array<float, 3> rot{m * f, m * f * f, m};
      EXPECT_EQ(r1::render::tone_map(rot), rot) << m << " " << f;
    }
  }
}

TEST(ToneMap, MonotoneAndAlwaysBelowWhite) {
  float prev = -1.0f;
  for (double m = 0.5; m < 1e30; m *= 1.01) {
    const float out = max3(r1::render::tone_map({static_cast<float>(m), 0.0f, 0.0f}));
    EXPECT_GE(out, prev) << m;
    EXPECT_LT(out, 1.0f) << m;
    prev = out;
  }
  for (float m : {1.0f, 2.0f, 1e7f, 1e20f, std::numeric_limits<float>::max()}) {
    const auto out = r1::render::tone_map({m, m, m});
    for (float v : out) EXPECT_LT(v, 1.0f) << m;
  }
  // Strictly increasing where float resolution allows: just above the knee and around white.
  const auto at = [](float m) { return max3(r1::render::tone_map({m, 0.0f, 0.0f})); };
  EXPECT_LT(at(0.81f), at(0.82f));
  EXPECT_LT(at(1.0f), at(1.1f));
  EXPECT_LT(at(4.0f), at(8.0f));
}

TEST(ToneMap, SlopeIsOneAtTheKnee) {
  // C1: the one-sided slope just above the knee is 1, like the identity below it.
  const double k = r1::render::kToneKnee, h = 1e-4;
  const double slope = (static_cast<double>(max3(r1::render::tone_map({static_cast<float>(k + h), 0, 0}))) - k) / h;
  EXPECT_NEAR(slope, 1.0, 2e-3);
  // The documented formula at a few points.
  for (double m : {0.9, 1.0, 2.0, 10.0}) {
    const double d = m - k, expect = k + (1 - k) * d / (d + (1 - k));
    EXPECT_NEAR(max3(r1::render::tone_map({static_cast<float>(m), 0, 0})), expect, 1e-6) << m;
  }
}

TEST(ToneMap, KeepsChannelRatios) {
  const std::array<std::array<float, 3>, 5> colours{{{1.0f, 0.5f, 0.25f},
                                                     {0.2f, 3.0f, 1.5f},
                                                     {40.0f, 40.0f, 1.0f},
                                                     {0.9f, 0.0f, 0.6f},
                                                     {1e6f, 2e5f, 7e5f}}};
  for (const auto& c : colours) {
    const auto out = r1::render::tone_map(c);
    const float m_in = max3(c), m_out = max3(out);
    for (int i = 0; i < 3; ++i)
      EXPECT_NEAR(out[i] / m_out, c[i] / m_in, 1e-6) << c[0] << "," << c[1] << "," << c[2] << " ch " << i;
  }
}

TEST(ToneMap, NonFiniteAndNegativeChannelsBecomeZero) {
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  EXPECT_EQ(r1::render::tone_map({nan, 0.5f, -0.25f}), (std::array<float, 3>{0.0f, 0.5f, 0.0f}));
  EXPECT_EQ(r1::render::tone_map({inf, -inf, 0.1f}), (std::array<float, 3>{0.0f, 0.0f, 0.1f}));
  EXPECT_EQ(r1::render::tone_map({-0.0f, -1.0f, -inf}), (std::array<float, 3>{0.0f, 0.0f, 0.0f}));
}

// ---- OCIO display transform (R1-RND-083) ----

TEST(Display, OcioMatchesClosedFormEncode) {
  const std::vector<double> samples{0.0, 0.0031308, 0.18, 0.5, 1.0};
  std::vector<float> rgb;
  for (double s : samples) rgb.insert(rgb.end(), 3, static_cast<float>(s));
  ASSERT_TRUE(r1::render::ocio_linear_to_srgb(rgb).is_ok());
  for (std::size_t i = 0; i < samples.size(); ++i)
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(rgb[3 * i + k], srgb_encode(samples[i]), 1.0 / 255.0) << "linear " << samples[i];
  // Tighter than required: OCIO's curve differs from the piecewise IEC one only near the joint.
  EXPECT_NEAR(rgb[3 * 2], srgb_encode(0.18), 1e-4);
  EXPECT_NEAR(rgb[3 * 4], 1.0, 1e-5);
}

TEST(Display, CompositesPremultipliedOverBackground) {
  Image im(3, 1);
  float* opaque = im.px(0, 0);
  opaque[0] = 0.18f, opaque[1] = 0.5f, opaque[2] = 0.0f, opaque[3] = 1.0f;
  // px(1, 0) stays fully transparent: the background shows.
  float* half = im.px(2, 0);
  half[0] = 0.25f, half[1] = 0.0f, half[2] = 0.0f, half[3] = 0.5f;
  const std::array<float, 3> bg{0.5f, 0.04f, 0.2f};
  auto r = r1::render::display_srgb8(im, bg);
  ASSERT_TRUE(r.is_ok()) << r.status().message();
  const auto& b = *r;
  ASSERT_EQ(b.size(), 9u);
  const auto near = [](int got, double linear) { return std::abs(got - code_of(srgb_encode(linear))) <= 1; };
  EXPECT_TRUE(near(b[0], 0.18)) << int(b[0]);
  EXPECT_TRUE(near(b[1], 0.5)) << int(b[1]);
  EXPECT_EQ(b[2], 0);
  for (int k = 0; k < 3; ++k) EXPECT_TRUE(near(b[3 + k], static_cast<double>(bg[k]))) << k << " " << int(b[3 + k]);
  EXPECT_TRUE(near(b[6], 0.25 + 0.5 * 0.5)) << int(b[6]);
  EXPECT_TRUE(near(b[7], 0.5 * 0.04)) << int(b[7]);
  EXPECT_TRUE(near(b[8], 0.5 * 0.2)) << int(b[8]);
}

TEST(Display, HighlightsRollOffBelowWhite) {
  Image im(2, 1);
  for (int x = 0; x < 2; ++x) {
    float* p = im.px(x, 0);
    p[0] = p[1] = p[2] = x == 0 ? 4.0f : 1000.0f;
    p[3] = 1.0f;
  }
  auto r = r1::render::display_srgb8(im, {0, 0, 0});
  ASSERT_TRUE(r.is_ok());
  EXPECT_LE((*r)[0], (*r)[3]);
  EXPECT_GT((*r)[0], 240);  // bright, not clipped to a flat plateau far below white
}

TEST(Display, BadBufferIsAnError) {
  Image im(2, 2);
  im.rgba.pop_back();
  EXPECT_EQ(r1::render::display_srgb8(im, {0, 0, 0}).status().kind(), ErrorKind::kInternal);
}

// ---- EXR and PNG (R1-RND-084..085) ----

TEST(WriteImage, ExrReadsBackExactFloatsWithFlow) {
  r1::test::TempDir d;
  const Image im = test_image(7, 5, true);
  const fs::path p = d / "frame.exr";
  const auto s = r1::render::write_image(im, p, {0.1f, 0.2f, 0.3f});
  ASSERT_TRUE(s.is_ok()) << s.message();
  const ReadBack r = read_back(p, OIIO::TypeDesc::FLOAT);
  ASSERT_EQ(r.spec.width, 7);
  ASSERT_EQ(r.spec.height, 5);
  ASSERT_EQ(r.spec.nchannels, 7);
  EXPECT_EQ(r.spec.format, OIIO::TypeDesc::FLOAT);
  EXPECT_EQ(r.spec.get_string_attribute("oiio:ColorSpace"), "Linear");
  // By name: OpenEXR stores channels sorted, so the file's order is not the writer's.
  const char* names[7] = {"R", "G", "B", "A", "flow.X", "flow.Y", "flow.Z"};
  int idx[7];
  for (int c = 0; c < 7; ++c) {
    idx[c] = r.spec.channelindex(names[c]);
    ASSERT_GE(idx[c], 0) << names[c];
  }
  const std::size_t n = 7 * 5;
  for (std::size_t i = 0; i < n; ++i) {
    for (int c = 0; c < 4; ++c) EXPECT_EQ(r.floats[7 * i + idx[c]], im.rgba[4 * i + c]) << i << " " << names[c];
    for (int c = 0; c < 3; ++c)
      EXPECT_EQ(r.floats[7 * i + idx[4 + c]], im.flow[3 * i + c]) << i << " " << names[4 + c];
  }
  EXPECT_EQ(entries(d.path()), 1u);
}

TEST(WriteImage, ExrWithoutFlowHasFourChannels) {
  r1::test::TempDir d;
  const Image im = test_image(4, 3, false);
  ASSERT_TRUE(r1::render::write_image(im, d / "frame.EXR", {0, 0, 0}).is_ok());  // case-insensitive
  const ReadBack r = read_back(d / "frame.EXR", OIIO::TypeDesc::FLOAT);
  ASSERT_EQ(r.spec.nchannels, 4);
  EXPECT_EQ(r.spec.alpha_channel, 3);
  for (std::size_t i = 0; i < im.rgba.size(); ++i) EXPECT_EQ(r.floats[i], im.rgba[i]) << i;
}

TEST(WriteImage, PngReadsBackTheDisplayBytes) {
  r1::test::TempDir d;
  const Image im = test_image(9, 6, true);
  const std::array<float, 3> bg{0.02f, 0.03f, 0.05f};
  const fs::path p = d / "frame.Png";
  ASSERT_TRUE(r1::render::write_image(im, p, bg).is_ok());
  auto expect = r1::render::display_srgb8(im, bg);
  ASSERT_TRUE(expect.is_ok());
  const ReadBack r = read_back(p, OIIO::TypeDesc::UINT8);
  ASSERT_EQ(r.spec.width, 9);
  ASSERT_EQ(r.spec.height, 6);
  ASSERT_EQ(r.spec.nchannels, 3);
  EXPECT_EQ(r.bytes, *expect);
  EXPECT_EQ(entries(d.path()), 1u);
}

TEST(WriteImage, ReplacesAnExistingFileAndLeavesNoTemporary) {
  r1::test::TempDir d;
  r1::test::write_file(d / "frame.png", "not a png");
  ASSERT_TRUE(r1::render::write_image(test_image(3, 3, false), d / "frame.png", {0, 0, 0}).is_ok());
  const auto bytes = r1::test::read_bytes(d / "frame.png");
  ASSERT_GE(bytes.size(), 8u);
  EXPECT_EQ(bytes[1], 'P');
  EXPECT_EQ(bytes[2], 'N');
  EXPECT_EQ(bytes[3], 'G');
  EXPECT_EQ(entries(d.path()), 1u);
}

TEST(WriteImage, SameImageGivesSameBytes) {
  r1::test::TempDir d;
  const Image im = test_image(8, 8, true);
  for (const char* ext : {".png", ".exr"}) {
    const fs::path a = d / (std::string("a") + ext), b = d / (std::string("b") + ext);
    ASSERT_TRUE(r1::render::write_image(im, a, {0, 0, 0}).is_ok());
    ASSERT_TRUE(r1::render::write_image(im, b, {0, 0, 0}).is_ok());
    EXPECT_EQ(r1::test::read_bytes(a), r1::test::read_bytes(b)) << ext;
  }
}

TEST(WriteImage, MissingDirectoryIsAnOutputErrorAndLeavesNothing) {
  r1::test::TempDir d;
  for (const char* name : {"no/such/dir/frame.png", "no/such/dir/frame.exr"}) {
    const auto s = r1::render::write_image(test_image(2, 2, false), d / name, {0, 0, 0});
    ASSERT_FALSE(s.is_ok()) << name;
    EXPECT_EQ(s.kind(), ErrorKind::kOutput) << name;
    EXPECT_EQ(s.message().rfind((d / name).string() + ": ", 0), 0u) << s.message();
  }
  EXPECT_EQ(entries(d.path()), 0u);
}

TEST(WriteImage, DirectoryTargetIsAnOutputErrorAndLeavesItAlone) {
  r1::test::TempDir d;
  fs::create_directory(d / "frame.png");
  const auto s = r1::render::write_image(test_image(2, 2, false), d / "frame.png", {0, 0, 0});
  EXPECT_EQ(s.kind(), ErrorKind::kOutput);
  EXPECT_TRUE(fs::is_directory(d / "frame.png"));
  EXPECT_EQ(entries(d.path()), 1u);
}

TEST(WriteImage, UnsupportedExtensionIsAnInputErrorAndLeavesNothing) {
  r1::test::TempDir d;
  for (const char* name : {"frame.jpg", "frame.tif", "frame", "frame.png.bak"}) {
    const auto s = r1::render::write_image(test_image(2, 2, false), d / name, {0, 0, 0});
    ASSERT_FALSE(s.is_ok()) << name;
    EXPECT_EQ(s.kind(), ErrorKind::kInput) << name;
    EXPECT_EQ(s.message(), (d / name).string() + ": unsupported image extension (use .png or .exr)");
  }
  EXPECT_EQ(entries(d.path()), 0u);
}

// ---- labels (R1-RND-086) ----

TEST(DrawText, ChangesOnlyPixelsNearTheAnchor) {
  Image im(200, 80);
  const Image before = im;
  const int x = 60, y = 50, size = 20;
  const auto s = r1::render::draw_text(im, x, y, "Hi r1", size, {1.0f, 0.5f, 0.25f});
  ASSERT_TRUE(s.is_ok()) << s.message();
  int changed = 0;
  for (int py = 0; py < im.height; ++py) {
    for (int px = 0; px < im.width; ++px) {
      const float* a = im.px(px, py);
      const float* b = before.px(px, py);
      if (std::memcmp(a, b, 4 * sizeof(float)) == 0) continue;
      ++changed;
      // Left of the baseline start, a few glyph heights to the right, from a cap height above
      // the baseline to a descender below it.
      EXPECT_GE(px, x - 2) << px << "," << py;
      EXPECT_LE(px, x + 5 * size) << px << "," << py;
      EXPECT_GE(py, y - size) << px << "," << py;
      EXPECT_LE(py, y + size / 2) << px << "," << py;
      // Premultiplied-consistent: coverage times (r, g, b, 1).
      EXPECT_GT(a[3], 0.0f);
      EXPECT_LE(a[3], 1.0f);
      EXPECT_FLOAT_EQ(a[0], a[3]);
      EXPECT_NEAR(a[1], 0.5f * a[3], 1e-6);
      EXPECT_NEAR(a[2], 0.25f * a[3], 1e-6);
    }
  }
  EXPECT_GT(changed, 20);
}

TEST(DrawText, IsDeterministic) {
  Image a = test_image(120, 40, false), b = a;
  ASSERT_TRUE(r1::render::draw_text(a, 5, 30, "cluster 0x1f", 16, {0.9f, 0.9f, 0.2f}).is_ok());
  ASSERT_TRUE(r1::render::draw_text(b, 5, 30, "cluster 0x1f", 16, {0.9f, 0.9f, 0.2f}).is_ok());
  EXPECT_EQ(a.rgba, b.rgba);
  EXPECT_NE(a.rgba, test_image(120, 40, false).rgba);
}

TEST(DrawText, ClipsAtTheEdgeAndRejectsBadSizes) {
  Image im(30, 20);
  EXPECT_TRUE(r1::render::draw_text(im, 25, 5, "edge", 24, {1, 1, 1}).is_ok());
  EXPECT_EQ(im.rgba.size(), 30u * 20u * 4u);
  EXPECT_EQ(r1::render::draw_text(im, 0, 10, "x", 0, {1, 1, 1}).kind(), ErrorKind::kInput);
}

}  // namespace
