#include "pipelines/single/sh.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace scatter {

void sh_basis(const Vec3& d, int bands, float* out) {
  if (bands < 1 || bands > kMaxShBands) throw std::invalid_argument("sh_basis: bands must be in [1, 5]");
  const double x = d.x, y = d.y, z = d.z;
  const double x2 = x * x, y2 = y * y, z2 = z * z;
  double v[25];
  v[0] = 0.282094791773878;
  v[1] = 0.488602511902920 * y;
  v[2] = 0.488602511902920 * z;
  v[3] = 0.488602511902920 * x;
  v[4] = 1.092548430592079 * x * y;
  v[5] = 1.092548430592079 * y * z;
  v[6] = 0.315391565252520 * (3 * z2 - 1);
  v[7] = 1.092548430592079 * x * z;
  v[8] = 0.546274215296040 * (x2 - y2);
  v[9] = 0.590043589926644 * y * (3 * x2 - y2);
  v[10] = 2.890611442640554 * x * y * z;
  v[11] = 0.457045799464466 * y * (5 * z2 - 1);
  v[12] = 0.373176332590115 * z * (5 * z2 - 3);
  v[13] = 0.457045799464466 * x * (5 * z2 - 1);
  v[14] = 1.445305721320277 * z * (x2 - y2);
  v[15] = 0.590043589926644 * x * (x2 - 3 * y2);
  v[16] = 2.503342941796705 * x * y * (x2 - y2);
  v[17] = 1.770130769779931 * y * z * (3 * x2 - y2);
  v[18] = 0.946174695757560 * x * y * (7 * z2 - 1);
  v[19] = 0.669046543557289 * y * z * (7 * z2 - 3);
  v[20] = 0.105785546915204 * (35 * z2 * z2 - 30 * z2 + 3);
  v[21] = 0.669046543557289 * x * z * (7 * z2 - 3);
  v[22] = 0.473087347878780 * (x2 - y2) * (7 * z2 - 1);
  v[23] = 1.770130769779931 * x * z * (x2 - 3 * y2);
  v[24] = 0.625835735449176 * (x2 * (x2 - 3 * y2) - y2 * (3 * x2 - y2));
  for (int i = 0; i < bands * bands; ++i) out[i] = static_cast<float>(v[i]);
}

float sh_eval(const float* c, const Vec3& d, int bands) {
  float y[25];
  sh_basis(d, bands, y);
  double s = 0;
  for (int i = 0; i < bands * bands; ++i) s += double(c[i]) * y[i];
  return static_cast<float>(s);
}

std::vector<Vec3> sphere_directions(int n) {
  if (n < 1) throw std::invalid_argument("sphere_directions: n must be positive");
  std::vector<Vec3> dirs(n);
  const double golden = std::numbers::pi * (3 - std::sqrt(5.0));
  for (int k = 0; k < n; ++k) {
    double z = 1 - (2 * k + 1.0) / n;
    double r = std::sqrt(std::max(0.0, 1 - z * z));
    double phi = golden * k;
    dirs[k] = {r * std::cos(phi), r * std::sin(phi), z};
  }
  return dirs;
}

std::vector<float> sh_project(const std::vector<Vec3>& dirs, const std::vector<float>& f, int bands) {
  if (f.size() != dirs.size()) throw std::invalid_argument("sh_project: one value per direction");
  const int n = sh_count(bands);
  std::vector<double> acc(n, 0.0);
  float y[25];
  for (size_t k = 0; k < dirs.size(); ++k) {
    sh_basis(dirs[k], bands, y);
    for (int i = 0; i < n; ++i) acc[i] += double(f[k]) * y[i];
  }
  std::vector<float> c(n);
  const double w = 4 * std::numbers::pi / double(dirs.size());
  for (int i = 0; i < n; ++i) c[i] = static_cast<float>(acc[i] * w);
  return c;
}

}  // namespace scatter
