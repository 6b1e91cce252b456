// Perceptual image comparison (spec/render.md R1-RND-112..116, R1-ERR-003, R1-ERR-005): reading
// PNG/EXR as display sRGB, per-pixel CIEDE2000/CIE76 statistics, the verdict, the heatmap PNG.
#include "image_diff.hpp"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "image.hpp"
#include "r1/color/delta_e.hpp"
#include "r1/reference/atomic_file.hpp"

namespace r1::render {

namespace fs = std::filesystem;

namespace {

// The largest image side read: the same bound as r1 render's --size, so every image r1 renders
// can be compared, while a corrupt header cannot make the reader allocate without bound.
constexpr int kMaxSide = 16384;

// 8-bit quantization as r1 render's PNG does it (R1-RND-083): clamp to [0, 1], round to nearest,
// halves up.
std::uint8_t quantize8(double v) {
  if (!(v > 0.0)) return 0;  // also NaN
  if (v >= 1.0) return 255;
  return static_cast<std::uint8_t>(std::floor(v * 255.0 + 0.5));
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>((c >= 'A' && c <= 'Z') ? c - 'A' + 'a' : c);
  return s;
}

// OpenImageIO's messages can span lines; an error line keeps the first (R1-ERR-001).
std::string first_line(std::string s) {
  const auto nl = s.find('\n');
  if (nl != std::string::npos) s.resize(nl);
  return s.empty() ? "unknown error" : s;
}

// PNG RGBA (straight alpha) over the background in linear light, encoded like r1 render's PNG.
Status composite_png_alpha(const std::vector<std::uint8_t>& rgba, std::size_t n, std::array<std::uint8_t, 3> background,
                           std::vector<std::uint8_t>& out) {
  out.assign(3 * n, 0);
  std::vector<std::size_t> partial;  // pixels with 0 < alpha < 255
  std::vector<float> linear;         // their composited linear RGB
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint8_t* p = rgba.data() + 4 * i;
    const std::uint8_t a8 = p[3];
    if (a8 == 255) {
      std::copy_n(p, 3, out.begin() + static_cast<std::ptrdiff_t>(3 * i));
    } else if (a8 == 0) {
      std::copy_n(background.begin(), 3, out.begin() + static_cast<std::ptrdiff_t>(3 * i));
    } else {
      const double a = a8 / 255.0;
      partial.push_back(i);
      for (int k = 0; k < 3; ++k) {
        const double c = static_cast<double>(srgb8_to_linear(p[k]));
        const double bg = static_cast<double>(srgb8_to_linear(background[static_cast<std::size_t>(k)]));
        linear.push_back(static_cast<float>(c * a + bg * (1.0 - a)));
      }
    }
  }
  R1_TRY(ocio_linear_to_srgb(linear));
  for (std::size_t j = 0; j < partial.size(); ++j)
    for (std::size_t k = 0; k < 3; ++k) out[3 * partial[j] + k] = quantize8(static_cast<double>(linear[3 * j + k]));
  return Status::ok();
}

// Heat value -> ramp position in [0, 1] (R1-RND-115): clamped because everything at or beyond the
// scale is equally "bright" and a negative difference cannot occur; NaN -> 1, so a broken value
// shows as bright rather than hiding as black.
double ramp_position(float v, double scale) {
  const double t = static_cast<double>(v) / scale;
  if (std::isnan(t)) return 1.0;
  return std::clamp(t, 0.0, 1.0);
}

}  // namespace

Verdict judge(const DiffStats& stats, const DiffOptions& options) {
  if (stats.mean_2000 > options.fail_mean || stats.max_2000 > options.warn_max) return Verdict::kFail;
  if (stats.over > 0) return Verdict::kWarn;
  return Verdict::kPass;
}

const char* verdict_name(Verdict v) {
  switch (v) {
    case Verdict::kPass: return "PASS";
    case Verdict::kWarn: return "WARN";
    case Verdict::kFail: return "FAIL";
    case Verdict::kSizeMismatch: return "SIZE MISMATCH";
  }
  return "FAIL";
}

double percentile_nearest_rank(std::span<double> values, int percent) {
  if (values.empty()) return 0.0;
  const std::uint64_t n = values.size();
  // Clamped to 0..100 so that the rank always names one of the values.
  const std::uint64_t p = static_cast<std::uint64_t>(std::clamp(percent, 0, 100));
  // rank = ceil(p N / 100), exact in integers; rank 0 (p = 0) means the smallest value.
  const std::uint64_t rank = std::max<std::uint64_t>(1, (p * n + 99) / 100);
  const auto nth = values.begin() + static_cast<std::ptrdiff_t>(rank - 1);
  // nth_element places the value of that rank exactly as a full sort would; which equal value
  // lands there cannot change the result.
  std::nth_element(values.begin(), nth, values.end());
  return *nth;
}

DiffStats diff_srgb8(std::span<const std::uint8_t> a, std::span<const std::uint8_t> b, int width, int height,
                     const DiffOptions& options, std::vector<float>* heat) {
  DiffStats st;
  st.width = width, st.height = height;
  if (width <= 0 || height <= 0) return st;
  const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  if (a.size() != 3 * n || b.size() != 3 * n) return st;
  st.pixels = n;

  std::vector<double> de00(n), de76(n);
  double sum00 = 0, sum76 = 0;
  std::size_t max_at = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint8_t* p = a.data() + 3 * i;
    const std::uint8_t* q = b.data() + 3 * i;
    double d00 = 0, d76 = 0;
    // Identical bytes are exactly 0 without the conversion (most pixels of a near-match).
    if (p[0] != q[0] || p[1] != q[1] || p[2] != q[2]) {
      const color::Lab x = color::srgb8_to_lab(p[0], p[1], p[2]);
      const color::Lab y = color::srgb8_to_lab(q[0], q[1], q[2]);
      d00 = color::delta_e_2000(x, y);
      d76 = color::delta_e_76(x, y);
    }
    de00[i] = d00, de76[i] = d76;
    sum00 += d00, sum76 += d76;
    // Strictly greater: the first pixel in row-major order keeps the maximum on ties.
    if (d00 > st.max_2000) {
      st.max_2000 = d00;
      max_at = i;
    }
    st.max_76 = std::max(st.max_76, d76);
    if (d00 > options.threshold) ++st.over;
  }
  st.mean_2000 = sum00 / static_cast<double>(n);
  st.mean_76 = sum76 / static_cast<double>(n);
  st.max_x = static_cast<int>(max_at % static_cast<std::size_t>(width));
  st.max_y = static_cast<int>(max_at / static_cast<std::size_t>(width));
  if (heat) {
    heat->resize(n);
    for (std::size_t i = 0; i < n; ++i) (*heat)[i] = static_cast<float>(de00[i]);
  }
  st.p95_2000 = percentile_nearest_rank(de00, 95);
  st.p99_2000 = percentile_nearest_rank(de00, 99);
  st.p99_76 = percentile_nearest_rank(de76, 99);
  return st;
}

Result<std::vector<std::uint8_t>> read_srgb8(const fs::path& path, int* width, int* height,
                                             std::array<std::uint8_t, 3> background) {
  const std::string where = path.string() + ": ";
  std::error_code ec;
  if (!fs::exists(path, ec)) return Status::input(where + "no such file");
  if (fs::is_directory(path, ec)) return Status::input(where + "is a directory, not an image");

  // Straight alpha as stored: OpenImageIO would otherwise premultiply PNG RGBA on reading.
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  auto in = OIIO::ImageInput::open(path.string(), &config);
  if (!in) return Status::input(where + "not a readable PNG or EXR image (" + first_line(OIIO::geterror()) + ")");
  const std::string format = lower(in->format_name());
  const OIIO::ImageSpec spec = in->spec();
  if (format != "png" && format != "openexr")
    return Status::input(where + "unsupported image format " + format + " (r1 diff reads PNG and EXR)");
  if (spec.deep) return Status::input(where + "deep images are not supported");
  if (spec.width < 1 || spec.height < 1 || spec.width > kMaxSide || spec.height > kMaxSide || spec.depth != 1)
    return Status::input(where + "image size " + std::to_string(spec.width) + "x" + std::to_string(spec.height) +
                         " is outside 1..16384 a side");
  const std::size_t n = static_cast<std::size_t>(spec.width) * static_cast<std::size_t>(spec.height);
  const int nch = spec.nchannels;

  std::vector<std::uint8_t> out;
  if (format == "png") {
    if (spec.format != OIIO::TypeDesc::UINT8)
      return Status::input(where + "PNG with " + std::string(spec.format.c_str()) + " channels (r1 diff reads 8-bit PNG)");
    if (nch != 3 && nch != 4)
      return Status::input(where + "PNG with " + std::to_string(nch) + " channels (r1 diff reads RGB or RGBA)");
    std::vector<std::uint8_t> px(n * static_cast<std::size_t>(nch));
    if (!in->read_image(0, 0, 0, nch, OIIO::TypeDesc::UINT8, px.data()))
      return Status::input(where + "cannot read the pixels (" + first_line(in->geterror()) + ")");
    if (nch == 3) {
      out = std::move(px);
    } else {
      if (Status s = composite_png_alpha(px, n, background, out); !s) return s.with_prefix(where);
    }
  } else {
    const int ir = spec.channelindex("R"), ig = spec.channelindex("G"), ib = spec.channelindex("B");
    const int ia = spec.channelindex("A");
    if (ir < 0 || ig < 0 || ib < 0)
      return Status::input(where + "EXR without R, G and B channels (" + std::to_string(nch) + " channels)");
    std::vector<float> px(n * static_cast<std::size_t>(nch));
    if (!in->read_image(0, 0, 0, nch, OIIO::TypeDesc::FLOAT, px.data()))
      return Status::input(where + "cannot read the pixels (" + first_line(in->geterror()) + ")");
    Image image(spec.width, spec.height);
    for (std::size_t i = 0; i < n; ++i) {
      const float* s = px.data() + i * static_cast<std::size_t>(nch);
      float* d = image.rgba.data() + 4 * i;
      d[0] = s[ir], d[1] = s[ig], d[2] = s[ib];
      d[3] = ia >= 0 ? s[ia] : 1.0f;  // no alpha channel: opaque
    }
    auto rgb = display_srgb8(image, srgb8_to_linear(background));
    if (!rgb) return rgb.status().with_prefix(where);
    out = std::move(rgb).value();
  }
  in->close();
  *width = spec.width;
  *height = spec.height;
  return out;
}

Status write_heatmap(std::span<const float> heat, int width, int height, double scale, const fs::path& out) {
  if (lower(out.extension().string()) != ".png")
    return Status::input(out.string() + ": the heatmap is a PNG (name it .png)");
  if (!(scale > 0.0) || !std::isfinite(scale))
    return Status::input("heatmap scale must be positive and finite, got " + std::to_string(scale));
  if (width <= 0 || height <= 0 ||
      heat.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height))
    return Status::internal("heatmap: " + std::to_string(heat.size()) + " values for " + std::to_string(width) + "x" +
                            std::to_string(height) + " pixels");

  std::vector<std::uint8_t> rgb(3 * heat.size());
  for (std::size_t i = 0; i < heat.size(); ++i) {
    const double s = 3.0 * ramp_position(heat[i], scale);
    for (std::size_t k = 0; k < 3; ++k)
      rgb[3 * i + k] = static_cast<std::uint8_t>(std::floor(255.0 * std::clamp(s - static_cast<double>(k), 0.0, 1.0) + 0.5));
  }

  // Encoded in memory (OpenImageIO through an IOProxy), then written by AtomicFile: the file
  // appears complete or not at all (R1-ERR-003).
  std::vector<unsigned char> encoded;
  {
    OIIO::Filesystem::IOVecOutput proxy(encoded);
    OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
    spec.attribute("oiio:ColorSpace", "sRGB");
    void* proxy_ptr = &proxy;
    spec.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy_ptr);
    auto writer = OIIO::ImageOutput::create("png");
    if (!writer) return Status::internal("heatmap: no PNG writer (" + first_line(OIIO::geterror()) + ")");
    if (!writer->open(out.filename().string(), spec) || !writer->write_image(OIIO::TypeDesc::UINT8, rgb.data()) ||
        !writer->close())
      return Status::internal("heatmap: PNG encoding failed (" + first_line(writer->geterror()) + ")");
  }
  AtomicFile file(out);
  R1_TRY(file.open());
  R1_TRY(file.write(std::span<const std::uint8_t>(encoded.data(), encoded.size())));
  return file.commit();
}

CoveredMean covered_mean_2000(std::span<const std::uint8_t> a, std::span<const std::uint8_t> b, std::span<const float> heat,
                              const std::array<std::uint8_t, 3>& background) {
  const auto background_at = [&](std::span<const std::uint8_t> img, std::size_t p) {
    return img[3 * p] == background[0] && img[3 * p + 1] == background[1] && img[3 * p + 2] == background[2];
  };
  CoveredMean m;
  double sum = 0;
  for (std::size_t p = 0; p < heat.size(); ++p) {
    const bool in_b = !background_at(b, p);
    m.b_covered += in_b ? 1 : 0;
    if (!in_b && background_at(a, p)) continue;
    ++m.covered;
    sum += static_cast<double>(heat[p]);
  }
  m.mean_2000 = m.covered > 0 ? sum / static_cast<double>(m.covered) : 0.0;
  return m;
}

}  // namespace r1::render
