#include "pipelines/psf/beam.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <thread>

#include "core/errors.hpp"
#include "pipelines/psf/psf_model.hpp"

namespace scatter::psf {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kTransverseBins = 1000;

struct Tally {
  std::vector<double> hist;  // bins x kTransverseBins
  double half_width = 0;     // transverse range [-half_width, half_width]
};

// Direction after scattering by Henyey-Greenstein from `d` (unit).
void hg_scatter(double g, std::mt19937_64& rng, double d[3]) {
  std::uniform_real_distribution<double> u(0, 1);
  double xi = u(rng), cos_t;
  if (std::abs(g) < 1e-3)
    cos_t = 1 - 2 * xi;
  else {
    double s = (1 - g * g) / (1 - g + 2 * g * xi);
    cos_t = (1 + g * g - s * s) / (2 * g);
  }
  cos_t = std::clamp(cos_t, -1.0, 1.0);
  double sin_t = std::sqrt(1 - cos_t * cos_t), phi = 2 * kPi * u(rng);
  // An orthonormal basis around d.
  double t[3] = {std::abs(d[0]) < 0.9 ? 1.0 : 0.0, std::abs(d[0]) < 0.9 ? 0.0 : 1.0, 0.0};
  double uu[3] = {d[1] * t[2] - d[2] * t[1], d[2] * t[0] - d[0] * t[2], d[0] * t[1] - d[1] * t[0]};
  double n = std::sqrt(uu[0] * uu[0] + uu[1] * uu[1] + uu[2] * uu[2]);
  for (double& x : uu) x /= n;
  double v[3] = {d[1] * uu[2] - d[2] * uu[1], d[2] * uu[0] - d[0] * uu[2],
                 d[0] * uu[1] - d[1] * uu[0]};
  for (int i = 0; i < 3; ++i)
    d[i] = cos_t * d[i] + sin_t * (std::cos(phi) * uu[i] + std::sin(phi) * v[i]);
}

void trace(const BeamParams& p, long long photons, uint64_t seed, Tally& t) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  const double c = p.a + p.b, albedo = p.b / c, cos_cone = std::cos(p.cone);
  const double bin = p.length / p.bins, tb = 2 * t.half_width / kTransverseBins;
  for (long long i = 0; i < photons; ++i) {
    double x[3] = {0, 0, 0}, d[3] = {1, 0, 0}, w = 1;
    for (int events = 0; events < 100000; ++events) {
      double s = -std::log(1 - u(rng)) / c;
      for (int k = 0; k < 3; ++k) x[k] += s * d[k];
      if (x[0] >= p.length || x[0] < -p.length) break;
      if (x[0] >= 0 && d[0] >= cos_cone) {
        int bx = static_cast<int>(x[0] / bin);
        for (int axis : {1, 2}) {
          int by = static_cast<int>((x[axis] + t.half_width) / tb);
          if (by >= 0 && by < kTransverseBins) t.hist[size_t(bx) * kTransverseBins + by] += w;
        }
      }
      w *= albedo;  // survival biasing; Russian roulette below
      if (w < 1e-3) {
        if (u(rng) > 0.1) break;
        w *= 10;
      }
      hg_scatter(p.g, rng, d);
    }
  }
}

// FWHM of a sampled profile (linear interpolation at half the maximum); 0 if it is not resolved.
double fwhm(const double* h, int n, double dx) {
  int peak = static_cast<int>(std::max_element(h, h + n) - h);
  double half = h[peak] / 2;
  if (!(half > 0)) return 0;
  int l = peak, r = peak;
  while (l > 0 && h[l] > half) --l;
  while (r < n - 1 && h[r] > half) ++r;
  if (l == 0 || r == n - 1) return 0;
  double xl = l + (half - h[l]) / (h[l + 1] - h[l]);
  double xr = r - 1 + (h[r - 1] - half) / (h[r - 1] - h[r]);
  return (xr - xl) * dx;
}

}  // namespace

std::vector<BeamRow> beam_spread(const BeamParams& p) {
  if (!(p.b > 0 && p.b <= 1e3)) throw ValidationError("--b", "must be in (0, 1000]");
  if (!(p.a >= 0 && p.a <= 1e3)) throw ValidationError("--a", "must be in [0, 1000]");
  if (!(p.g > -1 && p.g < 1)) throw ValidationError("--g", "must be in (-1, 1)");
  if (!(p.length > 0 && p.length <= 1e6)) throw ValidationError("--length", "must be in (0, 1e6]");
  if (p.bins < 1 || p.bins > 1000) throw ValidationError("--bins", "must be in [1, 1000]");
  if (!(p.cone > 0 && p.cone <= kPi)) throw ValidationError("--cone", "must be in (0, pi]");
  if (p.photons < 1 || p.photons > 10'000'000'000LL)
    throw ValidationError("--photons", "must be in [1, 1e10]");
  const int threads = p.threads > 0 ? p.threads : std::max(1u, std::thread::hardware_concurrency());
  // Transverse range: a few model widths at the far end (no shift), at least a few mean free paths.
  const double theta2 = mean_square_angle(p.g);
  double wmax = std::sqrt(blur_width2(theta2, p.b * p.length, p.length, p.a / p.b, 0.0));
  const double half_width = std::max(4 * wmax, 5 / (p.a + p.b));
  std::vector<Tally> tallies(
      threads, Tally{std::vector<double>(size_t(p.bins) * kTransverseBins, 0.0), half_width});
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t) {
    long long share = p.photons / threads + (t < p.photons % threads ? 1 : 0);
    pool.emplace_back(trace, std::cref(p), share, uint64_t(p.seed) * 7919 + t,
                      std::ref(tallies[t]));
  }
  for (auto& th : pool) th.join();
  std::vector<BeamRow> rows;
  const double bin = p.length / p.bins, k = 2 * std::sqrt(2 * std::log(2.0));
  for (int bx = 0; bx < p.bins; ++bx) {
    std::vector<double> h(kTransverseBins, 0.0);
    for (const auto& t : tallies)
      for (int i = 0; i < kTransverseBins; ++i) h[i] += t.hist[size_t(bx) * kTransverseBins + i];
    BeamRow r;
    r.distance = (bx + 0.5) * bin;
    for (double v : h) r.events += v;
    // A moving average over 9 bins keeps a noise spike from being taken for the maximum.
    std::vector<double> smooth(kTransverseBins, 0.0);
    for (int i = 0; i < kTransverseBins; ++i) {
      int lo = std::max(0, i - 4), hi = std::min(kTransverseBins - 1, i + 4);
      for (int j = lo; j <= hi; ++j) smooth[i] += h[j] / (hi - lo + 1);
    }
    r.fwhm_mc = fwhm(smooth.data(), kTransverseBins, 2 * half_width / kTransverseBins);
    r.fwhm_model = k * std::sqrt(blur_width2(theta2, p.b * r.distance, r.distance, p.a / p.b, 8.0));
    r.fwhm_model_noshift =
        k * std::sqrt(blur_width2(theta2, p.b * r.distance, r.distance, p.a / p.b, 0.0));
    rows.push_back(r);
  }
  return rows;
}

void to_json(nlohmann::json& j, const BeamRow& r) {
  j = {{"distance", r.distance},
       {"events", r.events},
       {"fwhm_mc", r.fwhm_mc},
       {"fwhm_model", r.fwhm_model},
       {"fwhm_model_noshift", r.fwhm_model_noshift}};
}

}  // namespace scatter::psf
