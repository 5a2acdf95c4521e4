// The path tracer's error estimate (pipelines/reference/reference_pipeline.cpp): the relative
// norm of the per-pixel standard error, from the samples' spread or, with stratified batches
// (kernels/reference/path.cl), from the batches'; it predicts the error the render has.
#include <gtest/gtest.h>

#include <cmath>

#include "../../test_util.hpp"
#include "pipelines/accumulate.hpp"
#include "pipelines/metrics.hpp"
#include "pipelines/reference/reference_pipeline.hpp"
#include "reference_render.hpp"

namespace scatter {
namespace {

using test::reference_render;
using test::small_scene;

// error_estimate is ||std_error|| / ||image||, and it predicts the real error: two renders with
// other seeds differ by sqrt(2) times it (their difference has twice the variance), and passes
// accumulated (pipelines/accumulate.hpp) estimate what one render of all their samples does.
TEST(ReferencePipeline, TheEstimatedErrorIsTheStandardErrorsNormAndPredictsTheError) {
  Scene s = small_scene("sphere", 24, 16);
  RenderResult a = reference_render(s, Terms::Multiple, {{"spp", 24}, {"seed", 1}});
  RenderResult b = reference_render(s, Terms::Multiple, {{"spp", 24}, {"seed", 2}});
  ASSERT_TRUE(a.error_estimate);
  EXPECT_EQ(*a.error_estimate, relative_norm(*a.std_error, a.image));
  std::vector<uint8_t> all(size_t(s.width) * s.height, 1);
  double apart = relative_rmse(a.image, b.image, all);
  EXPECT_NEAR(apart, std::sqrt(2.0) * *a.error_estimate, 0.2 * apart);
  PassAccumulator passes;
  for (int seed = 3; seed < 7; ++seed) {
    RenderResult p = reference_render(s, Terms::Multiple, {{"spp", 24}, {"seed", seed}});
    passes.add(p.image, *p.std_error, 24);
  }
  RenderResult whole = reference_render(s, Terms::Multiple, {{"spp", 96}, {"seed", 9}});
  double combined = relative_norm(passes.std_error(), passes.mean());
  EXPECT_NEAR(combined, *whole.error_estimate, 0.15 * *whole.error_estimate);
  EXPECT_NEAR(combined, *a.error_estimate / 2, 0.2 * combined);     // 4x the samples
  EXPECT_FALSE(reference_render(s, Terms::Single).error_estimate);  // the marcher: exact
}

TEST(ReferencePipeline, BatchesLeaveThirtyTwoOfUpToSixteenSamples) {
  EXPECT_EQ(batch_for(3), 1);
  EXPECT_EQ(batch_for(63), 1);
  EXPECT_EQ(batch_for(64), 2);
  EXPECT_EQ(batch_for(192), 4);
  EXPECT_EQ(batch_for(256), 8);
  EXPECT_EQ(batch_for(512), 16);
  EXPECT_EQ(batch_for(1 << 20), 16);
}

// Stratified batches (the default at 256 samples: 8 a batch) against independent samples
// (batch=1) on a grey sphere, all orders: the same mean within the two estimates' noise, less
// noise (0.81x here; a coloured medium's real or null collisions are not stratified: 0.91x),
// and the batches' estimate predicts the error: two renders with other seeds differ by sqrt(2)
// times it.
TEST(ReferencePipeline, StratifiedBatchesLowerTheNoiseAndTheirEstimatePredictsIt) {
  Scene s = small_scene("sphere", 24, 16);
  s.medium.sigma_s = {2, 2, 2};
  s.medium.sigma_a = {0.05, 0.05, 0.05};
  RenderResult a = reference_render(s, Terms::All, {{"spp", 256}, {"seed", 1}});
  RenderResult b = reference_render(s, Terms::All, {{"spp", 256}, {"seed", 2}});
  RenderResult independent =
      reference_render(s, Terms::All, {{"spp", 256}, {"seed", 3}, {"batch", 1}});
  std::vector<uint8_t> all(size_t(s.width) * s.height, 1);
  const double ea = *a.error_estimate, ei = *independent.error_estimate;
  EXPECT_LT(ea, 0.9 * ei);
  EXPECT_NEAR(relative_rmse(a.image, b.image, all), std::sqrt(2.0) * ea, 0.2 * std::sqrt(2.0) * ea);
  EXPECT_NEAR(relative_rmse(a.image, independent.image, all), std::hypot(ea, ei),
              0.2 * std::hypot(ea, ei));
}

}  // namespace
}  // namespace scatter
