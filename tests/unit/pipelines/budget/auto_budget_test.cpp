// auto on the GPU: what it knows of its delegates' state, what its plan says after a frame, and
// that it meets a budget on a scene outside the shipped calibration set, measured against the
// reference.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "../../test_util.hpp"
#include "budget_scenes.hpp"
#include "pipelines/auto_pipeline.hpp"
#include "pipelines/metrics.hpp"
#include "pipelines/registry.hpp"
#include "scene/voxelizer.hpp"

namespace scatter {
namespace {

using test::sphere_scene;

// lbl keeps its state for a camera-only change, not for a moved light, another material or a
// request for terms it did not diffuse; auto asks its own delegate.
TEST(AutoBudget, KnowsWhatItsLblDelegateKeeps) {
  Scene s = sphere_scene(0.9, 4, 0, 16);
  s.voxels = 16;
  auto lbl = make_pipeline("lbl", test::shared_gpu());
  const RenderRequest all{Terms::All, {}, {}}, single{Terms::Single, {}, {}};
  EXPECT_FALSE(lbl->keeps(s, all));  // nothing made yet
  lbl->render(s, single);
  EXPECT_TRUE(lbl->keeps(s, single));
  EXPECT_FALSE(lbl->keeps(s, all));  // the single term diffused nothing
  lbl->render(s, all);
  EXPECT_TRUE(lbl->keeps(s, all));
  Scene moved = s;
  moved.camera.position = moved.camera.position + Vec3{0.5, 0.2, 0};
  EXPECT_TRUE(lbl->keeps(moved, all));
  moved.lights[0].position = moved.lights[0].position + Vec3{0.3, 0, 0};
  EXPECT_FALSE(lbl->keeps(moved, all));
  Scene denser = s;
  denser.medium.sigma_s = denser.medium.sigma_s * 2.0;
  EXPECT_FALSE(lbl->keeps(denser, all));
  EXPECT_FALSE(lbl->keeps(s, {Terms::All, {{"rays", 3}}, {}}));  // another march
}

// The plan auto returns with a frame says what its parts found while rendering: the path
// tracer's trace stage, the samples it drew and their standard error (planned: the samples it
// expected).
TEST(AutoBudget, ThePlanSaysWhatItsPartsFoundWhileRendering) {
  Scene s = sphere_scene(0.97, 5, -0.9, 16);  // backward: the path tracer, no lbl
  AutoPipeline a(test::shared_gpu(), nullptr);
  const RenderRequest request{Terms::Multiple, {}, {}, 0.3};
  Plan planned = a.plan(s, request);
  ASSERT_EQ(planned.pipeline, "auto -> reference:sampled");
  const std::string drawn = "samples per pixel: relative standard error";
  EXPECT_EQ(plan_stage(planned, "trace").reason.find(drawn), std::string::npos);
  RenderResult got = a.render(s, request);
  ASSERT_TRUE(got.error_estimate);
  const std::string trace = plan_stage(got.plan, "trace").reason;
  EXPECT_NE(trace.find(drawn), std::string::npos) << trace;
  EXPECT_NE(trace.find(short_number(100 * *got.error_estimate) + " %"), std::string::npos)
      << trace << " (error estimate " << *got.error_estimate << ")";
}

// What auto reached against the reference on `s` for each (terms, budget): the marched single
// term, and all terms as it plus the path tracer's multiple term at `spp`, whose noise is taken
// out of the error in quadrature (independent, zero mean).
void expect_budgets_met(const Scene& s, std::vector<std::pair<Terms, double>> budgets, int spp) {
  auto mask = coverage_mask(s, voxelize(s, {.resolution = s.voxels}));
  AutoPipeline a(test::shared_gpu(), nullptr);
  auto reference = make_pipeline("reference", test::shared_gpu());
  Image single = reference->render(s, {Terms::Single, {{"step", 0.125}}, {}}).image;
  RenderResult multiple =
      reference->render(s, {Terms::Multiple, {{"spp", double(spp)}, {"seed", 99}}, {}});
  Image all = single;
  for (size_t k = 0; k < all.rgb.size(); ++k) all.rgb[k] += multiple.image.rgb[k];
  const double noise = relative_norm(*multiple.std_error, all, mask);
  ASSERT_LT(noise, 0.05);
  for (auto [terms, budget] : budgets) {
    RenderResult got = a.render(s, {terms, {}, {}, budget});
    ASSERT_TRUE(got.plan.expected_error);
    EXPECT_LE(*got.plan.expected_error, budget) << got.plan.pipeline;
    ASSERT_TRUE(got.error_estimate);
    const Image& truth = terms == Terms::Single ? single : all;
    double err = relative_rmse(got.image, truth, mask);
    double n = terms == Terms::Single ? 0 : noise;
    EXPECT_LE(std::sqrt(std::max(0.0, err * err - n * n)), budget)
        << got.plan.pipeline << " error " << err << ", reference noise " << n;
    std::cout << to_string(terms) << " budget " << budget << ": " << got.plan.pipeline << " error "
              << err << " (expected " << *got.plan.expected_error << ", reference noise " << n
              << ")\n";
  }
}

// Done when: a budget request on a scene that was not among the calibration scenes meets its
// budget, measured against the reference. A sphere of albedo 0.95, tau 6 and g 0.3 is none of
// them (tools/calibrate.cpp: albedo 0.6/0.9/0.99, tau 1/4/16, g -0.7/0/0.7).
TEST(AutoBudget, MeetsItsBudgetOnASceneOutsideTheCalibrationSet) {
  expect_budgets_met(sphere_scene(0.95, 6, 0.3, 40), {{Terms::Single, 0.05}, {Terms::All, 0.2}},
                     2048);
}

// Backward scattering past the calibrated g: psf's all terms, predicted from g -0.7 doubled, and
// the path tracer's noise, grown with the phase function's spread. Before (calibrated at g 0 and
// 0.7 alone), auto took psf for the same sphere at 24 x 24, which reached 39 % at 20 %.
TEST(AutoBudget, MeetsItsBudgetPastTheCalibratedBackwardScattering) {
  expect_budgets_met(sphere_scene(0.97, 5, -0.9, 16), {{Terms::All, 0.2}}, 16384);
}

// Lit from behind: the calibration's grid is lit from the front, and its twins lit from the
// side and from behind scale the prediction. Before them, auto took psf's composite for this
// sphere (bench/budget-survey.sh's s11: albedo 0.82, tau 5.7, g -0.58, noise density, the light
// behind it, facing -0.36), predicted at 9.3 %, which reached 16.3 % at 10 %.
TEST(AutoBudget, MeetsItsBudgetLitFromBehind) {
  const nlohmann::json j = {
      {"mesh", {{"shape", "sphere"}, {"radius", 1.0}}},
      {"medium",
       {{"sigma_s", {3.888, 3.888, 3.888}},
        {"sigma_a", {0.8644, 0.8644, 0.8644}},
        {"g", -0.58},
        {"density",
         {{"type", "noise"}, {"scale", 2.0}, {"min", 0.2}, {"max", 1.0}, {"seed", 11}}}}},
      {"lights",
       {{{"type", "point"},
         {"position", {-1.772, 2.5, -1.421}},
         {"color", {1, 1, 1}},
         {"intensity", 20}}}},
      {"camera",
       {{"position", {0.3, 0.5, 4}}, {"target", {0, 0, 0}}, {"up", {0, 1, 0}}, {"fov_deg", 45}}},
      {"image", {{"width", 24}, {"height", 24}}},
      {"voxels", 32}};
  Scene s = parse_scene(j, ".");
  EXPECT_LT(classify(s, Terms::All).facing, -0.3);
  expect_budgets_met(s, {{Terms::All, 0.1}}, 16384);
}

}  // namespace
}  // namespace scatter
