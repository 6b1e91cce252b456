// The 3DGS .ply export: header layout, exact size, and every row decoding back to the epoch's
// position, radius, colour and the fixed opacity (R1-RND-095..097).
#include "r1/reference/ply_export.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>

#include "r1/fixedpoint/hemera.hpp"
#include "r1/reference/epoch.hpp"
#include "r1/reference/generate.hpp"
#include "r1/reference/graph_build.hpp"

namespace {

using r1::Q32;

r1::Epoch small_epoch() {
  r1::GenParams p;
  p.kind = r1::GenKind::kSbm;
  p.sizes = {40, 30, 20};
  p.p_in = 0.2;
  p.p_out = 0.02;
  p.seed = 3;
  auto s = r1::generate(p);
  EXPECT_TRUE(s.is_ok()) << s.status().message();
  auto g = r1::build_graph(*s);
  EXPECT_TRUE(g.is_ok()) << g.status().message();
  auto e = r1::run_epoch(*s, *g, {});
  EXPECT_TRUE(e.is_ok()) << e.status().message();
  return std::move(*e);
}

// The property list as the 3DGS training code writes it, spelled out independently of the exporter.
std::vector<std::string> expected_properties() {
  std::vector<std::string> v = {"x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2"};
  for (int k = 0; k < 45; ++k) v.push_back("f_rest_" + std::to_string(k));
  for (const char* s : {"opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"}) v.push_back(s);
  return v;
}

struct Parsed {
  std::size_t header_bytes = 0;
  std::size_t vertices = 0;
  std::vector<std::string> comments, properties;
  std::vector<std::vector<double>> rows;  // floats, widened exactly
};

// A minimal reader of what a splat viewer reads: the header line by line, then float rows.
Parsed parse(const std::string& bytes) {
  Parsed p;
  const std::string end = "end_header\n";
  const auto at = bytes.find(end);
  EXPECT_NE(at, std::string::npos);
  if (at == std::string::npos) return p;
  p.header_bytes = at + end.size();
  std::istringstream in(bytes.substr(0, at));
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  EXPECT_GE(lines.size(), 3u);
  EXPECT_EQ(lines.at(0), "ply");
  EXPECT_EQ(lines.at(1), "format binary_little_endian 1.0");
  for (std::size_t i = 2; i < lines.size(); ++i) {
    std::istringstream w(lines[i]);
    std::string kw;
    w >> kw;
    if (kw == "comment") {
      p.comments.push_back(lines[i]);
    } else if (kw == "element") {
      std::string name;
      w >> name >> p.vertices;
      EXPECT_EQ(name, "vertex");
    } else if (kw == "property") {
      std::string type, name;
      w >> type >> name;
      EXPECT_EQ(type, "float") << name;
      p.properties.push_back(name);
    } else {
      ADD_FAILURE() << "unexpected header line: " << lines[i];
    }
  }
  const std::size_t row_bytes = p.properties.size() * 4;
  for (std::size_t off = p.header_bytes; row_bytes > 0 && off + row_bytes <= bytes.size(); off += row_bytes) {
    std::vector<double> row(p.properties.size());
    for (std::size_t k = 0; k < row.size(); ++k) {
      std::uint32_t u = 0;
      for (int b = 3; b >= 0; --b) u = (u << 8) | static_cast<unsigned char>(bytes[off + 4 * k + b]);
      row[k] = static_cast<double>(std::bit_cast<float>(u));
    }
    p.rows.push_back(std::move(row));
  }
  return p;
}

double sigmoid(double x) { return 1 / (1 + std::exp(-x)); }

TEST(PlyExport, HeaderAndSizeFollowTheSplatLayout) {
  const auto e = small_epoch();
  const std::size_t n = e.frame.position.size();
  ASSERT_EQ(n, 90u);
  const std::string bytes = r1::ply_bytes(e);
  const auto p = parse(bytes);
  EXPECT_EQ(p.properties, expected_properties());
  EXPECT_EQ(p.properties.size(), r1::kPlyFloatsPerVertex);
  EXPECT_EQ(p.vertices, n);
  ASSERT_EQ(p.comments.size(), 1u);
  EXPECT_NE(p.comments[0].find(r1::hemera::to_hex(e.snapshot_digest)), std::string::npos) << p.comments[0];
  EXPECT_EQ(bytes.size(), p.header_bytes + 62 * 4 * n);
  EXPECT_EQ(p.rows.size(), n);
}

TEST(PlyExport, RowsDecodeBackToTheEpoch) {
  const auto e = small_epoch();
  const auto p = parse(r1::ply_bytes(e));
  ASSERT_EQ(p.rows.size(), e.frame.position.size());
  const auto col = [&](const std::string& name) {
    const auto& v = p.properties;
    return static_cast<std::size_t>(std::find(v.begin(), v.end(), name) - v.begin());
  };
  for (std::size_t i = 0; i < p.rows.size(); ++i) {
    SCOPED_TRACE(i);
    const auto& r = p.rows[i];
    for (int c = 0; c < 3; ++c) {
      // One float rounding: within half an ulp of the Q32 value, i.e. 2^-24 relative.
      const double q = e.frame.position[i][c].to_double();
      EXPECT_LE(std::abs(r[col(std::string(1, "xyz"[c]))] - q), std::abs(q) * 0x1p-24 + 1e-30);
      EXPECT_EQ(r[col(std::string("n") + "xyz"[c])], 0.0);
      // Colour: f_dc * C0 + 0.5 is the display byte / 255.
      const double want = e.encoding.color[i][c] / 255.0;
      EXPECT_NEAR(r[col("f_dc_" + std::to_string(c))] * r1::kShC0 + 0.5, want, 1e-6);
      // Isotropic scale: exp(scale) is sigma = radius / 2.
      const double radius = e.encoding.radius[i].to_double();
      ASSERT_GT(radius, 0);
      EXPECT_NEAR(std::exp(r[col("scale_" + std::to_string(c))]) * 2, radius, 1e-6 * radius);
    }
    for (int k = 0; k < 45; ++k) EXPECT_EQ(r[col("f_rest_" + std::to_string(k))], 0.0);
    EXPECT_NEAR(sigmoid(r[col("opacity")]), 0.9, 1e-6);
    EXPECT_EQ(r[col("rot_0")], 1.0);
    EXPECT_EQ(r[col("rot_1")], 0.0);
    EXPECT_EQ(r[col("rot_2")], 0.0);
    EXPECT_EQ(r[col("rot_3")], 0.0);
  }
}

// Colours at both ends of the byte range, a negative coordinate, and the sigma floor that guards
// ln(0) for a radius that a real epoch never has.
TEST(PlyExport, ExtremesAndZeroRadiusGuard) {
  r1::Epoch e;
  e.frame.position = {{Q32::from_int(-1000), Q32::from_raw(1), Q32::from_decimal("0.25")},
                      {Q32::from_int(1000), Q32::from_raw(-3), Q32::zero()}};
  e.encoding.radius = {Q32::zero(), Q32::from_int(40)};
  e.encoding.color = {{0, 255, 128}, {255, 0, 1}};
  const std::string bytes = r1::ply_bytes(e);
  const auto p = parse(bytes);
  ASSERT_EQ(p.rows.size(), 2u);
  EXPECT_EQ(bytes.size(), p.header_bytes + 62 * 4 * 2);
  EXPECT_EQ(p.rows[0][0], -1000.0);
  EXPECT_EQ(p.rows[0][1], 0x1p-32);
  EXPECT_EQ(p.rows[0][2], 0.25);
  EXPECT_EQ(p.rows[1][0], 1000.0);
  EXPECT_EQ(p.rows[1][1], -3 * 0x1p-32);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(p.rows[0][6 + c] * r1::kShC0 + 0.5, e.encoding.color[0][c] / 255.0, 1e-6);
    EXPECT_NEAR(p.rows[1][6 + c] * r1::kShC0 + 0.5, e.encoding.color[1][c] / 255.0, 1e-6);
    EXPECT_NEAR(std::exp(p.rows[0][55 + c]), r1::kSplatMinSigma, 1e-6 * r1::kSplatMinSigma);
    EXPECT_TRUE(std::isfinite(p.rows[0][55 + c]));
    EXPECT_NEAR(std::exp(p.rows[1][55 + c]), 20.0, 20e-6);
  }
}

}  // namespace
