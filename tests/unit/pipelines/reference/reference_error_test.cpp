// The path tracer's error estimate (pipelines/reference/reference_pipeline.cpp): the relative
// norm of the per-pixel standard error, from the samples' spread or, with stratified batches
// (kernels/reference/path.cl), from the batches'; it predicts the error the render has.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

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

// error_scatter on images whose answer is known: N equally noisy pixels give sqrt(2 / N) (the
// relative spread of a chi-square with N degrees of freedom), one pixel sqrt(2), a pixel's three
// channels count as one error, and an image without noise 0.
TEST(ErrorScatter, IsTheRelativeSpreadOfTheSquaredErrorOfIndependentNormalPixels) {
  Image e(4, 4);
  for (float& v : e.rgb) v = 0.3f;
  EXPECT_NEAR(error_scatter(e), std::sqrt(2.0 / 16), 1e-6);
  Image one(4, 4);
  one.rgb[3] = one.rgb[4] = one.rgb[5] = 2;  // pixel 1's three channels: one error, 3 x 4
  EXPECT_NEAR(error_scatter(one), std::sqrt(2.0), 1e-6);
  one.rgb[0] = 2;  // and pixel 0's red: 4
  EXPECT_NEAR(error_scatter(one), std::sqrt(2.0 * (12 * 12 + 4 * 4)) / (12 + 4), 1e-6);
  EXPECT_EQ(error_scatter(Image(4, 4)), 0);
}

// ... and it is that spread, drawn: 4000 images of normal errors on 40 pixels whose standard
// errors range over 10x, each pixel's three channels one error (as a grey medium's), give the
// relative spread of their squared error within 5 % (its own sampling error about 1.5 %); with
// the channels' errors independent the spread is less (sqrt(1/3) of it for equal channels),
// which error_scatter overstates.
TEST(ErrorScatter, IsTheSpreadOfDrawnNormalErrors) {
  Image sigma(8, 5);
  for (size_t p = 0; p < 40; ++p)
    for (int c = 0; c < 3; ++c) sigma.rgb[3 * p + c] = float(0.1 + 0.9 * (p % 10) / 9.0);
  std::mt19937 rng(7);
  std::normal_distribution<double> z;
  auto spread = [&](bool one_error) {
    std::vector<double> squares;
    for (int draw = 0; draw < 4000; ++draw) {
      double sq = 0;
      for (size_t p = 0; p < 40; ++p) {
        const double shared = z(rng);
        for (int c = 0; c < 3; ++c) {
          const double e = sigma.rgb[3 * p + c] * (one_error ? shared : z(rng));
          sq += e * e;
        }
      }
      squares.push_back(sq);
    }
    double mean = 0, var = 0;
    for (double q : squares) mean += q / squares.size();
    for (double q : squares) var += (q - mean) * (q - mean) / (squares.size() - 1);
    return std::sqrt(var) / mean;
  };
  const double predicted = error_scatter(sigma);
  EXPECT_NEAR(spread(true), predicted, 0.05 * predicted);
  EXPECT_NEAR(spread(false), predicted / std::sqrt(3.0), 0.05 * predicted);
}

// ... and it predicts how far the squared error one render reaches scatters over seeds: the
// squared differences of 24 pairs of renders of a small grey sphere (a few dozen noisy pixels),
// whose relative spread error_scatter gives from either render's standard error (the
// difference's is sqrt(2) times it per pixel: the same shape). Over ten sets of seeds the spread
// measured was 0.77-1.13 times the prediction.
TEST(ErrorScatter, PredictsTheSpreadOfTheErrorOneRenderReaches) {
  Scene s = small_scene("sphere", 12, 16);
  s.medium.sigma_s = {2, 2, 2};  // grey: the channels' errors are one (a coloured medium's are
  s.medium.sigma_a = {0.05, 0.05, 0.05};  // partly independent, and error_scatter overstates)
  std::vector<uint8_t> all(size_t(s.width) * s.height, 1);
  std::vector<double> squares;
  double predicted = 0;
  const int pairs = 24;
  for (int i = 0; i < pairs; ++i) {
    RenderResult a = reference_render(s, Terms::Multiple, {{"spp", 48}, {"seed", 2 * i + 1}});
    RenderResult b = reference_render(s, Terms::Multiple, {{"spp", 48}, {"seed", 2 * i + 2}});
    squares.push_back(std::pow(relative_rmse(a.image, b.image, all), 2));
    predicted += error_scatter(*a.std_error) / pairs;
  }
  double mean = 0, var = 0;
  for (double q : squares) mean += q / pairs;
  for (double q : squares) var += (q - mean) * (q - mean) / (pairs - 1);
  const double spread = std::sqrt(var) / mean;
  EXPECT_GT(predicted, 0.1);  // a handful of pixels: a wide spread
  EXPECT_NEAR(spread, predicted, 0.35 * predicted);
}

}  // namespace
}  // namespace scatter
