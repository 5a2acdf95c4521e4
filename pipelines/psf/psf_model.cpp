#include "pipelines/psf/psf_model.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace scatter::psf {
namespace {

constexpr double kPi = 3.14159265358979323846;

double hg(double cos_theta, double g) {
  double d = 1 + g * g - 2 * g * cos_theta;
  return (1 - g * g) / (4 * kPi * d * std::sqrt(d));
}

// Simpson's rule of f over [0, pi] with an even number of steps.
template <class F>
double simpson_0_pi(F f, int steps) {
  steps += steps % 2;
  double h = kPi / steps, sum = f(0.0) + f(kPi);
  for (int i = 1; i < steps; ++i) sum += (i % 2 ? 4 : 2) * f(i * h);
  return sum * h / 3;
}

}  // namespace

double mean_square_angle(double g) {
  return 2 * kPi *
         simpson_0_pi([&](double t) { return t * t * hg(std::cos(t), g) * std::sin(t); }, 20000);
}

double curvature_alpha(double g) {
  return 1.0 / (4.0 * (1.0 - g));
}

double blur_width2(double theta2, double ell, double S, double a_over_b, double shift) {
  if (ell <= shift || S <= 0) return 0.0;
  double l = ell - shift;
  double s = S * l / ell;
  return theta2 * l * s * s / (24.0 * (1.0 + theta2 * a_over_b * l * l / 12.0));
}

double pms_stretch(double ell) {
  if (ell < 1e-6) return 1.0;  // l / (1 - e^-l) -> 1 + l/2
  return std::sqrt(ell / -std::expm1(-ell));
}

double pms_norm(double g, double ell, int steps) {
  double k = pms_stretch(ell);
  return 2 * kPi *
         simpson_0_pi([&](double t) { return hg(std::cos(t / k), g) * std::sin(t); }, steps);
}

PmsTable pms_table(double g, int entries, double ell_min, double ell_max) {
  if (entries < 2 || !(ell_min > 0) || !(ell_max > ell_min))
    throw std::invalid_argument("pms_table range");
  PmsTable t;
  t.g = g;
  t.log_min = std::log(ell_min);
  t.log_max = std::log(ell_max);
  t.inv_norm.resize(entries);
  for (int i = 0; i < entries; ++i) {
    double ell = std::exp(t.log_min + (t.log_max - t.log_min) * i / (entries - 1));
    t.inv_norm[i] = static_cast<float>(1.0 / pms_norm(g, ell, 2048));
  }
  return t;
}

double PmsTable::inv_norm_at(double ell) const {
  int n = static_cast<int>(inv_norm.size());
  double x = (std::log(std::max(ell, 1e-30)) - log_min) / (log_max - log_min) * (n - 1);
  x = std::clamp(x, 0.0, double(n - 1));
  int i = std::min(static_cast<int>(x), n - 2);
  double f = x - i;
  return inv_norm[i] * (1 - f) + inv_norm[i + 1] * f;
}

double pms(const PmsTable& table, double ell, double theta) {
  return hg(std::cos(theta / pms_stretch(ell)), table.g) * table.inv_norm_at(ell);
}

double level_width(int level) {
  return level <= 0 ? 0.0 : kLevelWidth * std::ldexp(1.0, level);
}

double stored_width(int level) {
  if (level <= 0) return 0.0;
  double w = level_width(level), v = std::ldexp(1.0, level);
  return std::sqrt(w * w - kReconstruction * v * v);
}

double level_sigma(int level) {
  if (level <= 0) return 0.0;
  double fine = std::ldexp(1.0, level - 1), coarse = 2 * fine;  // voxel sizes in source voxels
  double w1 = stored_width(level), w0 = stored_width(level - 1);
  double var = w1 * w1 - w0 * w0 - 0.75 * fine * fine;
  if (var <= 0) throw std::logic_error("psf pyramid widths do not grow");
  return std::sqrt(var) / coarse;
}

std::vector<float> gaussian_taps(double sigma) {
  int r = std::max(1, static_cast<int>(std::ceil(3 * sigma)));
  std::vector<float> t(r + 1);
  double sum = 0;
  for (int i = 0; i <= r; ++i) {
    t[i] = static_cast<float>(std::exp(-0.5 * i * i / (sigma * sigma)));
    sum += (i == 0 ? 1 : 2) * t[i];
  }
  for (float& v : t) v = static_cast<float>(v / sum);
  return t;
}

Volume3 downsample_tent(const Volume3& v) {
  Volume3 out{(v.nx + 1) / 2, (v.ny + 1) / 2, (v.nz + 1) / 2, {}};
  out.rgb.assign(out.index(0, 0, out.nz) * 3, 0.f);
  const float w[4] = {1 / 8.f, 3 / 8.f, 3 / 8.f, 1 / 8.f};
  for (int k = 0; k < out.nz; ++k)
    for (int j = 0; j < out.ny; ++j)
      for (int i = 0; i < out.nx; ++i)
        for (int c = 0; c < 3; ++c) {
          double sum = 0;
          for (int dk = 0; dk < 4; ++dk)
            for (int dj = 0; dj < 4; ++dj)
              for (int di = 0; di < 4; ++di) {
                int x = 2 * i - 1 + di, y = 2 * j - 1 + dj, z = 2 * k - 1 + dk;
                if (x < 0 || y < 0 || z < 0 || x >= v.nx || y >= v.ny || z >= v.nz) continue;
                sum += double(w[di]) * w[dj] * w[dk] * v.rgb[3 * v.index(x, y, z) + c];
              }
          out.rgb[3 * out.index(i, j, k) + c] = static_cast<float>(sum);
        }
  return out;
}

Volume3 blur_gaussian(const Volume3& v, double sigma) {
  std::vector<float> taps = gaussian_taps(sigma);
  const int r = static_cast<int>(taps.size()) - 1;
  Volume3 cur = v;
  for (int axis = 0; axis < 3; ++axis) {
    Volume3 next = cur;
    const int n[3] = {cur.nx, cur.ny, cur.nz};
    for (int k = 0; k < cur.nz; ++k)
      for (int j = 0; j < cur.ny; ++j)
        for (int i = 0; i < cur.nx; ++i)
          for (int c = 0; c < 3; ++c) {
            double sum = 0;
            for (int d = -r; d <= r; ++d) {
              int p[3] = {i, j, k};
              p[axis] += d;
              if (p[axis] < 0 || p[axis] >= n[axis]) continue;
              sum += double(taps[std::abs(d)]) * cur.rgb[3 * cur.index(p[0], p[1], p[2]) + c];
            }
            next.rgb[3 * next.index(i, j, k) + c] = static_cast<float>(sum);
          }
    cur = std::move(next);
  }
  return cur;
}

OrderFlight order_flight(double g, int m) {
  if (m < 1) throw std::invalid_argument("order_flight: m >= 1");
  // E|R_m|^2 - E|R_(m-1)|^2 - (|mu_m|^2 - |mu_(m-1)|^2) with mu_m = sum_{k=1}^m g^k:
  //   2 + 2 S - 2 S g^m - g^(2m), S = sum_{k=1}^{m-1} g^k.
  double gm = std::pow(g, m), s = 0;
  for (int k = 1; k < m; ++k) s += std::pow(g, k);
  return {gm, (2 + 2 * s * (1 - gm) - gm * gm) / 3};
}

double walk_mean_square(double g, int m) {
  double sum = 2.0 * m;
  for (int k = 1; k < m; ++k) sum += 2.0 * (m - k) * std::pow(g, k);
  return sum;
}

}  // namespace scatter::psf
