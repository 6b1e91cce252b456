// The T0 content pass: textures from an epoch's content and their panels in the frame
// (spec/render.md R1-RND-130..137).
#include "content_pass.hpp"

#include <OpenImageIO/imagebuf.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "image.hpp"

namespace r1::render {

namespace {

// Texture sizes (R1-RND-133): wide enough that a T0 panel (at least 200 px across) is not
// magnified much, small enough to keep one per content particle in memory.
constexpr int kMaxImageSide = 2048;   // larger images are box-filtered down by a whole factor
constexpr int kTextWidth = 1024;      // the text page, pixels
constexpr int kTextSize = 44;         // its font size, pixels: about 45 characters a line
constexpr int kTextLine = 56;         // its line pitch, pixels: 16 lines a page
constexpr int kTextMargin = 48;       // its margins, pixels
constexpr int kCardWidth = 1024, kCardHeight = 640;

using Rgb = std::array<float, 3>;
constexpr Rgb kPage{0.80f, 0.78f, 0.72f};       // the text page: warm light grey
constexpr Rgb kInk{0.015f, 0.015f, 0.02f};      // text on it
constexpr Rgb kCardInk{0.90f, 0.90f, 0.90f};    // words on a card
constexpr Rgb kCardOther{0.06f, 0.09f, 0.16f};  // a card for content r1 does not draw (blue)
constexpr Rgb kCardMissing{0.30f, 0.02f, 0.02f};     // missing (red)
constexpr Rgb kCardUnreadable{0.30f, 0.13f, 0.01f};  // unreadable (orange)
constexpr Rgb kCardRefused{0.20f, 0.02f, 0.22f};     // refused (purple)
constexpr Rgb kBacking{0.05f, 0.05f, 0.05f};     // behind an image's transparent pixels

// A linear RGB image as a float RGBA frame for draw_text (alpha 1 throughout).
Image filled(int w, int h, Rgb c) {
  Image im(w, h);
  for (std::size_t i = 0; i < im.rgba.size(); i += 4) im.rgba[i] = c[0], im.rgba[i + 1] = c[1], im.rgba[i + 2] = c[2], im.rgba[i + 3] = 1;
  return im;
}

ContentTexture to_texture(const Image& im) {
  ContentTexture t{im.width, im.height, {}};
  t.rgb.resize(static_cast<std::size_t>(im.width) * im.height * 3);
  for (std::size_t i = 0, j = 0; j < t.rgb.size(); i += 4, j += 3) t.rgb[j] = im.rgba[i], t.rgb[j + 1] = im.rgba[i + 1], t.rgb[j + 2] = im.rgba[i + 2];
  return t;
}

// The bytes of the longest prefix of `s` that ends on a UTF-8 code point boundary and is at most
// `n` bytes long.
std::size_t utf8_prefix(std::string_view s, std::size_t n) {
  if (n >= s.size()) return s.size();
  while (n > 0 && (static_cast<unsigned char>(s[n]) & 0xC0) == 0x80) --n;
  return n;
}

// `s` cut (at code points) and ended with an ellipsis so that it sets within `width` pixels.
std::string fit(std::string_view s, int size, int width) {
  if (text_width(s, size) <= width) return std::string(s);
  // The longest prefix that fits with the ellipsis, by bisection over byte lengths cut back to
  // code points (widths grow with the prefix), so a long name costs a few measurements.
  const auto cut = [&](std::size_t n) { return std::string(s.substr(0, utf8_prefix(s, n))) + "\u2026"; };
  std::size_t lo = 0, hi = s.size();
  while (hi - lo > 1) {
    const std::size_t mid = (lo + hi) / 2;
    (text_width(cut(mid), size) <= width ? lo : hi) = mid;
  }
  return cut(lo);
}

void centred(Image& im, int baseline, std::string_view text, int size, Rgb ink) {
  const std::string line = fit(text, size, im.width - 2 * kTextMargin);
  const int w = std::max(0, text_width(line, size));
  (void)draw_text(im, (im.width - w) / 2, baseline, line, size, ink);  // no font: a card without words
}

ContentTexture card(Rgb background, std::string_view title, std::string_view subtitle) {
  Image im = filled(kCardWidth, kCardHeight, background);
  centred(im, kCardHeight / 2, title, 110, kCardInk);
  centred(im, kCardHeight / 2 + 90, subtitle, 34, kCardInk);
  return to_texture(im);
}

std::string file_name(const std::string& source) {
  const std::size_t slash = source.find_last_of('/');
  return slash == std::string::npos ? source : source.substr(slash + 1);
}

// Text typeset on the page (R1-RND-133): control characters become spaces, lines break at
// newlines and, greedily, between words at the page width (a word wider than the page breaks
// between code points); what does not fit ends in an ellipsis.
ContentTexture typeset(const std::string& text, int page_height) {
  Image im = filled(kTextWidth, page_height, kPage);
  const int width = kTextWidth - 2 * kTextMargin;
  const std::size_t max_lines = static_cast<std::size_t>(std::max(1, (page_height - 2 * kTextMargin) / kTextLine));
  const auto fits = [&](std::string_view s) { return text_width(s, kTextSize) <= width; };
  std::string clean;
  for (char c : text) clean += (static_cast<unsigned char>(c) < 0x20 && c != '\n') || c == 0x7f ? ' ' : c;
  std::vector<std::string> lines;
  std::size_t start = 0;
  while (start <= clean.size() && lines.size() <= max_lines) {
    std::size_t end = clean.find('\n', start);
    if (end == std::string::npos) end = clean.size();
    const std::string_view para(clean.data() + start, end - start);
    std::string line;
    std::size_t i = 0;
    while (i < para.size()) {
      if (para[i] == ' ') {
        ++i;
        continue;
      }
      std::size_t j = para.find(' ', i);
      if (j == std::string_view::npos) j = para.size();
      std::string_view word = para.substr(i, j - i);
      i = j;
      const std::string trial = line.empty() ? std::string(word) : line + " " + std::string(word);
      if (fits(trial)) {
        line = trial;
        continue;
      }
      if (!line.empty()) lines.push_back(std::move(line));
      line.clear();
      // A word wider than the page breaks between code points (at least one a line).
      while (!fits(word)) {
        // The longest prefix that fits, by bisection over byte lengths cut back to code points
        // (widths grow with the prefix).
        std::size_t lo = 0, hi = word.size();
        while (hi - lo > 1) {
          const std::size_t mid = (lo + hi) / 2;
          (fits(word.substr(0, utf8_prefix(word, mid))) ? lo : hi) = mid;
        }
        std::size_t n = utf8_prefix(word, lo);
        if (n == 0) n = word.size();  // not one code point fits: set the word as it is
        lines.emplace_back(word.substr(0, n));
        word.remove_prefix(n);
      }
      line = std::string(word);
    }
    lines.push_back(std::move(line));
    start = end + 1;
  }
  if (lines.size() > max_lines) {
    lines.resize(max_lines);
    lines.back() = fit(lines.back() + " \u2026", kTextSize, width);
  }
  for (std::size_t k = 0; k < lines.size(); ++k)
    (void)draw_text(im, kTextMargin, kTextMargin + kTextSize + static_cast<int>(k) * kTextLine, lines[k], kTextSize, kInk);
  return to_texture(im);
}

// IEC 61966-2-1 decode of a normalized value (for 16-bit images; 8-bit ones use the exact table).
double srgb_decode(double v) { return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4); }

// An image file as a linear texture (R1-RND-132): 8- and 16-bit images are display sRGB with
// straight alpha, float images scene-linear with premultiplied alpha; grey is spread to RGB;
// alpha composites over a dark backing. Nullopt when OpenImageIO cannot read it.
std::optional<ContentTexture> image_texture(const std::filesystem::path& path) {
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);  // straight alpha as stored, decoded before blending
  OIIO::ImageBuf buf(path.string(), 0, 0, nullptr, &config);
  if (!buf.read(0, 0, true, OIIO::TypeDesc::FLOAT)) {
    (void)OIIO::geterror();
    return std::nullopt;
  }
  const OIIO::ImageSpec& spec = buf.spec();
  const int w = spec.width, h = spec.height, nc = spec.nchannels;
  if (w <= 0 || h <= 0 || nc <= 0) return std::nullopt;
  std::vector<float> px(static_cast<std::size_t>(w) * h * nc);
  if (!buf.get_pixels(OIIO::ROI(0, w, 0, h, 0, 1, 0, nc), OIIO::TypeDesc::FLOAT, px.data())) return std::nullopt;
  const OIIO::TypeDesc stored = buf.nativespec().format;
  const bool is_float = stored.basetype == OIIO::TypeDesc::FLOAT || stored.basetype == OIIO::TypeDesc::HALF ||
                        stored.basetype == OIIO::TypeDesc::DOUBLE;
  const bool is_8bit = stored.basetype == OIIO::TypeDesc::UINT8;
  const int alpha = spec.alpha_channel >= 0 ? spec.alpha_channel : (nc == 2 ? 1 : (nc >= 4 ? 3 : -1));
  const auto decode = [&](float v) -> double {
    if (is_float) return static_cast<double>(v);
    if (is_8bit)
      return static_cast<double>(srgb8_to_linear(static_cast<std::uint8_t>(std::clamp(std::floor(v * 255.0f + 0.5f), 0.0f, 255.0f))));
    return srgb_decode(std::clamp(static_cast<double>(v), 0.0, 1.0));
  };
  // A whole-number box filter keeps large images within kMaxImageSide (R1-RND-132).
  const int k = std::max(1, (std::max(w, h) + kMaxImageSide - 1) / kMaxImageSide);
  ContentTexture t{(w + k - 1) / k, (h + k - 1) / k, {}};
  t.rgb.assign(static_cast<std::size_t>(t.width) * t.height * 3, 0.0f);
  for (int ty = 0; ty < t.height; ++ty)
    for (int tx = 0; tx < t.width; ++tx) {
      double acc[3] = {0, 0, 0};
      int count = 0;
      for (int y = ty * k; y < std::min(h, ty * k + k); ++y)
        for (int x = tx * k; x < std::min(w, tx * k + k); ++x) {
          const float* p = px.data() + (static_cast<std::size_t>(y) * w + x) * nc;
          const double a = alpha >= 0 ? std::clamp(static_cast<double>(p[alpha]), 0.0, 1.0) : 1.0;
          for (int c = 0; c < 3; ++c) {
            const int ch = nc >= 3 ? c : 0;
            const double lin = decode(p[ch]);
            // Float images are premultiplied (EXR), others straight.
            acc[c] += (is_float ? lin : lin * a) + (1 - a) * static_cast<double>(kBacking[static_cast<std::size_t>(c)]);
          }
          ++count;
        }
      for (int c = 0; c < 3; ++c) t.rgb[(static_cast<std::size_t>(ty) * t.width + tx) * 3 + c] = static_cast<float>(acc[c] / count);
    }
  return t;
}

// Bilinear lookup at (u, v) in [0, 1]^2, texel centres at (i + 1/2) / size, edges clamped.
Vec3 sample(const ContentTexture& t, double u, double v) {
  const double x = u * t.width - 0.5, y = v * t.height - 0.5;
  const double fx0 = std::floor(x), fy0 = std::floor(y);
  const double ax = x - fx0, ay = y - fy0;
  const auto at = [&](double xi, double yi) {
    const int cx = static_cast<int>(std::clamp(xi, 0.0, static_cast<double>(t.width - 1)));
    const int cy = static_cast<int>(std::clamp(yi, 0.0, static_cast<double>(t.height - 1)));
    const float* p = t.rgb.data() + (static_cast<std::size_t>(cy) * t.width + cx) * 3;
    return Vec3{static_cast<double>(p[0]), static_cast<double>(p[1]), static_cast<double>(p[2])};
  };
  return (at(fx0, fy0) * (1 - ax) + at(fx0 + 1, fy0) * ax) * (1 - ay) + (at(fx0, fy0 + 1) * (1 - ax) + at(fx0 + 1, fy0 + 1) * ax) * ay;
}

// The text page's height for the cylinder section's shape: arc length 2 R theta across, 2 hh high.
int text_page_height() {
  const double arc = 2 * kTextRadius * kTextHalfAngle, high = 2 * std::sqrt(1 - kTextRadius * kTextRadius);
  return static_cast<int>(std::lround(kTextWidth * high / arc));
}

}  // namespace

ContentScene make_content_scene(const ContentSet& c, std::uint32_t n) {
  ContentScene out;
  out.panel_of.assign(n, -1);
  for (const ContentEntry& e : c.entries) {
    if (e.particle >= n) continue;
    ContentPanel p;
    p.particle = e.particle;
    switch (e.status) {
      case ContentStatus::kMissing:
        p.texture = card(kCardMissing, "missing", file_name(e.source)), p.card = true;
        break;
      case ContentStatus::kUnreadable:
        p.texture = card(kCardUnreadable, "unreadable", file_name(e.source) + ": " + e.reason), p.card = true;
        break;
      case ContentStatus::kRefused:
        p.texture = card(kCardRefused, "refused", e.source + ": " + e.reason), p.card = true;
        break;
      case ContentStatus::kOk:
        if (e.kind == ContentKind::kImage) {
          if (auto t = image_texture(e.path)) p.texture = std::move(*t);
          else p.texture = card(kCardUnreadable, "unreadable", file_name(e.source) + ": not a readable image"), p.card = true;
        } else if (e.kind == ContentKind::kText) {
          p.texture = typeset(e.bytes, text_page_height());
          p.surface = ContentSurface::kCylinder;
        } else {
          p.texture = card(kCardOther, e.type, file_name(e.source)), p.card = true;
        }
        break;
    }
    out.panel_of[e.particle] = static_cast<std::int32_t>(out.panels.size());
    out.panels.push_back(std::move(p));
  }
  return out;
}

std::uint64_t draw_content(const Scene& s, const View& v, const CameraFrame& f, const CullResult& culled, OpaqueLayer& op) {
  if (!s.content) return 0;
  std::uint64_t drawn = 0;
  const int W = op.width;
  for (const Visible& vis : culled.visible) {
    if (vis.tier != Tier::kT0 || !s.content->has(vis.particle)) continue;
    const ContentPanel& panel = s.content->panels[static_cast<std::size_t>(s.content->panel_of[vis.particle])];
    const ContentTexture& tex = panel.texture;
    if (tex.width <= 0 || tex.height <= 0) continue;
    const std::uint32_t p = vis.particle;
    const Vec3 c = s.position[p];
    const double r = s.radius[p];
    // The panel's frame (R1-RND-131): n toward the camera, e_x the camera's right and e_y its up,
    // both made perpendicular to n, so the content faces the viewer upright.
    const Vec3 to_eye = v.camera.position - c;
    const Vec3 n = length(to_eye) > 0 ? normalize(to_eye) : f.forward * -1.0;
    Vec3 ex = f.right - n * dot(f.right, n);
    ex = length(ex) > 1e-12 ? normalize(ex) : normalize(cross(f.up, n));
    const Vec3 ey = cross(n, ex);
    const Rect rect = project_box(v, f, c - Vec3{r, r, r}, c + Vec3{r, r, r});
    if (rect.empty()) continue;
    ++drawn;
    const double aspect = static_cast<double>(tex.width) / tex.height;
    const double hh_flat = r / std::sqrt(1 + aspect * aspect), hw_flat = aspect * hh_flat;
    const double R = kTextRadius * r, hh_cyl = r * std::sqrt(1 - kTextRadius * kTextRadius);
    const Vec3 axis = c + n * R;  // the cylinder's axis passes here, parallel to e_y
    for (int y = rect.y0; y < rect.y1; ++y)
      for (int x = rect.x0; x < rect.x1; ++x) {
        const std::size_t k = static_cast<std::size_t>(y) * W + x;
        const Ray ray = pixel_ray(v, f, x + 0.5, y + 0.5);
        double t_hit = op.t[k], u = 0, w = 0;
        bool hit = false;
        if (panel.surface == ContentSurface::kPanel) {
          const double den = dot(ray.d, n);
          if (den >= 0) continue;  // the panel faces the camera; a ray cannot see its back
          const double t = dot(c - ray.o, n) / den;
          if (!(t > kNear && t < t_hit)) continue;
          const Vec3 q = ray.o + ray.d * t - c;
          const double lx = dot(q, ex), ly = dot(q, ey);
          if (std::fabs(lx) > hw_flat || std::fabs(ly) > hh_flat) continue;
          t_hit = t, u = 0.5 * (lx / hw_flat + 1), w = 0.5 * (1 - ly / hh_flat), hit = true;
        } else {
          // The concave side of the section faces the camera; the nearer root inside it wins.
          const Vec3 o = ray.o - axis;
          const double ox = dot(o, ex), oz = dot(o, n), oy = dot(o, ey);
          const double dx = dot(ray.d, ex), dz = dot(ray.d, n), dy = dot(ray.d, ey);
          const double a = dx * dx + dz * dz, b = ox * dx + oz * dz, cc = ox * ox + oz * oz - R * R;
          const double disc = b * b - a * cc;
          if (!(a > 0) || disc < 0) continue;
          const double sq = std::sqrt(disc);
          for (const double t : {(-b - sq) / a, (-b + sq) / a}) {
            if (!(t > kNear && t < t_hit)) continue;
            const double px = ox + t * dx, pz = oz + t * dz, py = oy + t * dy;
            const double theta = std::atan2(px, -pz);  // 0 at the particle's centre, + toward e_x
            if (std::fabs(theta) > kTextHalfAngle || std::fabs(py) > hh_cyl) continue;
            t_hit = t, u = 0.5 * (theta / kTextHalfAngle + 1), w = 0.5 * (1 - py / hh_cyl), hit = true;
            break;
          }
        }
        if (!hit) continue;
        // Content is drawn as it is, unlit (R1-RND-134): an image keeps its colours.
        op.t[k] = t_hit;
        op.color[k] = sample(tex, u, w);
        op.owner[k] = p;
      }
  }
  return drawn;
}

}  // namespace r1::render
