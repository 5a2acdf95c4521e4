// Shared by the single pipeline's tests: small scenes, the reference marcher's single term, and
// a fixture holding one pipeline for the whole test binary.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <utility>

#include "../../test_util.hpp"
#include "pipelines/metrics.hpp"
#include "pipelines/reference/reference_pipeline.hpp"
#include "pipelines/single/single_pipeline.hpp"

namespace scatter::single_test {

// The homogeneous sphere of scenes/sphere.json, small enough for a unit test.
inline Scene small_sphere(int size = 64, int voxels = 32) {
  Scene s = load_scene(test::source_path("scenes/sphere.json"));
  s.width = s.height = size;
  s.voxels = voxels;
  return s;
}

// The paper's path (SH of transmittance); the exact_tr tests set it to 1, the default.
inline const Settings kQuick = {{"samples", 20000}, {"directions", 64}, {"exact_tr", 0}};

// A homogeneous box seen over a corner, lit from behind and the side (cube-torus without the
// torus): flat faces, edges and corners.
inline Scene small_box() {
  Scene s = load_scene(test::source_path("scenes/cube-torus.json"));
  s.medium.density = small_sphere().medium.density;  // constant
  s.width = s.height = 64;
  s.voxels = 32;
  return s;
}

// The reference marcher's single term for `s`, and the pixels its medium covers.
struct Expected {
  Image image;
  std::vector<uint8_t> mask;
};
inline Expected reference_single(const Scene& s) {
  ReferencePipeline ref(test::shared_gpu());
  return {ref.render(s, {Terms::Single, {{"step", 0.25}}, nullptr}).image,
          coverage_mask(s, voxelize(s, {.resolution = s.voxels}))};
}

// small_sphere()'s bake of 6000 samples over 32 directions.
inline SingleBake small_sphere_bake() {
  Scene s = small_sphere();
  VoxelGrid grid = voxelize(s, {.resolution = s.voxels, .margin = kSingleGridMargin});
  SingleBakeParams p;
  p.samples = 6000;
  p.directions = 32;
  return bake_single(test::shared_gpu().cl(), grid, p);
}

// Mean and standard deviation of the Gaussians' sum at 400 random points inside the unit sphere
// (up to 0.98 from its centre).
inline std::pair<double, double> coverage(const SingleBake& b) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-1, 1);
  double sum = 0, sum2 = 0;
  int n = 0;
  while (n < 400) {
    Vec3 x{u(rng), u(rng), u(rng)};
    if (length(x) > 0.98) continue;
    double g = gaussian_sum(b, x);
    sum += g;
    sum2 += g * g;
    ++n;
  }
  double mean = sum / n;
  return {mean, std::sqrt(std::max(0.0, sum2 / n - mean * mean))};
}

// Sum of a's pixels over sum of b's.
inline double mean_ratio(const Image& a, const Image& b) {
  double x = 0, y = 0;
  for (size_t i = 0; i < a.rgb.size(); ++i) {
    x += a.rgb[i];
    y += b.rgb[i];
  }
  return x / y;
}

// The splatted scattering coefficient sum_i w_i sigma_s,i G_i(x) (channel 0) by brute force, over
// the pieces whose side of their plane holds x (all, without a split), with the weights'
// convention of gaussian_sum (a Gaussian's peak is its weight).
inline double splatted_sigma_s(const SingleBake& b, const Vec3& x) {
  double sum = 0;
  for (int i = 0; i < b.count; ++i) {
    Vec3 c{b.position[3 * i], b.position[3 * i + 1], b.position[3 * i + 2]};
    double s = b.sigma[i], r2 = dot(x - c, x - c);
    if (r2 > 9 * s * s) continue;
    const float* pl = &b.plane[4 * size_t(i)];
    if (pl[0] * x.x + pl[1] * x.y + pl[2] * x.z > pl[3]) continue;
    sum += b.weight[i] * b.sigma_s[3 * i] * std::exp(-0.5 * r2 / (s * s));
  }
  return sum;
}

// Relative RMSE of the splatted sigma_s against the scene's medium at 300 fixed points inside
// the box (-0.9, 0.9)^3.
inline double splatted_sigma_s_error(const Scene& s, const SingleBake& b) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.9, 0.9);
  double e = 0, r = 0;
  for (int k = 0; k < 300; ++k) {
    Vec3 x{u(rng), u(rng), u(rng)};
    double truth = s.medium.sigma_s[0] * s.medium.density->density(x);
    e += std::pow(splatted_sigma_s(b, x) - truth, 2);
    r += truth * truth;
  }
  return std::sqrt(e / r);
}

class SinglePipelineTest : public ::testing::Test {
 protected:
  static SinglePipeline& pipeline() {
    static SinglePipeline p(test::shared_gpu(), nullptr);
    return p;
  }
};

}  // namespace scatter::single_test
