// Small fixed-size vector maths shared by the JSON reader, the scene model, the voxelizer and the
// pipelines.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>

namespace scatter {

struct Vec3 {
  double x = 0, y = 0, z = 0;

  constexpr double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr double& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr Vec3 operator+(const Vec3& o) const { return {x + o.x, y + o.y, z + o.z}; }
  constexpr Vec3 operator-(const Vec3& o) const { return {x - o.x, y - o.y, z - o.z}; }
  constexpr Vec3 operator-() const { return {-x, -y, -z}; }
  constexpr Vec3 operator*(double s) const { return {x * s, y * s, z * s}; }
  constexpr Vec3 operator/(double s) const { return {x / s, y / s, z / s}; }
  constexpr Vec3 operator*(const Vec3& o) const { return {x * o.x, y * o.y, z * o.z}; }
  Vec3& operator+=(const Vec3& o) { return *this = *this + o; }
  constexpr bool operator==(const Vec3&) const = default;
};

constexpr Vec3 operator*(double s, const Vec3& v) {
  return v * s;
}
constexpr double dot(const Vec3& a, const Vec3& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
constexpr Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double length(const Vec3& v) {
  return std::sqrt(dot(v, v));
}
inline Vec3 normalize(const Vec3& v) {
  double l = length(v);
  return l > 0 ? v / l : v;
}
inline Vec3 vmin(const Vec3& a, const Vec3& b) {
  return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)};
}
inline Vec3 vmax(const Vec3& a, const Vec3& b) {
  return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)};
}

// Axis-aligned box; empty until a point is added.
struct Aabb {
  Vec3 lo{1e300, 1e300, 1e300};
  Vec3 hi{-1e300, -1e300, -1e300};

  void add(const Vec3& p) {
    lo = vmin(lo, p);
    hi = vmax(hi, p);
  }
  bool empty() const { return lo.x > hi.x; }
  Vec3 size() const { return hi - lo; }
  Vec3 center() const { return (lo + hi) * 0.5; }
};

// Column-major 4x4 matrix in float, the layout OpenGL uniforms take.
struct Mat4 {
  std::array<float, 16> m{};

  static Mat4 identity() {
    Mat4 r;
    r.m[0] = r.m[5] = r.m[10] = r.m[15] = 1.0f;
    return r;
  }
  float& at(int row, int col) { return m[col * 4 + row]; }
  float at(int row, int col) const { return m[col * 4 + row]; }
  Mat4 operator*(const Mat4& o) const {
    Mat4 r;
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) {
        float s = 0;
        for (int k = 0; k < 4; ++k) s += at(i, k) * o.at(k, j);
        r.at(i, j) = s;
      }
    return r;
  }
};

// Right-handed view matrix (camera looks down -z in view space).
Mat4 look_at(const Vec3& eye, const Vec3& target, const Vec3& up);
// OpenGL clip-space perspective projection; fov_y in radians.
Mat4 perspective(double fov_y, double aspect, double z_near, double z_far);
// OpenGL clip-space orthographic projection of the box [-h, h]^2 x [near, far] in view space.
Mat4 orthographic(double half_extent, double z_near, double z_far);

}  // namespace scatter
