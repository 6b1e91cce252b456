// T0 content (spec/epoch.md R1-EPO-030..036, spec/render.md R1-RND-130..137): the side file's
// errors, paths kept inside its folder, type detection, the epoch's copies and index read back,
// and frames that show an image's pixels, text, and cards for missing content.
#include <gtest/gtest.h>

#include <OpenImageIO/imagebuf.h>

#include <cmath>
#include <filesystem>
#include <set>

#include "content.hpp"
#include "content_pass.hpp"
#include "renderer.hpp"
#include "test_epochs.hpp"
#include "test_support.hpp"

namespace {

using namespace r1::render;
namespace fs = std::filesystem;

const std::vector<r1::ParticleId> kIds = {r1::hemera::hash("alpha"), r1::hemera::hash("beta"), r1::hemera::hash("gamma")};

// A w x h 8-bit RGB PNG whose quadrants are red (top left), blue (top right), green (bottom left)
// and white (bottom right).
void write_quadrants(const fs::path& p, int w, int h) {
  OIIO::ImageBuf buf(OIIO::ImageSpec(w, h, 3, OIIO::TypeDesc::UINT8));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const bool right = x >= w / 2, bottom = y >= h / 2;
      float c[3] = {0, 0, 0};
      if (!bottom && !right) c[0] = 1, c[1] = 0, c[2] = 0;      // red
      if (!bottom && right) c[0] = 0, c[1] = 0, c[2] = 1;       // blue
      if (bottom && !right) c[0] = 0, c[1] = 1, c[2] = 0;       // green
      if (bottom && right) c[0] = 1, c[1] = 1, c[2] = 1;        // white
      buf.setpixel(x, y, c);
    }
  ASSERT_TRUE(buf.write(p.string())) << buf.geterror();
}

r1::Result<ContentSet> read_side(const fs::path& side, const std::string& text) {
  r1::test::write_file(side, text);
  return read_content_side_file(side, kIds);
}

const ContentEntry& only(const ContentSet& c) {
  EXPECT_EQ(c.entries.size(), 1u);
  return c.entries.front();
}

TEST(ContentSideFile, BadLinesAreErrorsNamingFileAndLine) {
  r1::test::TempDir d;
  r1::test::write_file(d / "a.txt", "hello");
  const std::string side = (d / "side.tsv").string();
  for (const auto& [text, line] : std::vector<std::pair<std::string, int>>{
           {"# comment\n\nalpha a.txt\n", 3},             // no TAB
           {"alpha\ta.txt\textra\n", 1},                  // three fields
           {"alpha\t\n", 1},                              // empty path
           {"alpha\ta.txt\nbeta\ta\\q.txt\n", 2},         // bad escape
           {"alpha\ta.txt\nalpha\ta.txt\n", 2},           // a second entry for one particle
           {"alpha\ta.txt\n\xff\ta.txt\n", 2}}) {         // not UTF-8
    const auto r = read_side(side, text);
    ASSERT_FALSE(r.is_ok()) << text;
    EXPECT_EQ(r.status().message().rfind(side + ":" + std::to_string(line) + ": ", 0), 0u) << r.status().message();
    EXPECT_EQ(r.status().message().find('\n'), std::string::npos);
  }
  EXPECT_FALSE(read_content_side_file(d / "absent.tsv", kIds).is_ok());
}

TEST(ContentSideFile, NamesIdsAndUnknownParticles) {
  r1::test::TempDir d;
  r1::test::write_file(d / "a.txt", "hello");
  const std::string text = "alpha\ta.txt\n" + r1::hemera::to_hex(kIds[2]) + "\ta.txt\nnobody\ta.txt\n";
  const auto r = read_side(d / "side.tsv", text);
  ASSERT_TRUE(r.is_ok()) << r.status().message();
  ASSERT_EQ(r->entries.size(), 2u);
  EXPECT_EQ(r->entries[0].particle, 0u);
  EXPECT_EQ(r->entries[1].particle, 2u);
  EXPECT_EQ(r->unknown, 1u);
}

TEST(ContentSideFile, PathsLeavingTheFolderAreRefusedNotRead) {
  r1::test::TempDir d;
  fs::create_directories(d / "site" / "sub");
  r1::test::write_file(d / "secret.txt", "outside");
  r1::test::write_file(d / "site" / "sub" / "in.txt", "inside");
  fs::create_symlink(d / "secret.txt", d / "site" / "link_out.txt");
  fs::create_symlink(d / "site" / "sub" / "in.txt", d / "site" / "link_in.txt");
  const fs::path side = d / "site" / "side.tsv";
  const auto status_of = [&](const std::string& path) {
    const auto r = read_side(side, "alpha\t" + path + "\n");
    EXPECT_TRUE(r.is_ok()) << r.status().message();
    return r.is_ok() ? only(*r) : ContentEntry{};
  };
  for (const std::string& p : {std::string("../secret.txt"), std::string("sub/../../secret.txt"), (d / "secret.txt").string(),
                               std::string("link_out.txt"), std::string("."), std::string("sub/..")}) {
    const ContentEntry e = status_of(p);
    EXPECT_EQ(e.status, ContentStatus::kRefused) << p;
    EXPECT_TRUE(e.bytes.empty()) << p;
  }
  EXPECT_EQ(status_of("sub/in.txt").status, ContentStatus::kOk);
  EXPECT_EQ(status_of("sub/in.txt").bytes, "inside");
  EXPECT_EQ(status_of("link_in.txt").status, ContentStatus::kOk);  // a link that stays inside
  EXPECT_EQ(status_of("nothing.png").status, ContentStatus::kMissing);
  EXPECT_EQ(status_of("sub").status, ContentStatus::kUnreadable);  // a folder
}

TEST(ContentSideFile, TypesFromBytesAndExtension) {
  r1::test::TempDir d;
  write_quadrants(d / "q.png", 8, 8);
  r1::test::write_file(d / "t.txt", "Grüße\nline two");
  r1::test::write_file(d / "bad.txt", std::string("a\xff", 2));
  r1::test::write_file(d / "doc.pdf", std::string("%PDF-1.7\0\x01\x02", 11));
  r1::test::write_file(d / "notes", "plain words");
  r1::test::write_file(d / "ascii.pdf", "%PDF-1.7\n");
  r1::test::write_file(d / "blob", std::string("\0\0\1", 3));
  r1::test::write_file(d / "fake.png", "not an image");
  const auto one = [&](const std::string& f) {
    const auto r = read_side(d / "side.tsv", "alpha\t" + f + "\n");
    EXPECT_TRUE(r.is_ok());
    return r.is_ok() ? only(*r) : ContentEntry{};
  };
  ContentEntry e = one("q.png");
  EXPECT_EQ(e.status, ContentStatus::kOk);
  EXPECT_EQ(e.kind, ContentKind::kImage);
  EXPECT_EQ(e.file, "content/0.png");
  e = one("t.txt");
  EXPECT_EQ(e.kind, ContentKind::kText);
  EXPECT_EQ(e.type, "txt");
  EXPECT_EQ(one("bad.txt").status, ContentStatus::kUnreadable);
  e = one("doc.pdf");
  EXPECT_EQ(e.kind, ContentKind::kOther);
  EXPECT_EQ(e.type, "pdf");
  e = one("ascii.pdf");  // a document type is a card even when its bytes are text
  EXPECT_EQ(e.kind, ContentKind::kOther);
  EXPECT_EQ(e.type, "pdf");
  e = one("notes");
  EXPECT_EQ(e.kind, ContentKind::kText);
  EXPECT_EQ(e.file, "content/0");
  e = one("blob");
  EXPECT_EQ(e.kind, ContentKind::kOther);
  EXPECT_EQ(e.type, "binary");
  EXPECT_EQ(one("fake.png").status, ContentStatus::kUnreadable);
}

TEST(ContentEpochFiles, IndexAndCopiesReadBack) {
  r1::test::TempDir d;
  write_quadrants(d / "q.png", 8, 8);
  r1::test::write_file(d / "t.md", "# title\nwords");
  const auto c = read_side(d / "side.tsv", "alpha\tq.png\nbeta\tgone.jpg\ngamma\tt.md\n");
  ASSERT_TRUE(c.is_ok()) << c.status().message();
  const fs::path ep = d / "epoch";
  fs::create_directories(ep / "content");
  for (const auto& [name, bytes] : content_epoch_files(*c)) r1::test::write_file(ep / name, bytes);
  auto back = read_epoch_content(ep, 3);
  ASSERT_TRUE(back.is_ok()) << back.status().message();
  ASSERT_EQ(back->entries.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    const ContentEntry &a = c->entries[i], &b = back->entries[i];
    EXPECT_EQ(a.particle, b.particle);
    EXPECT_EQ(a.status, b.status);
    EXPECT_EQ(a.type, b.type);
    EXPECT_EQ(a.source, b.source);
    EXPECT_EQ(a.reason, b.reason);
    EXPECT_EQ(a.file, b.file);
    EXPECT_EQ(a.bytes, b.bytes);
  }
  EXPECT_EQ(back->entries[1].status, ContentStatus::kMissing);
  EXPECT_EQ(back->entries[2].path, ep / "content/2.md");
  // Fewer particles than the index names, a modified copy, an index naming another file: errors.
  EXPECT_FALSE(read_epoch_content(ep, 2).is_ok());
  r1::test::write_file(ep / "content/2.md", "# title\nwordz");
  EXPECT_FALSE(read_epoch_content(ep, 3).is_ok());
  std::string index = r1::test::read_file(ep / "content.tsv");
  index.replace(index.find("content/2.md"), 12, "../../x.md00");
  r1::test::write_file(ep / "content.tsv", index);
  const auto bad = read_epoch_content(ep, 3);
  ASSERT_FALSE(bad.is_ok());
  EXPECT_NE(bad.status().message().find("content.tsv:4: "), std::string::npos) << bad.status().message();
  // No index: no content.
  fs::remove(ep / "content.tsv");
  EXPECT_TRUE(read_epoch_content(ep, 3)->entries.empty());
}

// ---- frames ----

// One particle of radius 10 at the origin (and one far out of view), seen from (0, 0, 18) looking
// down -z with +y up in a 201-pixel square at 50 degrees: s = 238 px, so T0.
struct OneParticle {
  r1::Epoch epoch = test::epoch_from("content", {{{0, 0, 0}, 10, r1::Shape::kSphere}, {{5000, 5000, 0}, 10, r1::Shape::kSphere}});
  View view;
  OneParticle() {
    view.width = view.height = 201;
    view.camera.position = {0, 0, 18};
    view.camera.orientation = *look_at(view.camera.position, {0, 0, 0}, {0, 1, 0});
    view.camera.fov_deg = 50;
    view.field = view.edges = view.labels = false;
  }
  Image render(const ContentSet* c, FrameStats* st = nullptr) const {
    Scene s = make_scene(epoch);
    ContentScene cs;
    if (c) {
      cs = make_content_scene(*c, s.n);
      s.content = &cs;
    }
    auto im = render_frame(s, view, {}, st);
    EXPECT_TRUE(im.is_ok()) << im.status().message();
    return im.is_ok() ? *im : Image{};
  }
  ContentSet content(const fs::path& dir) const {
    const auto c = read_content_side_file(dir / "side.tsv", epoch.ids);
    EXPECT_TRUE(c.is_ok()) << c.status().message();
    return c.is_ok() ? *c : ContentSet{};
  }
};

ContentSet side_for(const OneParticle& fr, const fs::path& dir, const std::string& path) {
  r1::test::write_file(dir / "side.tsv", r1::hemera::to_hex(fr.epoch.ids[0]) + "\t" + path + "\n");
  return fr.content(dir);
}

std::array<float, 3> rgb(const Image& im, int x, int y) {
  const float* p = im.px(x, y);
  return {p[0], p[1], p[2]};
}

std::size_t differing(const Image& a, const Image& b) {
  std::size_t n = 0;
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x)
      if (rgb(a, x, y) != rgb(b, x, y)) ++n;
  return n;
}

TEST(ContentFrame, ImageShowsItsPixelsUprightOnAPanel) {
  r1::test::TempDir d;
  write_quadrants(d / "q.png", 64, 64);
  OneParticle fr;
  const ContentSet c = side_for(fr, d.path(), "q.png");
  FrameStats st;
  const Image im = fr.render(&c, &st);
  EXPECT_EQ(st.content, 1u);
  EXPECT_EQ(st.tier_count[0], 1u);
  // The square panel has half side r / sqrt 2 = 7.07 units, 84 px at depth 18: quadrants at +-40 px
  // from the centre pixel (100, 100) show the image's colours exactly (linear = display here).
  const auto near = [](std::array<float, 3> got, std::array<float, 3> want) {
    for (int k = 0; k < 3; ++k)
      if (std::fabs(got[static_cast<std::size_t>(k)] - want[static_cast<std::size_t>(k)]) > 1e-6f) return false;
    return true;
  };
  EXPECT_TRUE(near(rgb(im, 60, 60), {1, 0, 0}));     // top left: red
  EXPECT_TRUE(near(rgb(im, 140, 60), {0, 0, 1}));    // top right: blue
  EXPECT_TRUE(near(rgb(im, 60, 140), {0, 1, 0}));    // bottom left: green
  EXPECT_TRUE(near(rgb(im, 140, 140), {1, 1, 1}));   // bottom right: white
  EXPECT_EQ(im.px(60, 60)[3], 1.0f);
  // Outside the panel but inside the sphere's silhouette: nothing (the particle opened).
  EXPECT_EQ(im.px(100, 100 - 95)[3], 0.0f);
  // Far enough for T1, the same particle is its sphere again, with no red anywhere.
  OneParticle t1 = fr;
  t1.view.tiers.t0 = 1000;
  FrameStats st1;
  const Image sphere = t1.render(&c, &st1);
  EXPECT_EQ(st1.content, 0u);
  EXPECT_FALSE(near(rgb(sphere, 60, 60), {1, 0, 0}));
  EXPECT_GT(sphere.px(100, 100 - 95)[3], 0.0f);
  // Same bytes twice (R1-RND-093).
  EXPECT_EQ(fr.render(&c).rgba, im.rgba);
}

TEST(ContentFrame, MissingRefusedAndOtherContentShowAsCards) {
  r1::test::TempDir d;
  fs::create_directories(d / "site");
  r1::test::write_file(d / "outside.txt", "x");
  r1::test::write_file(d / "site" / "doc.pdf", std::string("%PDF\0\x01", 6));
  OneParticle fr;
  const Image plain = fr.render(nullptr);
  const ContentSet missing = side_for(fr, d / "site", "gone.png");
  ASSERT_EQ(missing.entries.at(0).status, ContentStatus::kMissing);
  const ContentSet refused = side_for(fr, d / "site", "../outside.txt");
  ASSERT_EQ(refused.entries.at(0).status, ContentStatus::kRefused);
  const ContentSet other = side_for(fr, d / "site", "doc.pdf");
  const Image a = fr.render(&missing), b = fr.render(&refused), c = fr.render(&other);
  // Each differs from the plain T1 sphere and from the others (a card of its own colour and words).
  EXPECT_GT(differing(a, plain), 10000u);
  EXPECT_GT(differing(b, plain), 10000u);
  EXPECT_GT(differing(c, plain), 10000u);
  EXPECT_GT(differing(a, b), 10000u);
  EXPECT_GT(differing(a, c), 10000u);
  // The missing card is red near its top left corner (no words there).
  const auto m = rgb(a, 15, 50);
  EXPECT_GT(m[0], 0.2f);
  EXPECT_LT(m[1], 0.05f);
  // Its words are drawn: the card is not one flat colour.
  std::set<std::array<float, 3>> colours;
  for (int x = 0; x < 201; ++x) colours.insert(rgb(a, x, 100));
  EXPECT_GT(colours.size(), 3u);
}

TEST(ContentFrame, TextIsTypesetOnACurvedPage) {
  r1::test::TempDir d;
  OneParticle fr;
  r1::test::write_file(d / "empty.txt", "");
  r1::test::write_file(d / "words.txt", "The quick brown fox jumps over the lazy dog. " + std::string(400, 'x') + "\nsecond paragraph");
  const ContentSet empty = side_for(fr, d.path(), "empty.txt");
  const ContentSet words = side_for(fr, d.path(), "words.txt");
  ASSERT_EQ(words.entries.at(0).kind, ContentKind::kText);
  const Image page = fr.render(&empty), text = fr.render(&words), plain = fr.render(nullptr);
  EXPECT_GT(differing(page, plain), 10000u);  // the page itself
  EXPECT_GT(differing(text, page), 200u);     // ink on it
  // The page is light at the centre of the panel.
  EXPECT_GT(rgb(page, 100, 100)[0], 0.5f);
  // The section curves toward the camera: its centre lies at X'(p), 18 units from the eye, its
  // sides nearer (a flat panel's sides would be farther, 18 / cos of the ray's angle).
  int left = 201, right = -1;
  for (int x = 0; x < 201; ++x)
    if (page.px(x, 100)[3] > 0) left = std::min(left, x), right = std::max(right, x);
  ASSERT_LT(left, 90);
  ASSERT_GT(right, 110);
  const auto depth = [&](int x) { return page.depth[static_cast<std::size_t>(100 * 201 + x)]; };
  EXPECT_NEAR(depth(100), 18.0, 0.05);
  EXPECT_LT(depth(left), 18.0 - 2.0);
  EXPECT_LT(depth(right), 18.0 - 2.0);
}

TEST(ContentFrame, EdgesEnterAnOpenedParticleAtItsSphere) {
  r1::test::TempDir d;
  write_quadrants(d / "q.png", 64, 64);
  OneParticle fr;
  fr.epoch.edges.push_back({0, 1, r1::Q32::kOneRaw, 0});
  const ContentSet c = side_for(fr, d.path(), "q.png");
  const Image bare = fr.render(&c);
  fr.view.edges = true;
  FrameStats st;
  const Image with_edges = fr.render(&c, &st);
  ASSERT_GE(st.edges_drawn, 1u);
  // The tube toward the other particle (up and to the right) starts at the sphere, behind the
  // panel's plane and outside it: the panel's pixels are the same with and without edges.
  std::size_t differ = 0;
  for (int y = 20; y <= 180; ++y)
    for (int x = 20; x <= 180; ++x) differ += rgb(bare, x, y) != rgb(with_edges, x, y);
  EXPECT_EQ(differ, 0u);
  EXPECT_GT(differing(bare, with_edges), 0u);  // the tube is drawn outside the panel
}

TEST(ContentFrame, AnImageThatDoesNotDecodeIsTheUnreadableCard) {
  r1::test::TempDir d;
  r1::test::write_file(d / "x.png", "not a png");
  ContentSet c;
  ContentEntry e;
  e.particle = 0, e.kind = ContentKind::kImage, e.type = "png", e.source = "x.png", e.path = d / "x.png";
  c.entries.push_back(e);
  const ContentScene cs = make_content_scene(c, 2);
  ASSERT_TRUE(cs.has(0));
  EXPECT_FALSE(cs.has(1));
  EXPECT_TRUE(cs.panels[0].card);
  EXPECT_EQ(cs.panels[0].texture.width, 1024);
  EXPECT_EQ(cs.panels[0].texture.height, 640);
}

TEST(ContentFrame, OnlyT0ParticlesWithContentOpen) {
  r1::test::TempDir d;
  OneParticle fr;
  // Content for the other particle only: particle 0 stays a sphere at T0.
  write_quadrants(d / "q.png", 4, 4);
  r1::test::write_file(d / "side.tsv", r1::hemera::to_hex(fr.epoch.ids[1]) + "\tq.png\n");
  const ContentSet c = fr.content(d.path());
  FrameStats st;
  EXPECT_EQ(fr.render(&c, &st).rgba, fr.render(nullptr).rgba);
  EXPECT_EQ(st.content, 0u);
}

}  // namespace
