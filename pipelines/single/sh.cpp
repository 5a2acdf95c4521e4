#include "pipelines/single/sh.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace scatter {

void sh_basis(const Vec3& d, int bands, float* out) {
  if (bands < 1 || bands > kMaxShBands)
    throw std::invalid_argument("sh_basis: bands must be in [1, 8]");
  // Real SH without the Condon-Shortley phase: Y_l^0 = K P_l(z); for m > 0 sqrt(2) K P~_l^m(z)
  // Re((x+iy)^m), for m < 0 the same with Im; P~_l^m = P_l^m / sin^m(theta), a polynomial in z by
  // the usual recurrences; index l^2 + l + m. Equal to the textbook constants (0.2821, 0.4886 y,
  // ...).
  const double x = d.x, y = d.y, z = d.z;
  double c[kMaxShBands], sn[kMaxShBands];  // Re and Im of (x + iy)^m
  c[0] = 1;
  sn[0] = 0;
  for (int m = 1; m < bands; ++m) {
    c[m] = c[m - 1] * x - sn[m - 1] * y;
    sn[m] = c[m - 1] * y + sn[m - 1] * x;
  }
  double pmm = 1;  // P~_m^m = (2m - 1)!!
  for (int m = 0; m < bands; ++m) {
    if (m > 0) pmm *= 2 * m - 1;
    double p_prev = 0, p = pmm;  // P~_{l-1}^m, P~_l^m at l = m
    for (int l = m; l < bands; ++l) {
      if (l == m + 1) {
        p_prev = p;
        p = z * (2 * m + 1) * pmm;
      } else if (l > m + 1) {
        double next = ((2 * l - 1) * z * p - (l + m - 1) * p_prev) / (l - m);
        p_prev = p;
        p = next;
      }
      double ratio = 1;  // (l - m)! / (l + m)!
      for (int k = l - m + 1; k <= l + m; ++k) ratio /= k;
      const double k_lm = std::sqrt((2 * l + 1) / (4 * std::numbers::pi) * ratio);
      if (m == 0) {
        out[l * l + l] = static_cast<float>(k_lm * p);
      } else {
        out[l * l + l + m] = static_cast<float>(std::sqrt(2.0) * k_lm * p * c[m]);
        out[l * l + l - m] = static_cast<float>(std::sqrt(2.0) * k_lm * p * sn[m]);
      }
    }
  }
}

float sh_eval(const float* c, const Vec3& d, int bands) {
  float y[kMaxShBands * kMaxShBands];
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

std::vector<float> sh_project(const std::vector<Vec3>& dirs, const std::vector<float>& f,
                              int bands) {
  if (f.size() != dirs.size()) throw std::invalid_argument("sh_project: one value per direction");
  const int n = sh_count(bands);
  std::vector<double> acc(n, 0.0);
  float y[kMaxShBands * kMaxShBands];
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
