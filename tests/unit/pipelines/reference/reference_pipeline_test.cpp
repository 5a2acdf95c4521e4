#include "pipelines/reference/reference_pipeline.hpp"

#include <gtest/gtest.h>

#include <numbers>

#include "../../test_util.hpp"
#include "../axis_box.hpp"
#include "pipelines/accumulate.hpp"
#include "pipelines/metrics.hpp"
#include "protocol/json_reader.hpp"

namespace scatter {
namespace {

RenderResult render(const Scene& scene, Terms terms, Settings settings = {}) {
  ReferencePipeline p(test::shared_gpu());
  return p.render(scene, {terms, std::move(settings)});
}

Scene small(const std::string& name, int size, int voxels) {
  Scene s = load_scene(test::source_path("scenes/" + name + ".json"));
  s.width = s.height = size;
  s.voxels = voxels;
  return s;
}

using test::axis_box;
using test::axis_box_radiance;

// The same box with index n: the axis ray enters with 1 - F0 (normal incidence), the light's
// straight shadow ray leaves through the top with 1 - F0, and the view ray bounces between the
// faces with F0 each time: down passes see the light backwards (p(-1)), up passes forwards (p(1)):
//   L = (1 - F0)^2 sigma_s E [p(-1) A + F0 e^(-2 st) p(1) 2 e^(-2 st)] / (1 - F0^2 e^(-4 st)),
//   A = (1 - e^(-4 st)) / (2 st).
double axis_box_dielectric(double sigma_s, double sigma_a, double g, double n) {
  double st = sigma_s + sigma_a, f0 = std::pow((n - 1) / (n + 1), 2);
  auto hg = [&](double c) {
    return (1 - g * g) / (4 * std::numbers::pi * std::pow(1 + g * g - 2 * g * c, 1.5));
  };
  double a = (1 - std::exp(-4 * st)) / (2 * st);
  double up = f0 * std::exp(-2 * st) * hg(1) * 2 * std::exp(-2 * st);
  return (1 - f0) * (1 - f0) * sigma_s * 2.0 * (hg(-1) * a + up) /
         (1 - f0 * f0 * std::exp(-4 * st));
}

TEST(ReferencePipeline, DielectricBoxMatchesClosedFormOnTheAxis) {
  Scene s = axis_box(0.8, 0.2, 0.3);
  s.medium.ior = 1.5;
  double expected = axis_box_dielectric(0.8, 0.2, 0.3, 1.5);
  double marched = render(s, Terms::Single).image.at(4, 4).x;
  EXPECT_NEAR(marched, expected, 1e-3 * expected);
  RenderResult mc = render(s, Terms::Single, {{"mc", 1}, {"spp", 6000}});
  EXPECT_NEAR(mc.image.at(4, 4).x, expected, 4 * mc.std_error->at(4, 4).x);
  // The two Fresnel crossings cost more than the internal bounces give back.
  EXPECT_LT(expected, axis_box_radiance(0.8, 0.2, 0.3));
}

// Marcher and Monte Carlo agree through a refracting sphere, summed over the image.
TEST(ReferencePipeline, DielectricSphereMarcherAndMonteCarloAgree) {
  Scene s = small("sphere", 32, 32);
  s.medium.ior = 1.4;
  Image march = render(s, Terms::Single).image;
  RenderResult mc = render(s, Terms::Single, {{"mc", 1}, {"spp", 300}});
  double diff = 0, var = 0, total = 0;
  for (size_t i = 0; i < march.rgb.size(); ++i) {
    diff += mc.image.rgb[i] - march.rgb[i];
    var += double(mc.std_error->rgb[i]) * mc.std_error->rgb[i];
    total += march.rgb[i];
  }
  EXPECT_GT(total, 0);
  EXPECT_LT(std::abs(diff), 4 * std::sqrt(var));
  EXPECT_LT(std::sqrt(var), 0.01 * total);  // the comparison is sharp enough to mean something
}

// Four samples per pixel give the channels 2, 1 and 1 samples: each must be divided by its own
// count. Averaged over many seeds, every channel converges to the closed form.
TEST(ReferencePipeline, FewSamplesKeepChannelsUnbiased) {
  Scene s = axis_box(0.8, 0.2, 0.3);
  double expected = axis_box_radiance(0.8, 0.2, 0.3);
  const int runs = 150;
  double sum[3] = {}, sum_sq[3] = {};
  for (int seed = 1; seed <= runs; ++seed) {
    Vec3 v = render(s, Terms::Single, {{"mc", 1}, {"spp", 4}, {"seed", seed}}).image.at(4, 4);
    for (int c = 0; c < 3; ++c) {
      sum[c] += v[c];
      sum_sq[c] += v[c] * v[c];
    }
  }
  for (int c = 0; c < 3; ++c) {
    double mean = sum[c] / runs, se = std::sqrt((sum_sq[c] / runs - mean * mean) / (runs - 1));
    EXPECT_NEAR(mean, expected, 4 * se) << "channel " << c;
    EXPECT_LT(se, 0.1 * expected);
  }
}

TEST(ReferencePipeline, MarcherMatchesClosedFormOnTheAxis) {
  for (double st : {0.1, 1.0, 5.0}) {
    Scene s = axis_box(0.8 * st, 0.2 * st, 0.3);
    double expected = axis_box_radiance(0.8 * st, 0.2 * st, 0.3);
    Vec3 got = render(s, Terms::Single).image.at(4, 4);
    // The light's transmittance is taken at each sub-step's midpoint: relative error about
    // (sigma_t h)^2 / 24 with h = step * voxel = 1/64, i.e. 2.5e-4 at sigma_t = 5.
    EXPECT_NEAR(got.x, expected, 1e-3 * expected) << "sigma_t " << st;
    EXPECT_NEAR(got.z, expected, 1e-3 * expected);
  }
}

TEST(ReferencePipeline, MonteCarloSingleMatchesClosedFormOnTheAxis) {
  Scene s = axis_box(0.8, 0.2, 0.3);
  double expected = axis_box_radiance(0.8, 0.2, 0.3);
  // 6001 samples: not a multiple of 3, so the channels get different sample counts.
  RenderResult r = render(s, Terms::Single, {{"mc", 1}, {"spp", 6001}});
  for (int c = 0; c < 3; ++c) {
    double got = r.image.at(4, 4)[c], se = r.std_error->at(4, 4)[c];
    EXPECT_GT(se, 0);
    EXPECT_LT(se, 0.05 * expected);
    EXPECT_NEAR(got, expected, 4 * se) << "channel " << c;
  }
}

// The deterministic marcher and the Monte Carlo single-scatter estimate agree within the Monte
// Carlo noise on every shipped scene: per-pixel z-scores have unit variance and no outliers.
// Only pixels the Monte Carlo resolves (standard error under a quarter of the mean) enter the
// z-scores: where one or two of the samples hit, the sample variance says little about the error.
// The sum over all pixels covers the rest.
TEST(ReferencePipeline, MarcherAndMonteCarloAgreeOnShippedScenes) {
  for (const char* name : {"sphere", "cube-torus", "layers", "bunny"}) {
    SCOPED_TRACE(name);
    Scene s = small(name, 32, 32);
    Image march = render(s, Terms::Single).image;
    RenderResult mc = render(s, Terms::Single, {{"mc", 1}, {"spp", 192}, {"seed", 7}});
    double z2 = 0, diff = 0, var = 0;
    int n = 0, outliers = 0;
    for (size_t i = 0; i < march.rgb.size(); ++i) {
      double se = mc.std_error->rgb[i];
      diff += mc.image.rgb[i] - march.rgb[i];
      var += se * se;
      if (se <= 0 || se > 0.25 * mc.image.rgb[i]) continue;
      double z = (mc.image.rgb[i] - march.rgb[i]) / se;
      z2 += z * z;
      outliers += std::abs(z) > 5;
      ++n;
    }
    ASSERT_GT(n, 300);
    EXPECT_LT(outliers, n / 200 + 1);
    EXPECT_LT(z2 / n, 1.5);                         // unit variance, with room for a noisy stderr
    EXPECT_LT(std::abs(diff), 4 * std::sqrt(var));  // no bias in the sum over the image
  }
}

TEST(ReferencePipeline, HalvingTheMarchStepChangesLittle) {
  for (const char* name : {"sphere", "cube-torus", "layers", "bunny"}) {
    Scene s = small(name, 48, 48);
    Image a = render(s, Terms::Single, {{"step", 0.25}}).image;
    Image b = render(s, Terms::Single, {{"step", 0.125}}).image;
    double num = 0, den = 0;
    for (size_t i = 0; i < a.rgb.size(); ++i) {
      num += (a.rgb[i] - b.rgb[i]) * (a.rgb[i] - b.rgb[i]);
      den += b.rgb[i] * b.rgb[i];
    }
    EXPECT_LT(std::sqrt(num / den), 1e-3) << name;
  }
}

TEST(ReferencePipeline, ExtremeMediaStayFinite) {
  for (double st : {1e-6, 1e-2, 1.0, 1e2, 1e4})
    for (double albedo : {0.0, 1.0})
      for (double g : {-0.99, 0.0, 0.99}) {
        nlohmann::json j = test::minimal_scene();
        j["medium"] = {{"sigma_s", albedo * st},
                       {"sigma_a", (1 - albedo) * st},
                       {"g", g},
                       {"ior", st > 1 ? 1.5 : 1.0}};
        j["lights"].push_back({{"type", "point"}, {"position", {0.5, 2, 1}}, {"intensity", 5}});
        j["image"] = {{"width", 12}, {"height", 12}};
        j["voxels"] = 12;
        Scene s = parse_scene(j, ".");
        for (Terms t : {Terms::Single, Terms::All}) {
          RenderResult r = render(s, t, {{"spp", 4}, {"max_depth", 256}});
          for (float v : r.image.rgb)
            ASSERT_TRUE(std::isfinite(v) && v >= 0) << st << " " << albedo << " " << g;
          if (r.std_error) {
            for (float v : r.std_error->rgb) ASSERT_TRUE(std::isfinite(v));
          }
        }
      }
}

TEST(ReferencePipeline, RejectsUnknownSettingsAndTerms) {
  Scene s = axis_box(1, 0.1, 0);
  EXPECT_THROW(render(s, Terms::Single, {{"sppp", 3}}), ValidationError);
  EXPECT_THROW(render(s, Terms::Single, {{"spp", 0}}), ValidationError);
  EXPECT_THROW(render(s, Terms::Surface), ValidationError);
}

TEST(ReferencePipeline, SameSeedRepeats) {
  Scene s = small("sphere", 16, 16);
  RenderResult a = render(s, Terms::Multiple, {{"spp", 8}, {"seed", 3}});
  RenderResult b = render(s, Terms::Multiple, {{"spp", 8}, {"seed", 3}});
  RenderResult c = render(s, Terms::Multiple, {{"spp", 8}, {"seed", 4}});
  EXPECT_EQ(a.image.rgb, b.image.rgb);
  EXPECT_NE(a.image.rgb, c.image.rgb);
}

// error_estimate is ||std_error|| / ||image||, and it predicts the real error: two renders with
// other seeds differ by sqrt(2) times it (their difference has twice the variance), and passes
// accumulated (pipelines/accumulate.hpp) estimate what one render of all their samples does.
TEST(ReferencePipeline, TheEstimatedErrorIsTheStandardErrorsNormAndPredictsTheError) {
  Scene s = small("sphere", 24, 16);
  RenderResult a = render(s, Terms::Multiple, {{"spp", 24}, {"seed", 1}});
  RenderResult b = render(s, Terms::Multiple, {{"spp", 24}, {"seed", 2}});
  ASSERT_TRUE(a.error_estimate);
  EXPECT_EQ(*a.error_estimate, relative_norm(*a.std_error, a.image));
  std::vector<uint8_t> all(size_t(s.width) * s.height, 1);
  double apart = relative_rmse(a.image, b.image, all);
  EXPECT_NEAR(apart, std::sqrt(2.0) * *a.error_estimate, 0.2 * apart);
  PassAccumulator passes;
  for (int seed = 3; seed < 7; ++seed) {
    RenderResult p = render(s, Terms::Multiple, {{"spp", 24}, {"seed", seed}});
    passes.add(p.image, *p.std_error, 24);
  }
  RenderResult whole = render(s, Terms::Multiple, {{"spp", 96}, {"seed", 9}});
  double combined = relative_norm(passes.std_error(), passes.mean());
  EXPECT_NEAR(combined, *whole.error_estimate, 0.15 * *whole.error_estimate);
  EXPECT_NEAR(combined, *a.error_estimate / 2, 0.2 * combined);  // 4x the samples
  EXPECT_FALSE(render(s, Terms::Single).error_estimate);         // the marcher: exact
}

}  // namespace
}  // namespace scatter
