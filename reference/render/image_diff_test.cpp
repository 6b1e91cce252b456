// Perceptual image comparison (spec/render.md R1-RND-112..116): statistics on constructed
// images, nearest-rank percentiles, the verdict, reading PNG/EXR as display sRGB, the heatmap.
#include "image_diff.hpp"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <random>
#include <vector>

#include "image.hpp"
#include "r1/color/delta_e.hpp"
#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;
using r1::ErrorKind;
using r1::render::DiffOptions;
using r1::render::DiffStats;
using r1::render::Verdict;

std::vector<std::uint8_t> flat(int w, int h, std::uint8_t r, std::uint8_t g, std::uint8_t b) {
  std::vector<std::uint8_t> v(static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 3);
  for (std::size_t i = 0; i < v.size(); i += 3) v[i] = r, v[i + 1] = g, v[i + 2] = b;
  return v;
}

void set_px(std::vector<std::uint8_t>& img, int w, int x, int y, std::uint8_t r, std::uint8_t g, std::uint8_t b) {
  const std::size_t i = 3 * (static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x));
  img[i] = r, img[i + 1] = g, img[i + 2] = b;
}

// Writes 8-bit pixels with `nch` channels (any) as a PNG through OpenImageIO.
void write_png(const fs::path& p, int w, int h, int nch, const std::vector<std::uint8_t>& px,
               OIIO::TypeDesc type = OIIO::TypeDesc::UINT8) {
  auto out = OIIO::ImageOutput::create(p.string());
  ASSERT_TRUE(out);
  OIIO::ImageSpec spec(w, h, nch, type);
  if (nch == 4) spec.alpha_channel = 3;
  spec.attribute("oiio:UnassociatedAlpha", 1);  // the bytes as given: no un-premultiplying
  ASSERT_TRUE(out->open(p.string(), spec));
  ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, px.data()));
  ASSERT_TRUE(out->close());
}

TEST(ImageDiff, IdenticalImagesAreZeroEverywhere) {
  std::vector<std::uint8_t> a(24 * 16 * 3);
  for (std::size_t i = 0; i < a.size(); ++i) a[i] = static_cast<std::uint8_t>(i * 37 % 251);
  std::vector<float> heat;
  const DiffStats st = r1::render::diff_srgb8(a, a, 24, 16, {}, &heat);
  EXPECT_EQ(st.width, 24);
  EXPECT_EQ(st.height, 16);
  EXPECT_EQ(st.pixels, 24u * 16u);
  for (double v : {st.mean_2000, st.max_2000, st.p95_2000, st.p99_2000, st.mean_76, st.max_76, st.p99_76}) EXPECT_EQ(v, 0.0);
  EXPECT_EQ(st.over, 0u);
  EXPECT_EQ(st.max_x, 0);
  EXPECT_EQ(st.max_y, 0);
  ASSERT_EQ(heat.size(), 24u * 16u);
  EXPECT_TRUE(std::all_of(heat.begin(), heat.end(), [](float v) { return v == 0.0f; }));
  EXPECT_EQ(r1::render::judge(st, {}), Verdict::kPass);
}

TEST(ImageDiff, OnePixelChangeGivesItsDifferenceAsMaxAndMaxOverPixelsAsMean) {
  const int w = 20, h = 10;
  const auto a = flat(w, h, 90, 100, 110);
  auto b = a;
  set_px(b, w, 7, 4, 200, 30, 40);
  const r1::color::Lab x = r1::color::srgb8_to_lab(90, 100, 110);
  const r1::color::Lab y = r1::color::srgb8_to_lab(200, 30, 40);
  const double d00 = r1::color::delta_e_2000(x, y);
  const double d76 = r1::color::delta_e_76(x, y);
  std::vector<float> heat;
  const DiffStats st = r1::render::diff_srgb8(a, b, w, h, {}, &heat);
  EXPECT_EQ(st.max_2000, d00);
  EXPECT_EQ(st.mean_2000, d00 / 200.0);
  EXPECT_EQ(st.max_76, d76);
  EXPECT_EQ(st.mean_76, d76 / 200.0);
  EXPECT_EQ(st.max_x, 7);
  EXPECT_EQ(st.max_y, 4);
  EXPECT_EQ(st.over, 1u);
  // One value of 200 is above both percentile ranks (190 and 198).
  EXPECT_EQ(st.p95_2000, 0.0);
  EXPECT_EQ(st.p99_2000, 0.0);
  EXPECT_EQ(st.p99_76, 0.0);
  EXPECT_EQ(heat[4 * w + 7], static_cast<float>(d00));
  EXPECT_EQ(r1::render::judge(st, {}), Verdict::kWarn);
  // The same change in both directions gives the same statistics.
  const DiffStats back = r1::render::diff_srgb8(b, a, w, h, {}, nullptr);
  EXPECT_EQ(back.max_2000, st.max_2000);
  EXPECT_EQ(back.mean_2000, st.mean_2000);
}

TEST(ImageDiff, MaxLocationIsTheFirstInRowMajorOrder) {
  const int w = 5, h = 4;
  const auto a = flat(w, h, 0, 0, 0);
  auto b = a;
  set_px(b, w, 3, 2, 255, 255, 255);
  set_px(b, w, 1, 3, 255, 255, 255);
  set_px(b, w, 4, 1, 255, 255, 255);
  const DiffStats st = r1::render::diff_srgb8(a, b, w, h, {}, nullptr);
  EXPECT_NEAR(st.max_2000, 100.0, 1e-9);  // black to white is the whole L* axis
  EXPECT_EQ(st.max_x, 4);
  EXPECT_EQ(st.max_y, 1);
  EXPECT_EQ(st.over, 3u);
}

TEST(ImageDiff, NearestRankPercentiles) {
  std::vector<double> v(100);
  std::iota(v.begin(), v.end(), 1.0);
  std::mt19937 rng(7);
  std::shuffle(v.begin(), v.end(), rng);
  EXPECT_EQ(r1::render::percentile_nearest_rank(v, 95), 95.0);
  EXPECT_EQ(r1::render::percentile_nearest_rank(v, 99), 99.0);
  EXPECT_EQ(r1::render::percentile_nearest_rank(v, 100), 100.0);
  EXPECT_EQ(r1::render::percentile_nearest_rank(v, 0), 1.0);
  std::vector<double> ten = {10, 9, 8, 7, 6, 5, 4, 3, 2, 1};
  EXPECT_EQ(r1::render::percentile_nearest_rank(ten, 95), 10.0);  // rank ceil(9.5) = 10
  EXPECT_EQ(r1::render::percentile_nearest_rank(ten, 50), 5.0);   // rank 5
  EXPECT_EQ(r1::render::percentile_nearest_rank(ten, 91), 10.0);  // rank ceil(9.1) = 10
  EXPECT_EQ(r1::render::percentile_nearest_rank(ten, 90), 9.0);   // rank 9
  std::vector<double> three = {0.5, 3.0, 2.0};
  EXPECT_EQ(r1::render::percentile_nearest_rank(three, 99), 3.0);
  EXPECT_EQ(r1::render::percentile_nearest_rank(three, 34), 2.0);  // rank ceil(1.02) = 2
  EXPECT_EQ(r1::render::percentile_nearest_rank(std::span<double>(), 95), 0.0);

  // Through diff_srgb8: 40 pixels, 37 identical, three different by distinct amounts. Ranks:
  // p95 -> 38, p99 -> 40; the sorted values are 37 zeros then the three differences.
  const int w = 40, h = 1;
  const auto a = flat(w, h, 128, 128, 128);
  auto b = a;
  set_px(b, w, 5, 0, 138, 128, 128);
  set_px(b, w, 17, 0, 128, 160, 128);
  set_px(b, w, 30, 0, 20, 20, 200);
  std::vector<float> heat;
  const DiffStats st = r1::render::diff_srgb8(a, b, w, h, {}, &heat);
  std::vector<double> d = {static_cast<double>(heat[5]), static_cast<double>(heat[17]), static_cast<double>(heat[30])};
  std::sort(d.begin(), d.end());
  EXPECT_EQ(static_cast<float>(st.p95_2000), static_cast<float>(d[0]));
  EXPECT_EQ(static_cast<float>(st.p99_2000), static_cast<float>(d[2]));
  EXPECT_EQ(st.max_2000, st.p99_2000);
}

TEST(ImageDiff, VerdictFollowsTheBounds) {
  DiffStats st;
  st.pixels = 100;
  DiffOptions o;
  EXPECT_EQ(r1::render::judge(st, o), Verdict::kPass);
  st.over = 1, st.max_2000 = 40, st.mean_2000 = 0.4;
  EXPECT_EQ(r1::render::judge(st, o), Verdict::kWarn);  // warn_max is off by default
  o.warn_max = 30;
  EXPECT_EQ(r1::render::judge(st, o), Verdict::kFail);
  o.warn_max = 40;
  EXPECT_EQ(r1::render::judge(st, o), Verdict::kWarn);  // bounds are inclusive
  st.mean_2000 = 2.0;
  EXPECT_EQ(r1::render::judge(st, o), Verdict::kWarn);
  st.mean_2000 = 2.0000001;
  EXPECT_EQ(r1::render::judge(st, o), Verdict::kFail);
  EXPECT_STREQ(r1::render::verdict_name(Verdict::kSizeMismatch), "SIZE MISMATCH");
  EXPECT_EQ(static_cast<int>(Verdict::kWarn), 1);
  EXPECT_EQ(static_cast<int>(Verdict::kFail), 4);
  EXPECT_EQ(static_cast<int>(Verdict::kSizeMismatch), 5);
}

TEST(ImageDiff, WrongSpanSizesGiveEmptyStats) {
  const auto a = flat(4, 4, 1, 2, 3);
  const DiffStats st = r1::render::diff_srgb8(a, std::span(a).first(12), 4, 4, {}, nullptr);
  EXPECT_EQ(st.pixels, 0u);
  EXPECT_EQ(st.max_2000, 0.0);
}

TEST(ImageDiff, ReadsPngRgbAndRgba) {
  r1::test::TempDir dir;
  const int w = 4, h = 3;
  std::vector<std::uint8_t> rgb(w * h * 3);
  for (std::size_t i = 0; i < rgb.size(); ++i) rgb[i] = static_cast<std::uint8_t>(i * 21);
  write_png(dir / "rgb.png", w, h, 3, rgb);
  int rw = 0, rh = 0;
  auto r = r1::render::read_srgb8(dir / "rgb.png", &rw, &rh);
  ASSERT_TRUE(r) << r.status().message();
  EXPECT_EQ(rw, w);
  EXPECT_EQ(rh, h);
  EXPECT_EQ(*r, rgb);

  // RGBA, straight alpha: opaque keeps the bytes, transparent is the background, half alpha lies
  // between them (composited in linear light, so above the mean of the codes for a dark background).
  std::vector<std::uint8_t> rgba(w * h * 4, 0);
  for (int i = 0; i < w * h; ++i) {
    rgba[4 * i + 0] = 200, rgba[4 * i + 1] = 100, rgba[4 * i + 2] = 50;
    rgba[4 * i + 3] = i == 0 ? 255 : (i == 1 ? 0 : 128);
  }
  write_png(dir / "rgba.png", w, h, 4, rgba);
  r = r1::render::read_srgb8(dir / "rgba.png", &rw, &rh, {10, 12, 18});
  ASSERT_TRUE(r) << r.status().message();
  const auto& px = *r;
  EXPECT_EQ((std::vector<std::uint8_t>(px.begin(), px.begin() + 3)), (std::vector<std::uint8_t>{200, 100, 50}));
  EXPECT_EQ((std::vector<std::uint8_t>(px.begin() + 3, px.begin() + 6)), (std::vector<std::uint8_t>{10, 12, 18}));
  EXPECT_GT(px[6], (200 + 10) / 2);
  EXPECT_LT(px[6], 200);
  EXPECT_EQ(px[6], px[3 * 5]);  // every half-alpha pixel alike
}

TEST(ImageDiff, ExrReadsAsTheBytesRenderWritesToPng) {
  r1::test::TempDir dir;
  r1::render::Image im(7, 5);
  for (int y = 0; y < 5; ++y)
    for (int x = 0; x < 7; ++x) {
      float* p = im.px(x, y);
      const float a = static_cast<float>((x + y) % 4) / 3.0f;
      p[0] = a * 0.9f * static_cast<float>(x) / 6.0f, p[1] = a * 0.4f, p[2] = a * 1.7f, p[3] = a;
    }
  const std::array<std::uint8_t, 3> bg8 = r1::render::View{}.background;
  const std::array<float, 3> bg = {r1::render::srgb8_to_linear(bg8[0]), r1::render::srgb8_to_linear(bg8[1]),
                                   r1::render::srgb8_to_linear(bg8[2])};
  ASSERT_TRUE(r1::render::write_image(im, dir / "f.exr", bg));
  ASSERT_TRUE(r1::render::write_image(im, dir / "f.png", bg));
  int w1 = 0, h1 = 0, w2 = 0, h2 = 0;
  const auto exr = r1::render::read_srgb8(dir / "f.exr", &w1, &h1);
  const auto png = r1::render::read_srgb8(dir / "f.png", &w2, &h2);
  ASSERT_TRUE(exr) << exr.status().message();
  ASSERT_TRUE(png) << png.status().message();
  EXPECT_EQ(w1, 7);
  EXPECT_EQ(h1, 5);
  EXPECT_EQ(*exr, *png);
  const DiffStats st = r1::render::diff_srgb8(*exr, *png, 7, 5, {}, nullptr);
  EXPECT_EQ(st.max_2000, 0.0);
  EXPECT_EQ(bg8, (std::array<std::uint8_t, 3>{10, 12, 18}));
}

TEST(ImageDiff, BadInputIsAnInputErrorNamingTheFile) {
  r1::test::TempDir dir;
  int w = 0, h = 0;
  auto expect_input = [&](const fs::path& p) {
    const auto r = r1::render::read_srgb8(p, &w, &h);
    ASSERT_FALSE(r) << p;
    EXPECT_EQ(r.status().kind(), ErrorKind::kInput) << r.status().message();
    EXPECT_NE(r.status().message().find(p.string()), std::string::npos) << r.status().message();
    EXPECT_EQ(r.status().message().find('\n'), std::string::npos);
  };
  expect_input(dir / "missing.png");
  expect_input(dir.path());
  r1::test::write_file(dir / "text.png", "this is not an image\n");
  expect_input(dir / "text.png");
  r1::test::write_file(dir / "text.exr", "nor is this\n");
  expect_input(dir / "text.exr");
  write_png(dir / "grey.png", 3, 2, 1, std::vector<std::uint8_t>(6, 100));
  expect_input(dir / "grey.png");
  write_png(dir / "grey_alpha.png", 3, 2, 2, std::vector<std::uint8_t>(12, 100));
  expect_input(dir / "grey_alpha.png");
  write_png(dir / "deep.png", 3, 2, 3, std::vector<std::uint8_t>(18, 100), OIIO::TypeDesc::UINT16);
  expect_input(dir / "deep.png");
}

TEST(ImageDiff, HeatmapIsWrittenAtomicallyWithTheDocumentedRamp) {
  r1::test::TempDir dir;
  const int w = 6, h = 2;
  const double scale = 6.0;
  const std::vector<float> heat = {0.0f, 2.0f, 4.0f, 6.0f, 100.0f, 1.0f, 0.5f, 3.0f, 5.0f, 7.0f, -1.0f, 0.0f};
  const fs::path out = dir / "heat.png";
  ASSERT_TRUE(r1::render::write_heatmap(heat, w, h, scale, out));
  auto in = OIIO::ImageInput::open(out.string());
  ASSERT_TRUE(in);
  EXPECT_EQ(in->spec().width, w);
  EXPECT_EQ(in->spec().height, h);
  EXPECT_EQ(in->spec().nchannels, 3);
  std::vector<std::uint8_t> px(static_cast<std::size_t>(w) * h * 3);
  ASSERT_TRUE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, px.data()));
  in->close();
  auto at = [&](int i) { return std::vector<int>{px[3 * i], px[3 * i + 1], px[3 * i + 2]}; };
  EXPECT_EQ(at(0), (std::vector<int>{0, 0, 0}));        // 0: black
  EXPECT_EQ(at(1), (std::vector<int>{255, 0, 0}));      // scale / 3: red
  EXPECT_EQ(at(2), (std::vector<int>{255, 255, 0}));    // 2 scale / 3: yellow
  EXPECT_EQ(at(3), (std::vector<int>{255, 255, 255}));  // scale: white
  EXPECT_EQ(at(4), (std::vector<int>{255, 255, 255}));  // beyond: white
  EXPECT_EQ(at(5), (std::vector<int>{128, 0, 0}));      // 127.5 rounds up
  EXPECT_EQ(at(7), (std::vector<int>{255, 128, 0}));
  EXPECT_EQ(at(10), (std::vector<int>{0, 0, 0}));       // negative clamps to black

  // Deterministic bytes, nothing but the file left behind.
  const std::string first = r1::test::read_file(out);
  ASSERT_TRUE(r1::render::write_heatmap(heat, w, h, scale, out));
  EXPECT_EQ(r1::test::read_file(out), first);
  std::size_t entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir.path())) ++entries;
  EXPECT_EQ(entries, 1u);

  // Errors: an unwritable place is an output error and writes nothing; bad arguments are input.
  const auto s = r1::render::write_heatmap(heat, w, h, scale, dir / "no" / "such" / "dir" / "heat.png");
  EXPECT_EQ(s.kind(), ErrorKind::kOutput);
  EXPECT_FALSE(fs::exists(dir / "no"));
  EXPECT_EQ(r1::render::write_heatmap(heat, w, h, scale, dir / "heat.jpg").kind(), ErrorKind::kInput);
  EXPECT_EQ(r1::render::write_heatmap(heat, w, h, 0.0, dir / "h2.png").kind(), ErrorKind::kInput);
  EXPECT_EQ(r1::render::write_heatmap(heat, w, h + 1, scale, dir / "h3.png").kind(), ErrorKind::kInternal);
  entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir.path())) ++entries;
  EXPECT_EQ(entries, 1u);
}

}  // namespace
