// The frame buffer's outputs and colour (spec/render.md R1-RND-080..086, R1-ERR-003): sRGB
// decode, the display tone map, OpenColorIO display encoding, EXR/PNG writing, text labels.
#include "image.hpp"

#include <fcntl.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <OpenColorIO/OpenColorIO.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>

namespace r1::render {

namespace fs = std::filesystem;
namespace OCIO = OCIO_NAMESPACE;

namespace {

// The IEC 61966-2-1 decode of every 8-bit code, c/255 <= 0.04045 ? (c/255)/12.92 :
// ((c/255 + 0.055)/1.055)^2.4, evaluated in 60-digit decimal arithmetic and rounded once to the
// nearest float. A table rather than std::pow because libm's pow is not correctly rounded and
// may differ between C libraries; these 256 constants are the same everywhere.
constexpr float kSrgbToLinear[256] = {
    0x0p+0f, 0x1.3e4568p-12f, 0x1.3e4568p-11f, 0x1.dd681cp-11f,
    0x1.3e4568p-10f, 0x1.8dd6c2p-10f, 0x1.dd681cp-10f, 0x1.167cbap-9f,
    0x1.3e4568p-9f, 0x1.660e14p-9f, 0x1.8dd6c2p-9f, 0x1.b6a31cp-9f,
    0x1.e1e31ep-9f, 0x1.07c38cp-8f, 0x1.1fcc2cp-8f, 0x1.390ffap-8f,
    0x1.53936cp-8f, 0x1.6f5adep-8f, 0x1.8c6a94p-8f, 0x1.aac6cp-8f,
    0x1.ca7382p-8f, 0x1.eb74e2p-8f, 0x1.06e76cp-7f, 0x1.18c2a6p-7f,
    0x1.2b4e0ap-7f, 0x1.3e8b7cp-7f, 0x1.527cd6p-7f, 0x1.6723eep-7f,
    0x1.7c8292p-7f, 0x1.929a88p-7f, 0x1.a96d92p-7f, 0x1.c0fd68p-7f,
    0x1.d94bbep-7f, 0x1.f25a44p-7f, 0x1.061552p-6f, 0x1.135f3ep-6f,
    0x1.210bb8p-6f, 0x1.2f1b8cp-6f, 0x1.3d8f84p-6f, 0x1.4c6866p-6f,
    0x1.5ba6fap-6f, 0x1.6b4c04p-6f, 0x1.7b5842p-6f, 0x1.8bcc74p-6f,
    0x1.9ca958p-6f, 0x1.adefaap-6f, 0x1.bfa02p-6f, 0x1.d1bb74p-6f,
    0x1.e4425ap-6f, 0x1.f73586p-6f, 0x1.054ad4p-5f, 0x1.0f31bap-5f,
    0x1.194fccp-5f, 0x1.23a55ep-5f, 0x1.2e32c8p-5f, 0x1.38f86p-5f,
    0x1.43f678p-5f, 0x1.4f2d64p-5f, 0x1.5a9d76p-5f, 0x1.664702p-5f,
    0x1.722a56p-5f, 0x1.7e47c8p-5f, 0x1.8a9fa4p-5f, 0x1.97323ap-5f,
    0x1.a3ffd8p-5f, 0x1.b108dp-5f, 0x1.be4d6cp-5f, 0x1.cbcdfap-5f,
    0x1.d98ac6p-5f, 0x1.e7841cp-5f, 0x1.f5ba48p-5f, 0x1.0216cap-4f,
    0x1.096f26p-4f, 0x1.10e65cp-4f, 0x1.187c9p-4f, 0x1.2031e8p-4f,
    0x1.280688p-4f, 0x1.2ffa92p-4f, 0x1.380e2ap-4f, 0x1.404174p-4f,
    0x1.489494p-4f, 0x1.5107acp-4f, 0x1.599adep-4f, 0x1.624e4ep-4f,
    0x1.6b221ep-4f, 0x1.74167p-4f, 0x1.7d2b66p-4f, 0x1.86612p-4f,
    0x1.8fb7cp-4f, 0x1.992f68p-4f, 0x1.a2c83ap-4f, 0x1.ac8256p-4f,
    0x1.b65ddcp-4f, 0x1.c05aecp-4f, 0x1.ca79a8p-4f, 0x1.d4ba3p-4f,
    0x1.df1ca2p-4f, 0x1.e9a12p-4f, 0x1.f447cap-4f, 0x1.ff10bcp-4f,
    0x1.04fe0cp-3f, 0x1.0a84fep-3f, 0x1.101d44p-3f, 0x1.15c6eep-3f,
    0x1.1b8208p-3f, 0x1.214ea6p-3f, 0x1.272cd4p-3f, 0x1.2d1ca2p-3f,
    0x1.331e1ep-3f, 0x1.393158p-3f, 0x1.3f566p-3f, 0x1.458d42p-3f,
    0x1.4bd60ep-3f, 0x1.5230d4p-3f, 0x1.589dap-3f, 0x1.5f1c84p-3f,
    0x1.65ad8ap-3f, 0x1.6c50c4p-3f, 0x1.73063ep-3f, 0x1.79ce06p-3f,
    0x1.80a82ep-3f, 0x1.8794cp-3f, 0x1.8e93ccp-3f, 0x1.95a55ep-3f,
    0x1.9cc986p-3f, 0x1.a40052p-3f, 0x1.ab49cep-3f, 0x1.b2a60ap-3f,
    0x1.ba1512p-3f, 0x1.c196f4p-3f, 0x1.c92bbep-3f, 0x1.d0d37cp-3f,
    0x1.d88e3ep-3f, 0x1.e05c0ep-3f, 0x1.e83cfcp-3f, 0x1.f03116p-3f,
    0x1.f83866p-3f, 0x1.00297ep-2f, 0x1.044072p-2f, 0x1.086116p-2f,
    0x1.0c8b7p-2f, 0x1.10bf86p-2f, 0x1.14fd6p-2f, 0x1.194502p-2f,
    0x1.1d9676p-2f, 0x1.21f1bep-2f, 0x1.2656e4p-2f, 0x1.2ac5ecp-2f,
    0x1.2f3edep-2f, 0x1.33c1cp-2f, 0x1.384e98p-2f, 0x1.3ce56cp-2f,
    0x1.418642p-2f, 0x1.46312p-2f, 0x1.4ae60ep-2f, 0x1.4fa51p-2f,
    0x1.546e2cp-2f, 0x1.59416cp-2f, 0x1.5e1edp-2f, 0x1.630664p-2f,
    0x1.67f82ap-2f, 0x1.6cf428p-2f, 0x1.71fa68p-2f, 0x1.770aecp-2f,
    0x1.7c25bcp-2f, 0x1.814adcp-2f, 0x1.867a54p-2f, 0x1.8bb428p-2f,
    0x1.90f86p-2f, 0x1.9647p-2f, 0x1.9ba01p-2f, 0x1.a10394p-2f,
    0x1.a67192p-2f, 0x1.abea1p-2f, 0x1.b16d14p-2f, 0x1.b6faa4p-2f,
    0x1.bc92c6p-2f, 0x1.c2357ep-2f, 0x1.c7e2d2p-2f, 0x1.cd9acap-2f,
    0x1.d35d6ap-2f, 0x1.d92ab6p-2f, 0x1.df02b8p-2f, 0x1.e4e57p-2f,
    0x1.ead2e8p-2f, 0x1.f0cb26p-2f, 0x1.f6ce2cp-2f, 0x1.fcdcp-2f,
    0x1.017a56p-1f, 0x1.048c18p-1f, 0x1.07a34ap-1f, 0x1.0abfeep-1f,
    0x1.0de208p-1f, 0x1.11099ap-1f, 0x1.1436a8p-1f, 0x1.176932p-1f,
    0x1.1aa13ep-1f, 0x1.1ddecap-1f, 0x1.2121dep-1f, 0x1.246a7ap-1f,
    0x1.27b8ap-1f, 0x1.2b0c54p-1f, 0x1.2e6598p-1f, 0x1.31c46ep-1f,
    0x1.3528dcp-1f, 0x1.3892ep-1f, 0x1.3c028p-1f, 0x1.3f77bcp-1f,
    0x1.42f29ap-1f, 0x1.467318p-1f, 0x1.49f93ep-1f, 0x1.4d850ap-1f,
    0x1.511682p-1f, 0x1.54ada4p-1f, 0x1.584a78p-1f, 0x1.5becfep-1f,
    0x1.5f9538p-1f, 0x1.634328p-1f, 0x1.66f6d4p-1f, 0x1.6ab03ap-1f,
    0x1.6e6f6p-1f, 0x1.723448p-1f, 0x1.75fef4p-1f, 0x1.79cf64p-1f,
    0x1.7da59ep-1f, 0x1.8181a4p-1f, 0x1.856378p-1f, 0x1.894b1cp-1f,
    0x1.8d3892p-1f, 0x1.912bdep-1f, 0x1.9525p-1f, 0x1.9923fep-1f,
    0x1.9d28d8p-1f, 0x1.a13392p-1f, 0x1.a5442cp-1f, 0x1.a95aacp-1f,
    0x1.ad771p-1f, 0x1.b1995ep-1f, 0x1.b5c198p-1f, 0x1.b9efbep-1f,
    0x1.be23d4p-1f, 0x1.c25ddep-1f, 0x1.c69ddcp-1f, 0x1.cae3d2p-1f,
    0x1.cf2fcp-1f, 0x1.d381aap-1f, 0x1.d7d994p-1f, 0x1.dc377ep-1f,
    0x1.e09b6ap-1f, 0x1.e5055cp-1f, 0x1.e97556p-1f, 0x1.edeb5cp-1f,
    0x1.f2676cp-1f, 0x1.f6e98cp-1f, 0x1.fb71bcp-1f, 0x1p+0f,
};

// The largest float below 1. The tone map's output is capped here so that it stays below
// display white even where the roll-off's exact value rounds up to 1 (maximum channel > ~6.7e6).
constexpr float kBelowOne = 0x1.fffffep-1f;

// Non-finite or negative -> 0 (R1-RND-082): a NaN or an infinity in the frame buffer is a bug
// upstream, and black makes it visible without letting it spread to the neighbouring pixels.
double sanitize(float v) { return (std::isfinite(v) && v > 0.0f) ? static_cast<double>(v) : 0.0; }

// 8-bit quantization: clamp to [0, 1], then round to nearest (halves up). Rounding rather than
// truncating keeps the code of an exact encode c/255 equal to c.
std::uint8_t quantize8(float v) {
  if (!(v > 0.0f)) return 0;  // also NaN
  if (v >= 1.0f) return 255;
  return static_cast<std::uint8_t>(std::floor(static_cast<double>(v) * 255.0 + 0.5));
}

// The display transform, built once. OCIO 2.1 ships no built-in configs, so the config is made
// here: a raw config plus "linear" (the scene-linear Rec.709 reference) and "sRGB", whose
// to-reference transform is the sRGB decode as OCIO's ExponentWithLinearTransform (gamma 2.4,
// offset 0.055). linear -> sRGB therefore runs that transform inverted: the sRGB encode.
struct DisplayProcessor {
  OCIO::ConstCPUProcessorRcPtr cpu;
  std::string error;  // non-empty when the config or processor could not be built
};

DisplayProcessor build_display_processor() {
  DisplayProcessor d;
  try {
    OCIO::ConfigRcPtr config = OCIO::Config::CreateRaw()->createEditableCopy();

    OCIO::ColorSpaceRcPtr linear = OCIO::ColorSpace::Create();
    linear->setName("linear");
    linear->setEncoding("scene-linear");
    linear->setDescription("scene-linear light, Rec.709/sRGB primaries, D65 (the r1 frame buffer)");
    config->addColorSpace(linear);

    OCIO::ExponentWithLinearTransformRcPtr decode = OCIO::ExponentWithLinearTransform::Create();
    // Alpha: gamma 1, offset 0 is the identity (OCIO requires gamma in [1, 10] on every channel).
    const double gamma[4] = {2.4, 2.4, 2.4, 1.0};
    const double offset[4] = {0.055, 0.055, 0.055, 0.0};
    decode->setGamma(gamma);
    decode->setOffset(offset);
    // OCIO allows only LINEAR or MIRROR here (CLAMP is refused). The input is never negative
    // (tone_map clamps it), so the choice does not change any output; LINEAR is OCIO's default.
    decode->setNegativeStyle(OCIO::NEGATIVE_LINEAR);
    decode->setDirection(OCIO::TRANSFORM_DIR_FORWARD);

    OCIO::ColorSpaceRcPtr srgb = OCIO::ColorSpace::Create();
    srgb->setName("sRGB");
    srgb->setEncoding("sdr-video");
    srgb->setDescription("sRGB display encoding (IEC 61966-2-1 curve), Rec.709 primaries");
    srgb->setTransform(decode, OCIO::COLORSPACE_DIR_TO_REFERENCE);
    config->addColorSpace(srgb);

    config->setRole(OCIO::ROLE_SCENE_LINEAR, "linear");
    config->setRole(OCIO::ROLE_REFERENCE, "linear");
    config->validate();

    OCIO::ConstProcessorRcPtr processor = config->getProcessor("linear", "sRGB");
    // LOSSLESS: no OPTIMIZATION_FAST_LOG_EXP_POW (part of OCIO's default), whose approximate pow
    // would move the result further from the closed-form curve.
    d.cpu = processor->getOptimizedCPUProcessor(OCIO::BIT_DEPTH_F32, OCIO::BIT_DEPTH_F32,
                                                OCIO::OPTIMIZATION_LOSSLESS);
  } catch (const std::exception& e) {
    d.error = e.what();
  }
  return d;
}

const DisplayProcessor& display_processor() {
  static const DisplayProcessor d = build_display_processor();  // thread-safe initialisation
  return d;
}

Status check_image(const Image& image) {
  const auto n = static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height);
  if (image.width <= 0 || image.height <= 0)
    return Status::internal("image has no pixels (" + std::to_string(image.width) + "x" +
                            std::to_string(image.height) + ")");
  if (image.rgba.size() != 4 * n) return Status::internal("image RGBA buffer has the wrong size");
  if (!image.flow.empty() && image.flow.size() != 3 * n)
    return Status::internal("image flow buffer has the wrong size");
  return Status::ok();
}

enum class Format { kExr, kPng };

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>((c >= 'A' && c <= 'Z') ? c - 'A' + 'a' : c);
  return s;
}

// Writes through OpenImageIO to `temp` (which exists, empty). Returns "" or the error text.
std::string oiio_write(const std::string& temp, const OIIO::ImageSpec& spec, OIIO::TypeDesc type,
                       const void* pixels) {
  auto out = OIIO::ImageOutput::create(temp);
  if (!out) {
    const std::string e = OIIO::geterror();
    return e.empty() ? "no image writer" : e;
  }
  if (!out->open(temp, spec)) return out->geterror();
  if (!out->write_image(type, pixels)) {
    std::string e = out->geterror();
    out->close();
    return e;
  }
  if (!out->close()) return out->geterror();
  return {};
}

// R1-ERR-003 for a writer that needs a file name (OIIO): a unique hidden temporary beside the
// target, ending in the format's extension so that OIIO picks the format, written, flushed,
// renamed over the target; on any failure the temporary is removed and the target is untouched.
Status write_atomically(const fs::path& path, const std::string& ext, const OIIO::ImageSpec& spec,
                        OIIO::TypeDesc type, const void* pixels) {
  const std::string where = path.string() + ": ";
  std::error_code ec;
  if (fs::is_directory(path, ec)) return Status::output(where + "is a directory");
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  if (!fs::is_directory(dir, ec))
    return Status::output(where + "directory " + dir.string() + " does not exist");

  std::string temp = (dir / ("." + path.filename().string() + ".tmp-XXXXXX" + ext)).string();
  const int fd = ::mkstemps(temp.data(), static_cast<int>(ext.size()));
  if (fd < 0) return Status::output(where + "cannot create a temporary: " + std::strerror(errno));
  // mkstemps makes the file 0600; an image is an ordinary output, readable like the others
  // AtomicFile writes (0644).
  ::fchmod(fd, 0644);
  ::close(fd);

  auto fail = [&](const std::string& why) {
    std::error_code rm;
    fs::remove(temp, rm);
    return Status::output(where + why);
  };
  if (std::string e = oiio_write(temp, spec, type, pixels); !e.empty()) return fail("write failed: " + e);

  // OIIO closes the file without fsync; flush it before the rename makes it visible.
  const int rfd = ::open(temp.c_str(), O_RDONLY | O_CLOEXEC);
  if (rfd < 0) return fail(std::string("cannot reopen the temporary: ") + std::strerror(errno));
  const bool synced = ::fsync(rfd) == 0;
  const int sync_errno = errno;
  ::close(rfd);
  if (!synced) return fail(std::string("flush failed: ") + std::strerror(sync_errno));
  if (::rename(temp.c_str(), path.c_str()) != 0)
    return fail(std::string("rename failed: ") + std::strerror(errno));
  return Status::ok();
}

}  // namespace

float srgb8_to_linear(std::uint8_t v) { return kSrgbToLinear[v]; }

std::array<float, 3> srgb8_to_linear(const std::array<std::uint8_t, 3>& rgb) {
  return {kSrgbToLinear[rgb[0]], kSrgbToLinear[rgb[1]], kSrgbToLinear[rgb[2]]};
}

// R1-RND-082. With m the largest channel and k = kToneKnee (0.8):
//   m <= k:  identity;
//   m >  k:  m' = k + (1 - k) * d / (d + (1 - k)),  d = m - k,
// and every channel is scaled by m'/m, so the ratios between channels (hue and saturation) are
// kept. The shoulder is rational (only +, -, *, /, correctly rounded, so the same on every
// machine), has slope 1 at the knee (C1: no visible band where the roll-off starts), rises
// strictly, and tends to 1 without reaching it. Computed in double, rounded once to float,
// capped at the largest float below 1.
std::array<float, 3> tone_map(std::array<float, 3> rgb) {
  const double c[3] = {sanitize(rgb[0]), sanitize(rgb[1]), sanitize(rgb[2])};
  const double m = std::max({c[0], c[1], c[2]});
  if (m <= kToneKnee)
    return {static_cast<float>(c[0]), static_cast<float>(c[1]), static_cast<float>(c[2])};
  const double span = 1.0 - kToneKnee;
  const double d = m - kToneKnee;
  const double mapped = kToneKnee + span * (d / (d + span));
  const double scale = mapped / m;
  std::array<float, 3> out{};
  for (int i = 0; i < 3; ++i) out[i] = std::min(static_cast<float>(c[i] * scale), kBelowOne);
  return out;
}

Status ocio_linear_to_srgb(std::span<float> rgb) {
  if (rgb.size() % 3 != 0) return Status::internal("RGB buffer length is not a multiple of 3");
  if (rgb.empty()) return Status::ok();
  const DisplayProcessor& d = display_processor();
  if (!d.cpu) return Status::internal("OpenColorIO display transform: " + d.error);
  try {
    OCIO::PackedImageDesc desc(rgb.data(), static_cast<long>(rgb.size() / 3), 1, 3);
    d.cpu->apply(desc);
  } catch (const std::exception& e) {
    return Status::internal(std::string("OpenColorIO: ") + e.what());
  }
  return Status::ok();
}

Result<std::vector<std::uint8_t>> display_srgb8(const Image& image, std::array<float, 3> background) {
  R1_TRY(check_image(image));
  const std::size_t n = static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height);
  const double bg[3] = {sanitize(background[0]), sanitize(background[1]), sanitize(background[2])};
  std::vector<float> rgb(3 * n);
  for (std::size_t i = 0; i < n; ++i) {
    const float* p = image.rgba.data() + 4 * i;
    // Premultiplied "over": C + (1 - A) * background. Alpha is clamped to [0, 1] (non-finite ->
    // 0, as for colour) so that a bad alpha can neither amplify nor negate the background.
    const double a = std::min(sanitize(p[3]), 1.0);
    std::array<float, 3> c{};
    for (int k = 0; k < 3; ++k) c[k] = static_cast<float>(sanitize(p[k]) + (1.0 - a) * bg[k]);
    const std::array<float, 3> t = tone_map(c);
    std::copy(t.begin(), t.end(), rgb.begin() + static_cast<std::ptrdiff_t>(3 * i));
  }
  R1_TRY(ocio_linear_to_srgb(rgb));
  std::vector<std::uint8_t> out(3 * n);
  for (std::size_t i = 0; i < 3 * n; ++i) out[i] = quantize8(rgb[i]);
  return out;
}

Status check_image_extension(const fs::path& path) {
  const std::string ext = lower(path.extension().string());
  if (ext == ".exr" || ext == ".png") return Status::ok();
  return Status::input(path.string() + ": unsupported image extension (use .png or .exr)");
}

Status write_image(const Image& image, const fs::path& path, std::array<float, 3> background) {
  R1_TRY(check_image_extension(path));
  const std::string ext = lower(path.extension().string());
  const Format format = ext == ".exr" ? Format::kExr : Format::kPng;
  if (Status s = check_image(image); !s) return s.with_prefix(path.string() + ": ");

  if (format == Format::kPng) {
    R1_ASSIGN(const std::vector<std::uint8_t> bytes, display_srgb8(image, background));
    OIIO::ImageSpec spec(image.width, image.height, 3, OIIO::TypeDesc::UINT8);
    spec.attribute("oiio:ColorSpace", "sRGB");
    return write_atomically(path, ext, spec, OIIO::TypeDesc::UINT8, bytes.data());
  }

  // EXR: 32-bit float, scene-linear, premultiplied (EXR's own convention), R G B A then the
  // flow vector when there is one. Interleaved here because OIIO writes one pixel at a time.
  const bool flow = !image.flow.empty();
  const int nch = flow ? 7 : 4;
  const std::size_t n = static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height);
  std::vector<float> pixels(static_cast<std::size_t>(nch) * n);
  for (std::size_t i = 0; i < n; ++i) {
    float* dst = pixels.data() + static_cast<std::size_t>(nch) * i;
    std::copy_n(image.rgba.data() + 4 * i, 4, dst);
    if (flow) std::copy_n(image.flow.data() + 3 * i, 3, dst + 4);
  }
  OIIO::ImageSpec spec(image.width, image.height, nch, OIIO::TypeDesc::FLOAT);
  spec.channelnames = {"R", "G", "B", "A"};
  if (flow) spec.channelnames.insert(spec.channelnames.end(), {"flow.X", "flow.Y", "flow.Z"});
  spec.alpha_channel = 3;
  spec.attribute("oiio:ColorSpace", "Linear");
  // Lossless and the same bytes for the same pixels; fixed here rather than left to OIIO's default.
  spec.attribute("compression", "zip");
  // OIIO stamps the time of writing (EXR's capDate) unless told a date: none, so that the same
  // pixels give the same bytes on every run (a golden set rewritten without a change stays as it was).
  spec.attribute("DateTime", "");
  return write_atomically(path, ext, spec, OIIO::TypeDesc::FLOAT, pixels.data());
}

// DejaVu Sans by name (OIIO searches its font directories, /usr/share/fonts among them), then
// by the Debian path: the same glyphs everywhere fonts-dejavu-core is installed.
static const char* const kFonts[] = {"DejaVuSans", "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf"};

Status draw_text(Image& image, int x, int y, std::string_view text, int size, std::array<float, 3> rgb) {
  R1_TRY(check_image(image));
  if (size <= 0) return Status::input("label size must be positive, got " + std::to_string(size));
  if (text.empty()) return Status::ok();
  // Wraps the frame buffer: OIIO draws into it in place.
  OIIO::ImageBuf buf(OIIO::ImageSpec(image.width, image.height, 4, OIIO::TypeDesc::FLOAT), image.rgba.data());
  // OIIO blends each channel as colour * coverage + dst * (1 - coverage). With alpha 1 in the
  // colour this is premultiplied "over" of an opaque glyph with coverage as its alpha, so the
  // buffer stays premultiplied-consistent.
  const float colour[4] = {rgb[0], rgb[1], rgb[2], 1.0f};
  for (const char* font : kFonts) {
    if (!OIIO::ImageBufAlgo::text_size("x", size, font).defined()) {
      (void)OIIO::geterror();  // clear OIIO's per-thread error message
      continue;
    }
    // nthreads = 1: one thread, so the blend order cannot depend on the machine.
    if (!OIIO::ImageBufAlgo::render_text(buf, x, y, text, size, font, colour, OIIO::ImageBufAlgo::TextAlignX::Left,
                                         OIIO::ImageBufAlgo::TextAlignY::Baseline, 0, {}, 1))
      return Status::internal("label \"" + std::string(text) + "\": " + buf.geterror());
    return Status::ok();
  }
  return Status::input("no font for labels: install fonts-dejavu-core");
}

int text_width(std::string_view text, int size) {
  if (text.empty() || size <= 0) return 0;
  for (const char* font : kFonts) {
    const OIIO::ROI roi = OIIO::ImageBufAlgo::text_size(text, size, font);
    if (!roi.defined()) {
      (void)OIIO::geterror();
      continue;
    }
    return roi.width();
  }
  return -1;
}

}  // namespace r1::render
