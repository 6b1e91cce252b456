// r1 diff through the command line (spec/render.md R1-RND-112..116, spec/errors.md R1-ERR-005):
// the verdict exit statuses, the report, JSON, the heatmap, and errors that are not verdicts.
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <nlohmann/json.hpp>

#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;
using r1::test::run_cli;

void write_image(const fs::path& p, int w, int h, int nch, OIIO::TypeDesc type, const void* px) {
  auto out = OIIO::ImageOutput::create(p.string());
  ASSERT_TRUE(out) << p;
  OIIO::ImageSpec spec(w, h, nch, type);
  if (nch == 4) spec.alpha_channel = 3;
  ASSERT_TRUE(out->open(p.string(), spec));
  ASSERT_TRUE(out->write_image(type, px));
  ASSERT_TRUE(out->close());
}

// A w x h RGB PNG: a smooth gradient, plus an optional single changed pixel.
void write_png(const fs::path& p, int w, int h, int changed_x = -1, int changed_y = -1) {
  std::vector<std::uint8_t> px(static_cast<std::size_t>(w) * h * 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      std::uint8_t* q = px.data() + 3 * (static_cast<std::size_t>(y) * w + x);
      q[0] = static_cast<std::uint8_t>(40 + 4 * x), q[1] = static_cast<std::uint8_t>(60 + 3 * y), q[2] = 120;
      if (x == changed_x && y == changed_y) q[0] = 250, q[1] = 10, q[2] = 10;
    }
  write_image(p, w, h, 3, OIIO::TypeDesc::UINT8, px.data());
}

void write_flat_png(const fs::path& p, int w, int h, std::uint8_t r, std::uint8_t g, std::uint8_t b) {
  std::vector<std::uint8_t> px(static_cast<std::size_t>(w) * h * 3);
  for (std::size_t i = 0; i < px.size(); i += 3) px[i] = r, px[i + 1] = g, px[i + 2] = b;
  write_image(p, w, h, 3, OIIO::TypeDesc::UINT8, px.data());
}

std::string last_line(const std::string& s) {
  std::string t = s;
  while (!t.empty() && t.back() == '\n') t.pop_back();
  const auto nl = t.rfind('\n');
  return nl == std::string::npos ? t : t.substr(nl + 1);
}

std::size_t entries(const fs::path& dir) {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++n;
  return n;
}

class CliDiff : public ::testing::Test {
 protected:
  r1::test::TempDir dir_;
  fs::path at(const std::string& name) const { return dir_ / name; }
};

TEST_F(CliDiff, IdenticalImagesPass) {
  write_png(at("a.png"), 32, 24);
  write_png(at("b.png"), 32, 24);
  const auto r = run_cli({"diff", at("a.png").string(), at("b.png").string()});
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_TRUE(r.err.empty()) << r.err;
  EXPECT_NE(r.out.find("32x24, 768 pixels"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("max 0.0000 at (0, 0)"), std::string::npos) << r.out;
  EXPECT_EQ(last_line(r.out).rfind("PASS", 0), 0u) << r.out;
}

TEST_F(CliDiff, OneChangedPixelWarnsAndReportsWhere) {
  write_png(at("a.png"), 32, 24);
  write_png(at("b.png"), 32, 24, 5, 7);
  auto r = run_cli({"diff", at("a.png").string(), at("b.png").string()});
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  EXPECT_TRUE(r.err.empty()) << r.err;
  EXPECT_NE(r.out.find("at (5, 7)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("1 pixels (0.130%)"), std::string::npos) << r.out;
  EXPECT_EQ(last_line(r.out).rfind("WARN", 0), 0u) << r.out;

  // JSON: the same statistics as one object.
  r = run_cli({"diff", at("a.png").string(), at("b.png").string(), "--json"});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["verdict"], "WARN");
  EXPECT_EQ(j["exit"], 1);
  EXPECT_EQ(j["pixels"], 768);
  EXPECT_EQ(j["over"], 1);
  EXPECT_EQ(j["max_x"], 5);
  EXPECT_EQ(j["max_y"], 7);
  EXPECT_GT(j["max_2000"].get<double>(), 2.0);
  EXPECT_DOUBLE_EQ(j["mean_2000"].get<double>(), j["max_2000"].get<double>() / 768.0);
  EXPECT_TRUE(j["warn_max"].is_null());

  // A hard ceiling below that pixel's difference turns the warning into a failure; a threshold
  // above it, into a pass.
  r = run_cli({"diff", at("a.png").string(), at("b.png").string(), "--warn-max", "5"});
  EXPECT_EQ(r.exit_code, 4) << r.out << r.err;
  EXPECT_EQ(last_line(r.out).rfind("FAIL", 0), 0u) << r.out;
  r = run_cli({"diff", at("a.png").string(), at("b.png").string(), "--threshold", "200"});
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
}

TEST_F(CliDiff, LargeHueShiftFails) {
  write_flat_png(at("red.png"), 16, 16, 200, 60, 50);
  write_flat_png(at("blue.png"), 16, 16, 50, 60, 200);
  const auto r = run_cli({"diff", at("red.png").string(), at("blue.png").string()});
  EXPECT_EQ(r.exit_code, 4) << r.out << r.err;
  EXPECT_TRUE(r.err.empty()) << r.err;
  EXPECT_NE(r.out.find("256 pixels (100.000%)"), std::string::npos) << r.out;
  EXPECT_EQ(last_line(r.out).rfind("FAIL", 0), 0u) << r.out;
  // A generous --fail-mean makes the same pair a warning only.
  EXPECT_EQ(run_cli({"diff", at("red.png").string(), at("blue.png").string(), "--fail-mean", "200"}).exit_code, 1);
}

TEST_F(CliDiff, SizeMismatchIsFive) {
  write_png(at("a.png"), 32, 24);
  write_png(at("b.png"), 24, 32);
  auto r = run_cli({"diff", at("a.png").string(), at("b.png").string()});
  EXPECT_EQ(r.exit_code, 5) << r.out << r.err;
  EXPECT_TRUE(r.err.empty()) << r.err;
  EXPECT_EQ(last_line(r.out).rfind("SIZE MISMATCH", 0), 0u) << r.out;
  r = run_cli({"diff", at("a.png").string(), at("b.png").string(), "--json", "--heatmap", at("h.png").string()});
  EXPECT_EQ(r.exit_code, 5) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["verdict"], "SIZE MISMATCH");
  EXPECT_FALSE(fs::exists(at("h.png")));
}

TEST_F(CliDiff, ErrorsAreNotVerdicts) {
  write_png(at("a.png"), 8, 8);
  r1::test::write_file(at("text.png"), "not an image\n");
  struct Case {
    std::vector<std::string> args;
    std::string names;  // what the one error line must mention
  };
  const std::vector<Case> cases = {
      {{"diff", at("a.png").string(), at("missing.png").string()}, at("missing.png").string()},
      {{"diff", at("missing.exr").string(), at("a.png").string()}, at("missing.exr").string()},
      {{"diff", at("a.png").string(), at("text.png").string()}, at("text.png").string()},
      {{"diff", at("a.png").string(), at("a.png").string(), "--threshold", "-1"}, "--threshold"},
      {{"diff", at("a.png").string(), at("a.png").string(), "--heatmap", at("h.jpg").string()}, at("h.jpg").string()},
      {{"diff", at("a.png").string()}, "B"},
  };
  for (const auto& c : cases) {
    const auto r = run_cli(c.args);
    EXPECT_EQ(r.exit_code, 2) << c.names << ": " << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_EQ(r.err.rfind("r1: ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(c.names), std::string::npos) << r.err;
  }
  EXPECT_FALSE(fs::exists(at("h.jpg")));
}

TEST_F(CliDiff, HeatmapIsWrittenAndAnUnwritableOneIsThreeWithNothingWritten) {
  write_png(at("a.png"), 32, 24);
  write_png(at("b.png"), 32, 24, 5, 7);
  auto r = run_cli({"diff", at("a.png").string(), at("b.png").string(), "--heatmap", at("heat.png").string()});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  auto in = OIIO::ImageInput::open(at("heat.png").string());
  ASSERT_TRUE(in);
  EXPECT_EQ(in->spec().width, 32);
  EXPECT_EQ(in->spec().height, 24);
  std::vector<std::uint8_t> px(32 * 24 * 3);
  ASSERT_TRUE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, px.data()));
  in->close();
  const std::size_t hot = 3 * (7 * 32 + 5);
  EXPECT_EQ(px[hot], 255);  // the changed pixel is far above 3 x the threshold: white
  EXPECT_EQ(px[hot + 2], 255);
  EXPECT_EQ(*std::max_element(px.begin(), px.begin() + static_cast<std::ptrdiff_t>(hot)), 0);  // all else black

  fs::create_directories(at("out"));
  const std::size_t before = entries(dir_.path());
  r = run_cli({"diff", at("a.png").string(), at("b.png").string(), "--heatmap", (at("out") / "no" / "heat.png").string()});
  EXPECT_EQ(r.exit_code, 3) << r.out << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find("heat.png"), std::string::npos) << r.err;
  EXPECT_EQ(entries(at("out")), 0u);
  EXPECT_EQ(entries(dir_.path()), before);
}

TEST_F(CliDiff, ExrIsCompositedOverTheViewBackground) {
  // A fully transparent scene-linear EXR is the background alone: the view default #0a0c12.
  std::vector<float> clear(10 * 6 * 4, 0.0f);
  write_image(at("clear.exr"), 10, 6, 4, OIIO::TypeDesc::FLOAT, clear.data());
  write_flat_png(at("bg.png"), 10, 6, 10, 12, 18);
  const auto r = run_cli({"diff", at("clear.exr").string(), at("bg.png").string()});
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("max 0.0000"), std::string::npos) << r.out;
}

}  // namespace
