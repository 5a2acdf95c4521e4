#include <gtest/gtest.h>

#include <cmath>

#include "../../test_util.hpp"
#include "pipelines/common/cl_scene.hpp"
#include "pipelines/lbl/light_rays.hpp"

namespace scatter::lbl {
namespace {

gpu::ClContext& cl() {
  return test::shared_gpu().cl();
}

// A 16^3 grid of voxels 0.1 wide whose inner 12^3 voxels hold a homogeneous medium.
Volume box_volume(float sigma_s, float sigma_a) {
  Volume v;
  v.nx = v.ny = v.nz = 16;
  v.voxel = 0.1;
  v.origin = {-0.8, -0.8, -0.8};
  v.sigma_s.assign(3 * v.count(), 0.f);
  v.sigma_t.assign(3 * v.count(), 0.f);
  for (int k = 2; k < 14; ++k)
    for (int j = 2; j < 14; ++j)
      for (int i = 2; i < 14; ++i)
        for (int c = 0; c < 3; ++c) {
          v.sigma_s[3 * v.index(i, j, k) + c] = sigma_s;
          v.sigma_t[3 * v.index(i, j, k) + c] = sigma_s + sigma_a;
        }
  set_index(v, std::vector<float>(v.count(), 1.f), 0);
  return v;
}

// Length of the ray o + t d inside the box [-0.6, 0.6]^3.
double chord(const float* ray) {
  double t0 = 0, t1 = 1e30;
  for (int a = 0; a < 3; ++a) {
    double o = ray[a], d = ray[3 + a];
    if (std::abs(d) < 1e-12) {
      if (o < -0.6 || o > 0.6) return 0;
      continue;
    }
    double ta = (-0.6 - o) / d, tb = (0.6 - o) / d;
    t0 = std::max(t0, std::min(ta, tb));
    t1 = std::min(t1, std::max(ta, tb));
  }
  return std::max(0.0, t1 - t0);
}

// The march's deposit summed over the grid equals, ray by ray, P (sigma_s / sigma_t) (1 -
// exp(-sigma_t L)) for the ray's chord L through the box (computed here on the CPU).
// With g != 0 the lattice's source is the same for the scaled coefficients (1 - g) sigma_s and
// sigma_t - g sigma_s.
void check_total_deposit(const Light& light, double g = 0) {
  const float ss = 2.f, sa = 0.5f;
  Volume v = box_volume(ss, sa);
  ClVolume dv = upload_volume(cl(), v);
  RaySet rays = light_rays({light}, v, 2, 4096);
  ASSERT_GT(rays.count(), 100);
  cl::Buffer ray_buf = upload(cl(), rays.rays);
  cl::Buffer deposit(cl().context(), CL_MEM_READ_WRITE, 3 * v.count() * sizeof(float));
  cl().queue().enqueueFillBuffer(deposit, 0.f, 0, 3 * v.count() * sizeof(float));
  cl::Buffer source(cl().context(), CL_MEM_READ_WRITE, 3 * v.count() * sizeof(float));
  for (cl::Buffer* b : {&deposit, &source})
    cl().queue().enqueueFillBuffer(*b, 0.f, 0, 3 * v.count() * sizeof(float));
  march(cl(), dv, ray_buf, rays.count(), false, 0.05, 0, g, deposit, source);
  auto total_of = [&](cl::Buffer& b) {
    std::vector<float> got(3 * v.count());
    cl().queue().enqueueReadBuffer(b, CL_TRUE, 0, got.size() * sizeof(float), got.data());
    double total = 0;
    for (size_t i = 0; i < got.size(); i += 3) total += got[i];
    return total;
  };
  auto expected_for = [&](double s, double t) {
    double e = 0;
    for (int r = 0; r < rays.count(); ++r) {
      const float* ray = &rays.rays[size_t(kRayFloats) * r];
      e += ray[6] * (s / t) * -std::expm1(-t * chord(ray));
    }
    return e;
  };
  double expected = expected_for(ss, ss + sa);
  EXPECT_GT(expected, 0);
  EXPECT_NEAR(total_of(deposit), expected, 1e-4 * expected);
  if (g == 0) return;
  double scaled = expected_for((1 - g) * ss, ss + sa - g * ss);
  EXPECT_LT(scaled, expected);
  EXPECT_NEAR(total_of(source), scaled, 1e-4 * scaled);
}

TEST(LblMarch, DirectionalDepositMatchesBeerLambertPerRay) {
  Light l;
  l.type = Light::Type::Directional;
  l.direction = normalize(Vec3{0.3, -0.2, -1});
  l.intensity = 2;
  check_total_deposit(l);
}

TEST(LblMarch, PointDepositMatchesBeerLambertPerRay) {
  Light l;
  l.type = Light::Type::Point;
  l.position = {1.5, 2, 2.5};
  l.intensity = 5;
  check_total_deposit(l);
  check_total_deposit(l, 0.6);
}

// Rays carry the light's power: a directional light's rays carry E times the disc they cover,
// a point light's carry I times the solid angle of the cone holding the volume, a spot's less.
TEST(LblMarch, RaysCarryTheLightsPower) {
  Volume v = box_volume(1, 0);
  const double radius = 0.5 * std::sqrt(3.0) * 1.6, pi = std::acos(-1.0);
  Light d;
  d.type = Light::Type::Directional;
  d.direction = {0, 0, -1};
  d.intensity = 3;
  double sum = 0;
  RaySet rays = light_rays({d}, v, 4, 4096);
  for (int r = 0; r < rays.count(); ++r) sum += rays.rays[size_t(kRayFloats) * r + 6];
  EXPECT_NEAR(sum, 3 * pi * radius * radius, 0.01 * sum);  // the disc, up to its pixelation

  Light p;
  p.position = {0, 0, 5};
  p.intensity = 7;
  sum = 0;
  rays = light_rays({p}, v, 4, 4096);
  for (int r = 0; r < rays.count(); ++r) sum += rays.rays[size_t(kRayFloats) * r + 6];
  double cos_max = std::sqrt(1 - radius * radius / 25);
  EXPECT_NEAR(sum, 7 * 2 * pi * (1 - cos_max), 1e-4 * sum);

  Light s = p;
  s.type = Light::Type::Spot;
  s.direction = {0, 0, -1};
  s.inner_deg = 5;
  s.outer_deg = 10;
  double spot = 0;
  rays = light_rays({s}, v, 4, 4096);
  for (int r = 0; r < rays.count(); ++r) spot += rays.rays[size_t(kRayFloats) * r + 6];
  EXPECT_GT(spot, 0);
  EXPECT_LT(spot, 7 * 2 * pi * (1 - std::cos(10 * pi / 180)));
  EXPECT_GT(spot, 7 * 2 * pi * (1 - std::cos(5 * pi / 180)));
}

// n = a + k y: a ray leaving horizontally at y0 keeps n cos(theta) = n(y0) = C, and its path is
// n(y(x)) = C cosh(k (x - x0) / C) (the paraxial limit is the parabola y0 + k (x - x0)^2 / (2 C)).
// It bends towards the higher index; the explicit Euler steps converge to it at first order.
TEST(LblMarch, RayInALinearIndexGradientFollowsTheClosedForm) {
  const double a = 1.2, k = 0.2;
  Volume v;
  v.nx = 84;
  v.ny = 44;
  v.nz = 4;
  v.voxel = 0.05;
  v.origin = {-2.1, -1.1, -0.1};
  v.sigma_s.assign(3 * v.count(), 0.f);
  v.sigma_t.assign(3 * v.count(), 0.f);
  std::vector<float> n(v.count());
  for (int z = 0; z < v.nz; ++z)
    for (int y = 0; y < v.ny; ++y)
      for (int x = 0; x < v.nx; ++x)
        n[v.index(x, y, z)] = float(a + k * (v.origin.y + (y + 0.5) * v.voxel));
  set_index(v, n, 0);
  ASSERT_FALSE(v.constant_n);
  ClVolume dv = upload_volume(cl(), v);
  RaySet ray;
  ray.rays = {-1.9f, 0.f, 0.f, 1.f, 0.f, 0.f, 1.f, 1.f, 1.f, 0.f, 0.f, 0.f};
  const double c = a, length = 3.0;
  auto max_error = [&](double step) {
    int steps = int(std::lround(length / step));
    std::vector<float> path = eikonal_trace(cl(), dv, ray, step, steps);
    double worst = 0;
    for (int i = 0; i < steps; ++i) {
      double x = path[3 * i] + 1.9, y = path[3 * i + 1];
      double expected = (c * std::cosh(k * x / c) - a) / k;
      worst = std::max(worst, std::abs(y - expected));
      EXPECT_NEAR(path[3 * i + 2], 0.0, 1e-6);
    }
    double x_end = path[3 * (steps - 1)] + 1.9;
    EXPECT_NEAR(x_end, length, 0.05 * length);
    EXPECT_GT(path[3 * (steps - 1) + 1], 0.7);  // bent up, towards the higher index
    return worst;
  };
  double coarse = max_error(0.02), fine = max_error(0.01);
  const double deflection = (c * std::cosh(k * length / c) - a) / k;  // 0.766
  EXPECT_LT(fine, 0.01 * deflection);
  EXPECT_LT(fine, 0.6 * coarse);  // first order: halving the step halves the error
}
}  // namespace
}  // namespace scatter::lbl
