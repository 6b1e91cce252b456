// T0 content through the command line (spec/epoch.md R1-EPO-030..036, spec/render.md
// R1-RND-130..137): `r1 epoch --content` copies and indexes the content, refuses paths that leave
// the side file's folder, rejects a bad side file with one line naming file:line and writes
// nothing; `r1 render` close to a particle shows its image, and a card for content that is missing.
#include <gtest/gtest.h>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imageio.h>

#include <cmath>

#include "r1/reference/epoch_io.hpp"
#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;
using r1::test::run_cli;

class CliContent : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new r1::test::TempDir;
    ASSERT_EQ(run_cli({"gen", "ring", "--n", "8", "-o", at("ring.graph").string()}).exit_code, 0);
    const auto r = run_cli({"epoch", at("ring.graph").string(), "-q", "-o", at("plain").string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    auto e = r1::read_epoch(at("plain"));
    ASSERT_TRUE(e.is_ok()) << e.status().message();
    epoch_ = new r1::Epoch(std::move(*e));
    // A solid red PNG in the content folder, a file outside it.
    fs::create_directories(at("site"));
    OIIO::ImageBuf red(OIIO::ImageSpec(16, 16, 3, OIIO::TypeDesc::UINT8));
    const float c[3] = {1, 0, 0};
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 16; ++x) red.setpixel(x, y, c);
    ASSERT_TRUE(red.write(at("site/red.png").string()));
    r1::test::write_file(at("outside.png"), r1::test::read_file(at("site/red.png")));
  }
  static void TearDownTestSuite() {
    delete epoch_;
    delete dir_;
  }
  static fs::path at(const std::string& name) { return dir_->path() / name; }
  static std::string id(std::size_t p) { return r1::hemera::to_hex(epoch_->ids[p]); }

  // Renders `epoch` from 1.5 r outside particle 0, radially away from the ring's centre, in a
  // 101-pixel square at 30 degrees (s = 251 px: T0) into an EXR; returns its scene-linear RGB.
  static std::vector<float> render(const fs::path& epoch, const std::string& out) {
    const auto& x = epoch_->frame.position[0];
    const double px = x[0].to_double(), py = x[1].to_double(), pz = x[2].to_double();
    const double r = epoch_->encoding.radius[0].to_double(), len = std::sqrt(px * px + py * py + pz * pz);
    const double d = 1.5 * r / len;
    const auto s = [](double v) { return std::to_string(v); };
    const auto res = run_cli({"render", epoch.string(), "--eye", s(px + px * d), s(py + py * d), s(pz + pz * d), "--target", s(px), s(py),
                              s(pz), "--fov", "30", "--size", "101x101", "--no-field", "--no-edges", "--no-labels", "-o",
                              at(out).string()});
    EXPECT_EQ(res.exit_code, 0) << res.err;
    std::vector<float> rgb(101 * 101 * 3);
    auto in = OIIO::ImageInput::open(at(out).string());
    EXPECT_TRUE(in);
    if (in) {
      EXPECT_TRUE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::FLOAT, rgb.data()));
    }
    return rgb;
  }
  static std::array<float, 3> pixel(const std::vector<float>& rgb, int x, int y) {
    const std::size_t k = (static_cast<std::size_t>(y) * 101 + x) * 3;
    return {rgb[k], rgb[k + 1], rgb[k + 2]};
  }

  static r1::test::TempDir* dir_;
  static r1::Epoch* epoch_;
};
r1::test::TempDir* CliContent::dir_ = nullptr;
r1::Epoch* CliContent::epoch_ = nullptr;

TEST_F(CliContent, EpochCopiesContentAndRenderShowsTheImage) {
  r1::test::write_file(at("site/side.tsv"), "# content\n" + id(0) + "\tred.png\n" + id(1) + "\t../outside.png\n" + id(2) +
                                                "\tgone.txt\nnot-a-particle\tred.png\n");
  const auto r = run_cli({"epoch", at("ring.graph").string(), "--content", at("site/side.tsv").string(), "-o", at("with").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("content            3 particles: 1 image, 0 text, 0 other; 1 missing, 0 unreadable, 1 refused; 1 entry names no particle of the snapshot\n"),
            std::string::npos)
      << r.out;
  // The copy is in the epoch, listed in the manifest and the index; the refused file was not read.
  EXPECT_EQ(r1::test::read_file(at("with/content/0.png")), r1::test::read_file(at("site/red.png")));
  const std::string manifest = r1::test::read_file(at("with/manifest.json"));
  EXPECT_NE(manifest.find("\"content/0.png\""), std::string::npos);
  EXPECT_NE(manifest.find("\"content.tsv\""), std::string::npos);
  const std::string index = r1::test::read_file(at("with/content.tsv"));
  EXPECT_NE(index.find("\n0\tok\timage\tpng\tcontent/0.png\t"), std::string::npos) << index;
  EXPECT_NE(index.find("\n1\trefused\t-\tpng\t-\t-\t-\t../outside.png\t"), std::string::npos) << index;
  EXPECT_NE(index.find("\n2\tmissing\t-\ttxt\t-\t-\t-\tgone.txt\tno such file\n"), std::string::npos) << index;
  EXPECT_EQ(std::distance(fs::directory_iterator(at("with/content")), fs::directory_iterator{}), 1);
  // The epoch's other files are those of the epoch without content.
  for (const char* f : {"positions.q32", "hierarchy.bin", "radius.q32"})
    EXPECT_EQ(r1::test::read_file(at("with") / f), r1::test::read_file(at("plain") / f)) << f;
  auto e = r1::read_epoch(at("with"));
  ASSERT_TRUE(e.is_ok()) << e.status().message();

  // Close up, particle 0 opens at T0 and shows its red image, unlit: linear (1, 0, 0) (a PNG of the
  // frame shows it tone-mapped, R1-RND-082); the plain epoch shows the sphere.
  const auto with = render(at("with"), "with.exr");
  const auto plain = render(at("plain"), "plain.exr");
  for (const auto& [x, y] : std::vector<std::pair<int, int>>{{50, 50}, {30, 30}, {70, 65}})
    EXPECT_EQ(pixel(with, x, y), (std::array<float, 3>{1, 0, 0})) << x << "," << y;
  EXPECT_NE(pixel(plain, 50, 50), (std::array<float, 3>{1, 0, 0}));
  // A modified copy makes the epoch unreadable (its digest), as any other file of it.
  r1::test::write_file(at("with/content/0.png"), "tampered");
  EXPECT_EQ(run_cli({"render", at("with").string(), "--size", "8x8", "-o", at("x.png").string()}).exit_code, 2);
}

TEST_F(CliContent, MissingContentShowsACardNotAnError) {
  r1::test::write_file(at("site/missing.tsv"), id(0) + "\tnot-there.png\n");
  const auto r = run_cli({"epoch", at("ring.graph").string(), "-q", "--content", at("site/missing.tsv").string(), "-o",
                          at("missing").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto card = render(at("missing"), "missing.exr");
  const auto plain = render(at("plain"), "plain2.exr");
  int differ = 0;
  for (int y = 0; y < 101; ++y)
    for (int x = 0; x < 101; ++x) differ += pixel(card, x, y) != pixel(plain, x, y);
  EXPECT_GT(differ, 5000);
  // The card is red where it has no words (its top edge).
  const auto c = pixel(card, 50, 2);
  EXPECT_GT(c[0], 0.2f);
  EXPECT_LT(c[1], 0.05f);
}

TEST_F(CliContent, AnEpochFromAnEarlierOneHasOnlyTheContentItIsGiven) {
  r1::test::write_file(at("site/one.tsv"), id(0) + "\tred.png\n");
  ASSERT_EQ(run_cli({"epoch", at("ring.graph").string(), "-q", "--content", at("site/one.tsv").string(), "-o", at("first").string()})
                .exit_code,
            0);
  // R1-EPO-036: --from reads the earlier epoch (content and all) and carries none of its content.
  auto r = run_cli({"epoch", at("ring.graph").string(), "-q", "--from", at("first").string(), "-o", at("next").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(fs::exists(at("next/content.tsv")));
  EXPECT_FALSE(fs::exists(at("next/content")));
  r = run_cli({"epoch", at("ring.graph").string(), "-q", "--from", at("first").string(), "--content", at("site/one.tsv").string(), "-o",
               at("next2").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r1::test::read_file(at("next2/content/0.png")), r1::test::read_file(at("site/red.png")));
  EXPECT_TRUE(r1::read_epoch(at("next2")).is_ok());
}

TEST_F(CliContent, BadSideFileIsOneLineExitTwoAndWritesNothing) {
  for (const std::string& text : {std::string("# ok\n") + id(0) + " red.png\n", id(0) + "\tred.png\n" + id(0) + "\tred.png\n"}) {
    r1::test::write_file(at("site/bad.tsv"), text);
    const auto r = run_cli({"epoch", at("ring.graph").string(), "--content", at("site/bad.tsv").string(), "-o", at("bad").string()});
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_EQ(r.err.rfind("r1: " + at("site/bad.tsv").string() + ":2: ", 0), 0u) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(fs::exists(at("bad")));
  }
  const auto r = run_cli({"epoch", at("ring.graph").string(), "--content", at("site/none.tsv").string(), "-o", at("bad").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("none.tsv"), std::string::npos);
}

}  // namespace
