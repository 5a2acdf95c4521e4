#include "core/vec.hpp"

namespace scatter {

Mat4 look_at(const Vec3& eye, const Vec3& target, const Vec3& up) {
  Vec3 f = normalize(target - eye);
  Vec3 s = normalize(cross(f, up));
  Vec3 u = cross(s, f);
  Mat4 r = Mat4::identity();
  for (int c = 0; c < 3; ++c) {
    r.at(0, c) = static_cast<float>(s[c]);
    r.at(1, c) = static_cast<float>(u[c]);
    r.at(2, c) = static_cast<float>(-f[c]);
  }
  r.at(0, 3) = static_cast<float>(-dot(s, eye));
  r.at(1, 3) = static_cast<float>(-dot(u, eye));
  r.at(2, 3) = static_cast<float>(dot(f, eye));
  return r;
}

Mat4 perspective(double fov_y, double aspect, double z_near, double z_far) {
  double t = 1.0 / std::tan(fov_y / 2);
  Mat4 r;
  r.at(0, 0) = static_cast<float>(t / aspect);
  r.at(1, 1) = static_cast<float>(t);
  r.at(2, 2) = static_cast<float>((z_far + z_near) / (z_near - z_far));
  r.at(2, 3) = static_cast<float>(2 * z_far * z_near / (z_near - z_far));
  r.at(3, 2) = -1.0f;
  return r;
}

Mat4 orthographic(double h, double z_near, double z_far) {
  Mat4 r = Mat4::identity();
  r.at(0, 0) = static_cast<float>(1 / h);
  r.at(1, 1) = static_cast<float>(1 / h);
  r.at(2, 2) = static_cast<float>(-2 / (z_far - z_near));
  r.at(2, 3) = static_cast<float>(-(z_far + z_near) / (z_far - z_near));
  return r;
}

}  // namespace scatter
