// The single pipeline with exact transmittance (exact_tr 1, the default): against the SH path,
// the gradient and curvature model (tr_gradient, tr_hessian) against its closed form and on a
// dense face, and the per-light transmittance kept while lights stay put.
#include <gtest/gtest.h>

#include <cmath>

#include "single_fixture.hpp"

namespace scatter::single_test {
namespace {

// exact_tr: the per-sample factor with optical depths summed through the voxels. On the box,
// whose faces and edges 25 SH coefficients blur, it must be much closer to the reference (the
// remaining error is the Gaussians'); and the two shadings of the same samples must agree on the
// whole.
TEST_F(SinglePipelineTest, ExactTransmittanceRemovesTheShError) {
  Scene s = small_box();
  Expected expected = reference_single(s);
  Settings exact = kQuick;
  exact["exact_tr"] = 1;
  exact["tr_gradient"] = 0;  // the factors at the samples' centres, as the SH path's
  Image with_sh = pipeline().render(s, {Terms::Single, kQuick, nullptr}).image;
  std::vector<float> sh_factors = pipeline().read_shaded();
  Image with_exact = pipeline().render(s, {Terms::Single, exact, nullptr}).image;
  std::vector<float> exact_factors = pipeline().read_shaded();
  double e_sh = relative_rmse(with_sh, expected.image, expected.mask);
  double e_exact = relative_rmse(with_exact, expected.image, expected.mask);
  EXPECT_LT(e_exact, 0.6 * e_sh) << "SH " << e_sh << ", exact " << e_exact;
  // Both shade the same samples: their factors agree on the whole (the SH differ most where the
  // transmittance is small, so the comparison is of sums, not ratios).
  double diff = 0, total = 0;
  for (size_t i = 0; i < exact_factors.size(); i += 4) {
    diff += std::abs(sh_factors[i] - exact_factors[i]);
    total += exact_factors[i];
  }
  EXPECT_GT(total, 0);
  EXPECT_LT(diff / total, 0.25);  // measured 15 %: the SH error on this box
}

// small_box seen from `distance` up its z axis and lit straight down it by a directional light.
Scene head_on_box(double distance, double fov_deg, double intensity) {
  Scene s = small_box();
  s.camera.position = {0, 0, distance};
  s.camera.target = {0, 0, 0};
  s.camera.fov_deg = fov_deg;
  s.lights = {{Light::Type::Directional, {}, Vec3{0, 0, -1}, {1, 1, 1}, intensity}};
  return s;
}

// tr_gradient: in a dense medium the transmittance falls by e within a fraction of a Gaussian,
// so its value at the centre misjudges the Gaussian's share and the clip at the face cuts off
// what it spread outwards. A dense box seen and lit head-on: taken at the centres, the image
// is 0.74 of the reference's on the whole; moved and scaled by the optical depth's
// gradient, 0.99.
TEST_F(SinglePipelineTest, TransmittanceGradientKeepsADenseFaceItsLight) {
  Scene s = head_on_box(5, 20, 3);
  s.medium.sigma_s = {10, 10, 10};
  s.medium.sigma_a = {0.2, 0.2, 0.2};
  Expected expected = reference_single(s);
  Settings on = {{"samples", 20000}, {"directions", 64}}, off = on;
  off["tr_gradient"] = 0;
  double r_off =
      mean_ratio(pipeline().render(s, {Terms::Single, off, nullptr}).image, expected.image);
  double r_on =
      mean_ratio(pipeline().render(s, {Terms::Single, on, nullptr}).image, expected.image);
  EXPECT_NEAR(r_on, 1.0, 0.06);
  EXPECT_LT(r_off, 0.85);
}

// The gradient and curvature of the optical depth by shade.cl against the closed form: a box lit
// straight down its z axis by a directional light and seen from far up that axis, where inside
// tau(to light) + tau(to eye) = 2 sigma_t (1 - z) up to the eye's slight perspective: gradient
// (0, 0, -2 sigma_t), no curvature. So each inner Gaussian moves by 2 sigma_t s^2 along z, keeps
// its sigma, and its factor grows by exp(2 sigma_t^2 s^2).
TEST_F(SinglePipelineTest, TransmittanceGradientMatchesTheClosedForm) {
  Scene s = head_on_box(40, 4, 1);
  const double st = (s.medium.sigma_s.x + s.medium.sigma_a.x + s.medium.sigma_s.y +
                     s.medium.sigma_a.y + s.medium.sigma_s.z + s.medium.sigma_a.z) /
                    3;
  Settings on = {{"samples", 20000}, {"directions", 64}}, off = on;
  off["tr_gradient"] = 0;
  pipeline().render(s, {Terms::Single, off, nullptr});
  std::vector<float> plain = pipeline().read_shaded();
  pipeline().render(s, {Terms::Single, on, nullptr});
  std::vector<float> moved = pipeline().read_shaded();
  auto [shifts, axes] = pipeline().read_moves();
  const SingleBake& b = *pipeline().current();
  ASSERT_EQ(shifts.size(), size_t(b.count) * 4);
  int checked = 0;
  for (int i = 0; i < b.count; ++i) {
    Vec3 p{b.position[3 * i], b.position[3 * i + 1], b.position[3 * i + 2]};
    double sg = b.sigma[i];
    // Inner samples whose differences (over +-sigma) stay a voxel and a half from every face.
    if (std::abs(p.x) > 0.6 || std::abs(p.y) > 0.6 || std::abs(p.z) > 0.6) continue;
    if (plain[4 * i] < 1e-12) continue;
    const double expected = 2 * st * sg * sg;
    EXPECT_NEAR(shifts[4 * i + 2], expected, 0.03 * expected) << i;
    EXPECT_NEAR(shifts[4 * i], 0.0, 0.05 * expected) << i;
    EXPECT_NEAR(shifts[4 * i + 1], 0.0, 0.05 * expected) << i;
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(axes[4 * i + k], sg, 0.01 * sg) << i;
    // The scale travels as its logarithm in the factor's fourth component.
    EXPECT_NEAR(moved[4 * i + 3], 2 * st * st * sg * sg, 0.01) << i;
    EXPECT_NEAR(std::exp(moved[4 * i + 3]) * moved[4 * i] / plain[4 * i],
                std::exp(2 * st * st * sg * sg), 0.01)
        << i;
    ++checked;
  }
  EXPECT_GT(checked, 200);  // 293 with this bake
}

// A sample whose light reaches the eye through more than 40 optical depths adds nothing: shade.cl
// gives it a zero factor (the splat draws nothing) and no gradient. The closed-form box above,
// denser: the depth, eye plus light, is 2 sigma_t (1 - z) (a_z, the sample's anchor), so samples
// below z = 1 - 40 / (2 sigma_t) are zero and no move, those above keep their light.
TEST_F(SinglePipelineTest, SamplesDeeperThanFortyOpticalDepthsAreSkipped) {
  Scene s = head_on_box(40, 4, 1);
  s.medium.sigma_s = {30, 30, 30};
  s.medium.sigma_a = {0.5, 0.5, 0.5};
  const double st = 30.5, cut = 1 - 40 / (2 * st), margin = 0.15;  // 2.4 voxels
  pipeline().render(s, {Terms::Single, {{"samples", 20000}, {"directions", 64}}, nullptr});
  std::vector<float> shaded = pipeline().read_shaded();
  auto [shifts, axes] = pipeline().read_moves();
  const SingleBake& b = *pipeline().current();
  int deep = 0, shallow = 0;
  for (int i = 0; i < b.count; ++i) {
    double x = b.depth_at[3 * i], y = b.depth_at[3 * i + 1], z = b.depth_at[3 * i + 2];
    if (std::abs(x) > 0.8 || std::abs(y) > 0.8) continue;  // the tau above holds inside
    if (z < cut - margin) {
      ++deep;
      for (int c = 0; c < 3; ++c) EXPECT_EQ(shaded[4 * i + c], 0.f) << i << " at z " << z;
      for (int k = 0; k < 3; ++k) EXPECT_EQ(shifts[4 * i + k], 0.f) << i;
    } else if (z > cut + margin && z < 0.9 && b.weight[i] > 0) {  // (the fit zeroes a few)
      ++shallow;
      EXPECT_GT(shaded[4 * i], 0.f) << i << " at z " << z;
    }
  }
  EXPECT_GT(deep, 1000);
  EXPECT_GT(shallow, 100);
}

// exact_tr keeps each light's transmittance while the light stays put: a camera move recomputes
// none, moving one light of two recomputes that one, and the image matches a fresh pipeline's.
TEST_F(SinglePipelineTest, ExactTransmittanceIsRecomputedOnlyForLightsThatMoved) {
  Scene s = small_sphere();
  s.lights.push_back({Light::Type::Directional, {}, normalize(Vec3{0, -1, -1}), {1, 0.5, 0.5}, 2});
  Settings exact = kQuick;
  exact["exact_tr"] = 1;
  SinglePipeline p(test::shared_gpu(), nullptr);
  p.render(s, {Terms::Single, exact, nullptr});
  EXPECT_EQ(p.light_passes(), 2);
  s.camera.position = {1, 0.5, 4};
  p.render(s, {Terms::Single, exact, nullptr});
  EXPECT_EQ(p.light_passes(), 2);
  s.lights[0].position = {-3, 3, 3};
  Image moved = p.render(s, {Terms::Single, exact, nullptr}).image;
  EXPECT_EQ(p.light_passes(), 3);
  SinglePipeline fresh(test::shared_gpu(), nullptr);
  Image expected = fresh.render(s, {Terms::Single, exact, nullptr}).image;
  ASSERT_EQ(moved.rgb.size(), expected.rgb.size());
  for (size_t i = 0; i < moved.rgb.size(); ++i)
    ASSERT_NEAR(moved.rgb[i], expected.rgb[i], 1e-6 + 1e-5 * expected.rgb[i]);
}

// The SH path after an exact frame of the same bake: the Gaussians the exact frame moved and
// stretched are the samples' own again (the image equals the first SH frame's exactly).
TEST_F(SinglePipelineTest, ShPathAfterAnExactFrameUsesTheSamplesOwnGaussians) {
  Scene s = small_box();
  Settings exact = kQuick;
  exact["exact_tr"] = 1;
  Image first = pipeline().render(s, {Terms::Single, kQuick, nullptr}).image;
  Image moved = pipeline().render(s, {Terms::Single, exact, nullptr}).image;
  Image again = pipeline().render(s, {Terms::Single, kQuick, nullptr}).image;
  ASSERT_EQ(first.rgb.size(), again.rgb.size());
  double differs = 0;
  for (size_t i = 0; i < first.rgb.size(); ++i)
    differs += std::abs(double(moved.rgb[i]) - first.rgb[i]);
  EXPECT_GT(differs, 0);  // the exact frame did move something
  for (size_t i = 0; i < first.rgb.size(); ++i) ASSERT_EQ(first.rgb[i], again.rgb[i]) << i;
}

// A medium far denser than its voxels (mean free path a third of a voxel) with the gradient
// bound at its largest: the moved Gaussians' scale is bounded, so the image stays finite and
// non-negative (unbounded, this scene's largest setting gave non-finite pixels).
TEST_F(SinglePipelineTest, DenseMediumAtTheLargestGradientBoundStaysFinite) {
  Scene s = small_box();
  s.medium.sigma_s = {300, 300, 300};
  s.medium.sigma_a = {3, 3, 3};
  Settings settings = {{"samples", 20000}, {"directions", 64}, {"tr_gradient_max", 4}};
  Image image = pipeline().render(s, {Terms::Single, settings, nullptr}).image;
  double sum = 0;
  for (float v : image.rgb) {
    ASSERT_TRUE(std::isfinite(v));
    ASSERT_GE(v, 0.f);
    sum += v;
  }
  EXPECT_GT(sum, 0);
}

}  // namespace
}  // namespace scatter::single_test
