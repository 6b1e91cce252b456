// Small fp64 vector algebra shared by the frame stage's boundary types and the renderers (spec/render.md
// R1-RND-001, R1-BKD-014). Every operation is plain IEEE +, -, *, /, sqrt in a fixed order, so two
// renders on one machine give the same bytes; pixels are not canonical (R-1.0 12.3).
#pragma once

#include <array>
#include <cmath>

namespace r1::render {

inline constexpr double kPi = 3.14159265358979323846;

struct Vec3 {
  double x = 0, y = 0, z = 0;

  constexpr Vec3() = default;
  constexpr Vec3(double x_, double y_, double z_) : x(x_), y(y_), z(z_) {}
  static constexpr Vec3 from(const std::array<double, 3>& a) { return {a[0], a[1], a[2]}; }
  constexpr std::array<double, 3> array() const { return {x, y, z}; }

  constexpr double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr Vec3 operator+(const Vec3& b) const { return {x + b.x, y + b.y, z + b.z}; }
  constexpr Vec3 operator-(const Vec3& b) const { return {x - b.x, y - b.y, z - b.z}; }
  constexpr Vec3 operator-() const { return {-x, -y, -z}; }
  constexpr Vec3 operator*(double s) const { return {x * s, y * s, z * s}; }
  constexpr Vec3 operator/(double s) const { return {x / s, y / s, z / s}; }
  Vec3& operator+=(const Vec3& b) { return *this = *this + b; }
  Vec3& operator-=(const Vec3& b) { return *this = *this - b; }
  Vec3& operator*=(double s) { return *this = *this * s; }
  constexpr bool operator==(const Vec3&) const = default;
};

constexpr Vec3 operator*(double s, const Vec3& v) { return v * s; }
constexpr double dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
constexpr Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
constexpr Vec3 hadamard(const Vec3& a, const Vec3& b) { return {a.x * b.x, a.y * b.y, a.z * b.z}; }
inline double length(const Vec3& a) { return std::sqrt(dot(a, a)); }
inline Vec3 normalize(const Vec3& a) { return a / length(a); }

// A ray o + t d; d has unit length wherever the renderer makes one.
struct Ray {
  Vec3 o, d;
  constexpr Vec3 at(double t) const { return o + d * t; }
};

}  // namespace r1::render
