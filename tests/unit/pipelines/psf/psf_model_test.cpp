// The PSF model's formulas against the paper's limiting cases and independent quadratures, and the
// light pyramid (kernels/psf/pyramid.cl) against a CPU computation of the same operations and
// against a direct 3D Gaussian convolution (the orders' kernels: orders_test.cpp).
#include "pipelines/psf/psf_model.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

#include "../../test_util.hpp"
#include "pipelines/common/cl_scene.hpp"
#include "pipelines/psf/light_pyramid.hpp"
#include "pipelines/psf/orders.hpp"
#include "psf_volumes.hpp"
#include "scene/scene.hpp"

namespace scatter::psf {
namespace {

using test_volumes::random_volume;
using test_volumes::upload4;

constexpr double kPi = std::numbers::pi;

TEST(PsfModel, MeanSquareAngleOfHenyeyGreenstein) {
  EXPECT_NEAR(mean_square_angle(0.0), (kPi * kPi - 4) / 2, 1e-6);  // isotropic, in closed form
  // The paper's figure 4 gives <theta^2> = 0.24 for g = 0.9.
  EXPECT_NEAR(mean_square_angle(0.9), 0.24, 0.01);
  EXPECT_NEAR(curvature_alpha(0.0), 0.25, 1e-12);
  EXPECT_NEAR(curvature_alpha(0.75), 1.0, 1e-12);
}

// Equation 1 exactly as printed (with alpha = 1 / (2 <theta^2>)), times the 2/3 correction.
double equation1(double theta2, double a, double b, double S) {
  double alpha = 1 / (2 * theta2);
  return (2.0 / 3.0) * 0.5 / (2 * a / (3 * S) + 16 * alpha / (b * S * S * S));
}

TEST(PsfModel, WidthIsEquationOneCorrectedAndReparameterised) {
  for (double a : {0.001, 0.05, 0.5})
    for (double b : {0.3, 2.0, 10.0})
      for (double S : {0.1, 1.0, 7.0})
        EXPECT_NEAR(blur_width2(0.7, b * S, S, a / b, 0.0), equation1(0.7, a, b, S),
                    1e-9 * equation1(0.7, a, b, S))
            << a << " " << b << " " << S;
}

TEST(PsfModel, WidthLimitingCases) {
  const double theta2 = 0.24, b = 2.0;
  // No absorption: w^2 = b <theta^2> S^3 / 24 (Tessendorf's), growing as S^3.
  for (double S : {0.5, 2.0, 40.0})
    EXPECT_NEAR(blur_width2(theta2, b * S, S, 0.0, 0.0), b * theta2 * S * S * S / 24,
                1e-12 * S * S * S);
  EXPECT_NEAR(blur_width2(theta2, b * 4, 4, 0, 0) / blur_width2(theta2, b * 2, 2, 0, 0), 8.0, 1e-9);
  // Long paths (S >> l, l^2 = 1 / (a b <theta^2>)): w^2 -> b <theta^2> S l^2 / 2 = S / (2a), linear
  // in S.
  const double a = 0.01, l = 1 / std::sqrt(a * b * theta2);
  for (double S : {1e4 * l, 1e5 * l}) {  // the ratio is 1 - 12 l^2 / S^2 + ...
    double w2 = blur_width2(theta2, b * S, S, a / b, 0.0);
    EXPECT_NEAR(w2 / (b * theta2 * S * l * l / 2), 1.0, 1e-6);
  }
  double S = 1e4 * l;
  EXPECT_NEAR(
      blur_width2(theta2, b * 2 * S, 2 * S, a / b, 0) / blur_width2(theta2, b * S, S, a / b, 0),
      2.0, 1e-3);
  // The 8/b shift: no blur before 8 scattering events, then the formula at S - 8/b.
  EXPECT_EQ(blur_width2(theta2, 7.9, 7.9 / b, 0, 8), 0.0);
  EXPECT_NEAR(blur_width2(theta2, b * 10, 10, 0, 8),
              blur_width2(theta2, b * 10 - 8, 10 - 8 / b, 0, 0), 1e-12);
}

TEST(PsfModel, MultipleScatteringPhaseFunctionIntegratesToOne) {
  for (double g : {0.0, 0.5, 0.9}) {
    PmsTable t = pms_table(g);
    for (double ell : {0.002, 0.3, 1.0, 4.5, 37.0, 900.0}) {
      // Independent quadrature of P_MS over the sphere (midpoint rule in theta, fine).
      const int n = 20000;
      double sum = 0;
      for (int i = 0; i < n; ++i) {
        double th = (i + 0.5) * kPi / n;
        sum += pms(t, ell, th) * std::sin(th) * (kPi / n);
      }
      EXPECT_NEAR(2 * kPi * sum, 1.0, 2e-3) << "g " << g << " l " << ell;
    }
    // Few scattering events: P_MS is the phase function itself.
    double hg = (1 - g * g) / (4 * kPi * std::pow(1 + g * g - 2 * g * std::cos(0.4), 1.5));
    EXPECT_NEAR(pms(t, 1e-3, 0.4), hg, 2e-3 * hg);
  }
  // Many events widen the lobe: less forward, more backward.
  PmsTable t = pms_table(0.9);
  EXPECT_LT(pms(t, 50, 0), pms(t, 0.01, 0));
  EXPECT_GT(pms(t, 50, kPi / 2), pms(t, 0.01, kPi / 2));
}

TEST(PsfModel, OrderFlightsAddUpToTheWalksMeanSquare) {
  // The flights' variances (3 axes) plus the squared total drift are the walk's E|R_m|^2, and
  // that grows as 2 m / (1 - g) (diffusion with the reduced coefficient) once m >> 1 / (1 - g).
  for (double g : {0.0, 0.3, 0.7, 0.9, -0.4}) {
    double var = 0, drift = 0;
    for (int m = 1; m <= 400; ++m) {
      OrderFlight f = order_flight(g, m);
      ASSERT_GE(f.variance, 0) << g << " " << m;
      EXPECT_NEAR(f.drift, std::pow(g, m), 1e-12);
      var += 3 * f.variance;
      drift += f.drift;
      EXPECT_NEAR(var + drift * drift, walk_mean_square(g, m), 1e-9 * walk_mean_square(g, m))
          << "g " << g << " m " << m;
    }
    // The exact sum: 2 m / (1 - g) - 2 g (1 - g^m) / (1 - g)^2.
    EXPECT_NEAR(walk_mean_square(g, 400),
                800 / (1 - g) - 2 * g * (1 - std::pow(g, 400)) / std::pow(1 - g, 2),
                1e-6 * walk_mean_square(g, 400));
  }
  EXPECT_NEAR(walk_mean_square(0.0, 5), 10.0, 1e-12);  // independent flights: 2 per flight
}

TEST(PsfModel, WalkMeanSquareMatchesAMonteCarloWalk) {
  // Flights of exponential length (mean 1) whose directions follow HG(g) from the previous one,
  // the first from the light's (+z): E|R_m|^2 and the mean displacement along z, against the
  // closed forms, at 200 000 walks (standard errors below 0.5 %).
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0, 1);
  std::exponential_distribution<double> flight(1.0);
  for (double g : {0.0, 0.8}) {
    const int walks = 200000, m = 6;
    double sum_r2 = 0, sum_z = 0;
    for (int w = 0; w < walks; ++w) {
      double d[3] = {0, 0, 1}, r[3] = {0, 0, 0};
      for (int k = 0; k < m; ++k) {
        // HG sample about d.
        double x = 2 * u(rng) - 1, ct = x;
        if (g != 0) {
          double t = (1 - g * g) / (1 + g * x);
          ct = (1 + g * g - t * t) / (2 * g);
        }
        double st = std::sqrt(std::max(0.0, 1 - ct * ct)), ph = 2 * kPi * u(rng);
        double a[3] = {std::fabs(d[0]) < 0.9 ? 1.0 : 0.0, std::fabs(d[0]) < 0.9 ? 0.0 : 1.0, 0};
        double e1[3] = {a[1] * d[2] - a[2] * d[1], a[2] * d[0] - a[0] * d[2],
                        a[0] * d[1] - a[1] * d[0]};
        double n1 = std::sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
        for (double& v : e1) v /= n1;
        double e2[3] = {d[1] * e1[2] - d[2] * e1[1], d[2] * e1[0] - d[0] * e1[2],
                        d[0] * e1[1] - d[1] * e1[0]};
        double nd[3];
        for (int i = 0; i < 3; ++i)
          nd[i] = ct * d[i] + st * (std::cos(ph) * e1[i] + std::sin(ph) * e2[i]);
        double len = flight(rng);
        for (int i = 0; i < 3; ++i) d[i] = nd[i], r[i] += len * nd[i];
      }
      sum_r2 += r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
      sum_z += r[2];
    }
    double drift = 0;
    for (int k = 1; k <= m; ++k) drift += order_flight(g, k).drift;
    EXPECT_NEAR(sum_r2 / walks, walk_mean_square(g, m), 0.02 * walk_mean_square(g, m)) << g;
    EXPECT_NEAR(sum_z / walks, drift, 0.02 + 0.01 * drift) << g;
  }
}

TEST(PsfOrders, FlightMixtureFollowsTheExponentialFlight) {
  // The radial CDF of isotropic 3D Gaussians (per-axis sigma) against 1 - e^-r, and E r^2 = 2.
  auto maxwell_cdf = [](double r, double s) {
    double x = r / s;
    return std::erf(x / std::sqrt(2.0)) - std::sqrt(2 / kPi) * x * std::exp(-x * x / 2);
  };
  for (int flights : {1, 3}) {
    double worst = 0, weight = 0, r2 = 0;
    for (const FlightGaussian& f : flight_mixture(flights)) {
      weight += f.weight;
      r2 += f.weight * 3 * f.sigma * f.sigma;
    }
    for (double r = 0; r < 12; r += 0.01) {
      double cdf = 0;
      for (const FlightGaussian& f : flight_mixture(flights))
        cdf += f.weight * maxwell_cdf(r, f.sigma);
      worst = std::max(worst, std::fabs(cdf - (1 - std::exp(-r))));
    }
    EXPECT_NEAR(weight, 1, 1e-3) << flights;
    EXPECT_NEAR(r2, 2, 1e-3) << flights;
    EXPECT_LT(worst, flights == 3 ? 0.054 : 0.37) << flights;
    EXPECT_GT(worst, flights == 3 ? 0.05 : 0.36) << flights;  // what the header says
  }
}

TEST(PsfModel, LevelWidthsAddUp) {
  // Level k's Gaussian widths compose: stored_k^2 = stored_{k-1}^2 + tent variance + (sigma_k
  // voxel_k)^2, and the trilinear reconstruction's 1/6 voxel^2 brings it to level_width(k).
  for (int k = 1; k < 8; ++k) {
    double fine = std::ldexp(1.0, k - 1), coarse = 2 * fine, s = level_sigma(k) * coarse;
    double w0 = stored_width(k - 1);
    EXPECT_NEAR(w0 * w0 + 0.75 * fine * fine + s * s + coarse * coarse / 6,
                std::pow(level_width(k), 2), 1e-9);
    EXPECT_GT(level_width(k), level_width(k - 1));
  }
}

Volume3 level_of(gpu::ClContext& cl, const Pyramid& p, size_t k) {
  const cl_int4& L = p.layout[k];
  Volume3 v{L.s[1], L.s[2], L.s[3], {}};
  std::vector<cl_float4> d(size_t(v.nx) * v.ny * v.nz);
  cl.queue().enqueueReadBuffer(p.data, CL_TRUE, size_t(L.s[0]) * sizeof(cl_float4),
                               d.size() * sizeof(cl_float4), d.data());
  for (const auto& x : d) v.rgb.insert(v.rgb.end(), {x.s[0], x.s[1], x.s[2]});
  return v;
}

TEST(PsfPyramid, KernelsMatchTheCpuOperations) {
  auto& cl = test::shared_gpu().cl();
  Volume3 src = random_volume(19, 12, 16, 7);  // odd and even sides
  Pyramid p = build_pyramid(cl, upload4(cl, src), src.nx, src.ny, src.nz, 0.1f);
  ASSERT_EQ(p.layout.size(), 5u);  // 19 -> 10 -> 5 -> 3 -> 2
  Volume3 cpu = src;
  for (size_t k = 0; k < p.layout.size(); ++k) {
    if (k > 0) cpu = blur_gaussian(downsample_tent(cpu), level_sigma(static_cast<int>(k)));
    Volume3 gpu = level_of(cl, p, k);
    ASSERT_EQ(gpu.rgb.size(), cpu.rgb.size());
    for (size_t i = 0; i < cpu.rgb.size(); ++i)
      ASSERT_NEAR(gpu.rgb[i], cpu.rgb[i], 1e-5) << "level " << k;
    EXPECT_NEAR(p.width[k], 0.1 * level_width(static_cast<int>(k)), 1e-6);
  }
}

// Trilinear reconstruction of level k at the source's voxel centres (as kernels/psf/march.cl).
double reconstruct(const Volume3& lv, int k, int i, int j, int l, int c) {
  double cell = std::ldexp(1.0, k);
  double q[3] = {(i + 0.5) / cell - 0.5, (j + 0.5) / cell - 0.5, (l + 0.5) / cell - 0.5};
  int n[3] = {lv.nx, lv.ny, lv.nz};
  double sum = 0;
  for (int corner = 0; corner < 8; ++corner) {
    double w = 1;
    int idx[3];
    for (int a = 0; a < 3; ++a) {
      int base = static_cast<int>(std::floor(q[a]));
      double f = q[a] - base;
      int bit = (corner >> a) & 1;
      idx[a] = std::clamp(base + bit, 0, n[a] - 1);
      w *= bit ? f : 1 - f;
    }
    sum += w * lv.rgb[3 * lv.index(idx[0], idx[1], idx[2]) + c];
  }
  return sum;
}

TEST(PsfPyramid, LevelsApproximateADirectGaussianConvolution) {
  auto& cl = test::shared_gpu().cl();
  // A smooth-ish source (a blob and a plateau) away from the grid's faces.
  const int n = 48;
  Volume3 src{n, n, n, {}};
  src.rgb.assign(size_t(n) * n * n * 3, 0.f);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        double r2 = std::pow(i - 20.0, 2) + std::pow(j - 24.0, 2) + std::pow(k - 26.0, 2);
        float v = static_cast<float>(
            std::exp(-r2 / 18.0) +
            ((i > 26 && i < 34 && j > 14 && j < 34 && k > 16 && k < 32) ? 0.5 : 0));
        for (int c = 0; c < 3; ++c) src.rgb[3 * src.index(i, j, k) + c] = v * (1 + c);
      }
  Pyramid p = build_pyramid(cl, upload4(cl, src), n, n, n, 1.0f);
  for (int k = 1; k <= 3; ++k) {
    Volume3 direct = blur_gaussian(src, level_width(k));
    Volume3 lv = level_of(cl, p, k);
    double err = 0, ref = 0;
    for (int l = 8; l < n - 8; ++l)
      for (int j = 8; j < n - 8; ++j)
        for (int i = 8; i < n - 8; ++i)
          for (int c = 0; c < 3; ++c) {
            double d = direct.rgb[3 * direct.index(i, j, l) + c];
            err += std::pow(reconstruct(lv, k, i, j, l, c) - d, 2);
            ref += d * d;
          }
    double rel = std::sqrt(err / ref);
    // What is left: the trilinear weights at these particular positions differ from their mean
    // (kReconstruction), and the tent is not a Gaussian. Measured 1.3, 2.9, 4.7 % for levels 1-3.
    std::printf("level %d: relative RMSE %.4f\n", k, rel);
    EXPECT_LT(rel, 0.06) << "level " << k;
    RecordProperty("level" + std::to_string(k) + "_rel_rmse", std::to_string(rel));
  }
}

}  // namespace
}  // namespace scatter::psf
