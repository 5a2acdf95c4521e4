#include "pipelines/reference/reference_pipeline.hpp"

#include <gtest/gtest.h>

#include <numbers>

#include "../../test_util.hpp"
#include "../axis_box.hpp"
#include "pipelines/metrics.hpp"
#include "protocol/json_reader.hpp"
#include "reference_render.hpp"

namespace scatter {
namespace {

using test::reference_render;
using test::small_scene;

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
  double marched = reference_render(s, Terms::Single).image.at(4, 4).x;
  EXPECT_NEAR(marched, expected, 1e-3 * expected);
  RenderResult mc = reference_render(s, Terms::Single, {{"mc", 1}, {"spp", 6000}});
  EXPECT_NEAR(mc.image.at(4, 4).x, expected, 4 * mc.std_error->at(4, 4).x);
  // The two Fresnel crossings cost more than the internal bounces give back.
  EXPECT_LT(expected, axis_box_radiance(0.8, 0.2, 0.3));
}

// Marcher and Monte Carlo agree through a refracting sphere, summed over the image.
TEST(ReferencePipeline, DielectricSphereMarcherAndMonteCarloAgree) {
  Scene s = small_scene("sphere", 32, 32);
  s.medium.ior = 1.4;
  Image march = reference_render(s, Terms::Single).image;
  RenderResult mc = reference_render(s, Terms::Single, {{"mc", 1}, {"spp", 300}});
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

// Few samples per pixel (each carries the three channels): averaged over many seeds, every
// channel converges to the closed form.
TEST(ReferencePipeline, FewSamplesKeepChannelsUnbiased) {
  Scene s = axis_box(0.8, 0.2, 0.3);
  double expected = axis_box_radiance(0.8, 0.2, 0.3);
  const int runs = 150;
  double sum[3] = {}, sum_sq[3] = {};
  for (int seed = 1; seed <= runs; ++seed) {
    Vec3 v =
        reference_render(s, Terms::Single, {{"mc", 1}, {"spp", 4}, {"seed", seed}}).image.at(4, 4);
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
    Vec3 got = reference_render(s, Terms::Single).image.at(4, 4);
    // The light's transmittance is taken at each sub-step's midpoint: relative error about
    // (sigma_t h)^2 / 24 with h = step * voxel = 1/64, i.e. 2.5e-4 at sigma_t = 5.
    EXPECT_NEAR(got.x, expected, 1e-3 * expected) << "sigma_t " << st;
    EXPECT_NEAR(got.z, expected, 1e-3 * expected);
  }
}

TEST(ReferencePipeline, MonteCarloSingleMatchesClosedFormOnTheAxis) {
  Scene s = axis_box(0.8, 0.2, 0.3);
  double expected = axis_box_radiance(0.8, 0.2, 0.3);
  RenderResult r = reference_render(s, Terms::Single, {{"mc", 1}, {"spp", 6001}});
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
// The sum over all pixels covers the rest; a pixel's three channels come from the same paths,
// so their errors are correlated: its variance is bounded by (sum of the channels' errors)^2.
TEST(ReferencePipeline, MarcherAndMonteCarloAgreeOnShippedScenes) {
  for (const char* name : {"sphere", "cube-torus", "layers", "bunny"}) {
    SCOPED_TRACE(name);
    Scene s = small_scene(name, 32, 32);
    Image march = reference_render(s, Terms::Single).image;
    RenderResult mc = reference_render(s, Terms::Single, {{"mc", 1}, {"spp", 192}, {"seed", 7}});
    double z2 = 0, diff = 0, var = 0;
    int n = 0, outliers = 0;
    for (size_t i = 0; i < march.rgb.size(); ++i) {
      double se = mc.std_error->rgb[i];
      diff += mc.image.rgb[i] - march.rgb[i];
      if (i % 3 == 0) {
        const float* e = &mc.std_error->rgb[i];
        var += std::pow(double(e[0]) + e[1] + e[2], 2);
      }
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
    Scene s = small_scene(name, 48, 48);
    Image a = reference_render(s, Terms::Single, {{"step", 0.25}}).image;
    Image b = reference_render(s, Terms::Single, {{"step", 0.125}}).image;
    double num = 0, den = 0;
    for (size_t i = 0; i < a.rgb.size(); ++i) {
      num += (a.rgb[i] - b.rgb[i]) * (a.rgb[i] - b.rgb[i]);
      den += b.rgb[i] * b.rgb[i];
    }
    EXPECT_LT(std::sqrt(num / den), 1e-3) << name;
  }
}

// Single scattering in a homogeneous index-matched sphere lit by a directional light, on the CPU:
// per pixel, Simpson's rule along the exact chord of the view ray through the sphere, with the
// light's exact chord to each point:
//   L = int sigma_s E p(wl . d) exp(-sigma_t (t - t0)) exp(-sigma_t s(x)) dt.
Image analytic_sphere_single(const Scene& s, double radius) {
  const Vec3 ss = s.medium.sigma_s, st = s.medium.sigma_s + s.medium.sigma_a;
  const Light& light = s.lights.at(0);
  const Vec3 wl = normalize(light.direction * -1.0), e = light.color * light.intensity;
  const double g = s.medium.g;
  auto hg = [&](double c) {
    return (1 - g * g) / (4 * std::numbers::pi * std::pow(1 + g * g - 2 * g * c, 1.5));
  };
  CameraFrame frame = camera_frame(s.camera, s.width, s.height);
  Image out(s.width, s.height);
  for (int j = 0; j < s.height; ++j)
    for (int i = 0; i < s.width; ++i) {
      Vec3 o = s.camera.position, d = frame.ray(i, j, s.width, s.height);
      double b = dot(o, d), c = dot(o, o) - radius * radius, disc = b * b - c;
      if (disc <= 0) continue;
      double t0 = -b - std::sqrt(disc), t1 = -b + std::sqrt(disc);
      const int n = 400;  // even
      double h = (t1 - t0) / n;
      Vec3 sum;
      for (int k = 0; k <= n; ++k) {
        double t = t0 + k * h;
        Vec3 x = o + d * t;
        double bx = dot(x, wl), cx = std::max(0.0, radius * radius - dot(x, x));
        double chord = -bx + std::sqrt(bx * bx + cx);
        double wk = (k == 0 || k == n) ? 1 : (k % 2 ? 4 : 2);
        for (int ch = 0; ch < 3; ++ch) sum[ch] += wk * std::exp(-st[ch] * (t - t0 + chord));
      }
      for (int ch = 0; ch < 3; ++ch)
        out.rgb[3 * (size_t(j) * s.width + i) + ch] =
            static_cast<float>(ss[ch] * e[ch] * hg(dot(wl, d)) * sum[ch] * h / 3);
    }
  return out;
}

// The sphere (radius 1, sigma_s 2, sigma_a 0.05; here with colour) under the shipped
// sphere's light as a sun: direction and irradiance of its point light at the centre.
Scene analytic_sphere(int size, int voxels) {
  nlohmann::json j = test::minimal_scene();
  j["mesh"] = {{"shape", "sphere"}, {"radius", 1.0}, {"detail", 384}};
  j["medium"] = {{"sigma_s", {2.0, 1.0, 0.5}}, {"sigma_a", {0.05, 0.2, 0.5}}, {"g", 0.3}};
  j["lights"] = {
      {{"type", "directional"}, {"direction", {-1, -1, -1}}, {"irradiance", 20.0 / 27.0}}};
  j["image"] = {{"width", size}, {"height", size}};
  j["voxels"] = voxels;
  return parse_scene(j, ".");
}

std::vector<uint8_t> hits_sphere(const Image& analytic) {
  std::vector<uint8_t> mask(size_t(analytic.width) * analytic.height);
  for (size_t p = 0; p < mask.size(); ++p) mask[p] = analytic.rgb[3 * p] > 0;
  return mask;
}

// The medium is bounded by the mesh exactly: the marcher matches the exact sphere's quadrature
// (measured 0.05 % at 16 voxels; the voxels only carry the density), where the voxel-bounded
// medium (voxel_boundary=1) is 5.6 % off. The mesh has 384 segments: at the default 96 the
// grazing pixels' chords through the facets, not the exact sphere's, make it 1.2 %.
TEST(ReferencePipeline, SingleTermMatchesTheAnalyticSphere) {
  Scene s = analytic_sphere(32, 16);
  Image exact = analytic_sphere_single(s, 1.0);
  std::vector<uint8_t> mask = hits_sphere(exact);
  double marched = relative_rmse(reference_render(s, Terms::Single).image, exact, mask);
  EXPECT_LT(marched, 0.005);
  double voxels =
      relative_rmse(reference_render(s, Terms::Single, {{"voxel_boundary", 1}}).image, exact, mask);
  EXPECT_GT(voxels, 0.03);
  // The Monte Carlo single term too, per pixel within its noise.
  RenderResult mc = reference_render(s, Terms::Single, {{"mc", 1}, {"spp", 256}});
  int n = 0, outliers = 0;
  double diff = 0, var = 0;
  for (size_t i = 0; i < exact.rgb.size(); ++i) {
    if (!mask[i / 3]) continue;
    double se = mc.std_error->rgb[i];
    diff += mc.image.rgb[i] - exact.rgb[i];
    var += se * se;
    ++n;
    outliers += std::abs(mc.image.rgb[i] - exact.rgb[i]) > 5 * se;
  }
  ASSERT_GT(n, 1000);
  EXPECT_LT(outliers, n / 200 + 1);
  EXPECT_LT(std::abs(diff), 4 * std::sqrt(var));
}

// With the mesh as the boundary a coarse grid renders what a fine one does where the density is
// smooth (a constant one here, with colour); the voxel-bounded medium's staircase does not.
TEST(ReferencePipeline, TheMeshBoundsTheMediumAtEveryGrid) {
  Scene coarse = small_scene("sphere", 24, 16), fine = small_scene("sphere", 24, 64);
  std::vector<uint8_t> all(24 * 24, 1);
  Image c = reference_render(coarse, Terms::Single).image,
        f = reference_render(fine, Terms::Single).image;
  EXPECT_LT(relative_rmse(c, f, all), 0.005);
  Image cv = reference_render(coarse, Terms::Single, {{"voxel_boundary", 1}}).image;
  Image fv = reference_render(fine, Terms::Single, {{"voxel_boundary", 1}}).image;
  EXPECT_GT(relative_rmse(cv, fv, all), 0.05);
  // All orders: the image sums agree within noise.
  RenderResult a = reference_render(coarse, Terms::All, {{"spp", 48}, {"seed", 1}});
  RenderResult b = reference_render(fine, Terms::All, {{"spp", 48}, {"seed", 2}});
  double diff = 0, var = 0, total = 0;
  for (size_t i = 0; i < a.image.rgb.size(); ++i) {
    diff += a.image.rgb[i] - b.image.rgb[i];
    var += std::pow(a.std_error->rgb[i], 2) + std::pow(b.std_error->rgb[i], 2);
    total += b.image.rgb[i];
  }
  EXPECT_LT(std::abs(diff), 4 * std::sqrt(var));
  EXPECT_LT(std::sqrt(var), 0.015 * total);  // sharp enough: the staircase moved it 5 %
}

// Spectral tracking keeps a grey medium's mean: the box of axis_box.hpp with all orders, against
// the one-channel-per-path tracker's mean over the image (main at 5dd5f27: 60000 samples per
// pixel, 20000 per channel, seed 11), within the two standard errors.
TEST(ReferencePipeline, GreyMediumKeepsItsMeanUnderSpectralTracking) {
  Scene s = axis_box(2.0, 0.05, 0.3);
  const double before = 0.149826, before_se = 8.69e-5;
  RenderResult r = reference_render(s, Terms::All, {{"spp", 3000}, {"seed", 5}});
  double sum = 0, var = 0;
  const size_t n = size_t(s.width) * s.height;
  for (size_t p = 0; p < n; ++p) {
    sum += r.image.rgb[3 * p];  // the channels are equal: one is the estimate
    var += std::pow(r.std_error->rgb[3 * p], 2);
    EXPECT_EQ(r.image.rgb[3 * p], r.image.rgb[3 * p + 2]);
  }
  double mean = sum / n, se = std::sqrt(var) / n;
  EXPECT_NEAR(mean, before, 4 * std::hypot(se, before_se));
  EXPECT_LT(se, 0.005 * before);
}

// A coloured medium's channels, carried together by one path, each match a grey run with that
// channel's coefficients, within noise (image means, all orders).
TEST(ReferencePipeline, ColouredChannelsMatchGreyRunsOfEachChannel) {
  const Vec3 ss{2.0, 1.0, 0.5}, sa{0.05, 0.2, 0.5};
  Scene colour = axis_box(0, 0, 0.3);
  colour.medium.sigma_s = ss;
  colour.medium.sigma_a = sa;
  RenderResult c = reference_render(colour, Terms::All, {{"spp", 2000}, {"seed", 3}});
  const size_t n = size_t(colour.width) * colour.height;
  for (int ch = 0; ch < 3; ++ch) {
    RenderResult grey =
        reference_render(axis_box(ss[ch], sa[ch], 0.3), Terms::All, {{"spp", 2000}, {"seed", 4}});
    double a = 0, b = 0, va = 0, vb = 0;
    for (size_t p = 0; p < n; ++p) {
      a += c.image.rgb[3 * p + ch];
      b += grey.image.rgb[3 * p + ch];
      va += std::pow(c.std_error->rgb[3 * p + ch], 2);
      vb += std::pow(grey.std_error->rgb[3 * p + ch], 2);
    }
    EXPECT_NEAR(a, b, 4 * std::sqrt(va + vb)) << "channel " << ch;
    EXPECT_LT(std::sqrt(va + vb), 0.02 * b) << "channel " << ch;
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
          RenderResult r = reference_render(s, t, {{"spp", 4}, {"max_depth", 256}});
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
  EXPECT_THROW(reference_render(s, Terms::Single, {{"sppp", 3}}), ValidationError);
  EXPECT_THROW(reference_render(s, Terms::Single, {{"spp", 0}}), ValidationError);
  EXPECT_THROW(reference_render(s, Terms::Surface), ValidationError);
}

TEST(ReferencePipeline, SameSeedRepeats) {
  Scene s = small_scene("sphere", 16, 16);
  RenderResult a = reference_render(s, Terms::Multiple, {{"spp", 8}, {"seed", 3}});
  RenderResult b = reference_render(s, Terms::Multiple, {{"spp", 8}, {"seed", 3}});
  RenderResult c = reference_render(s, Terms::Multiple, {{"spp", 8}, {"seed", 4}});
  EXPECT_EQ(a.image.rgb, b.image.rgb);
  EXPECT_NE(a.image.rgb, c.image.rgb);
}

// The mesh queries through the voxels' triangle lists (cells=1) find the BVH's hits
// (CellTriangles.KernelHitsMatchTheBvh), so with the same seed the paths are the same: the two
// images differ by float rounding where a path's crossing lands within it of a collision, far
// below the noise (each image's own relative standard error is stated beside it), on a convex
// and a non-convex mesh, index matched and dielectric.
TEST(ReferencePipeline, CellListsGiveTheBvhsImage) {
  for (const std::string name : {"sphere", "bunny"})
    for (double ior : {1.0, 1.4}) {
      SCOPED_TRACE(name + " ior " + std::to_string(ior));
      Scene s = small_scene(name, 24, 32);
      s.medium.ior = ior;
      RenderResult bvh = reference_render(s, Terms::All, {{"spp", 8}, {"seed", 5}, {"cells", 0}});
      RenderResult cells = reference_render(s, Terms::All, {{"spp", 8}, {"seed", 5}, {"cells", 1}});
      double apart = relative_rmse(cells.image, bvh.image,
                                   coverage_mask(s, voxelize(s, {.resolution = s.voxels})));
      EXPECT_LT(apart, 0.02 * *bvh.error_estimate) << "noise " << *bvh.error_estimate;
      EXPECT_GT(*bvh.error_estimate, 0.01);
    }
}

// A constant density inside the mesh is tracked without walks (setting homogeneous): the same
// image from the same seed as the bricks' walks give; a noise density keeps the walks.
TEST(ReferencePipeline, AConstantMediumGivesTheWalksImageWithoutThem) {
  Scene s = small_scene("sphere", 24, 24);
  RenderResult fast = reference_render(s, Terms::All, {{"spp", 8}, {"seed", 2}});
  RenderResult walked =
      reference_render(s, Terms::All, {{"spp", 8}, {"seed", 2}, {"homogeneous", 0}});
  std::vector<uint8_t> all(size_t(s.width) * s.height, 1);
  EXPECT_LT(relative_rmse(fast.image, walked.image, all), 1e-4);
  EXPECT_NE(plan_stage(fast.plan, "upload").reason.find("homogeneous"), std::string::npos);
  EXPECT_EQ(plan_stage(walked.plan, "upload").reason.find("homogeneous"), std::string::npos);
  Scene bunny = small_scene("bunny", 16, 16);
  RenderResult noise = reference_render(bunny, Terms::All, {{"spp", 3}});
  EXPECT_EQ(plan_stage(noise.plan, "upload").reason.find("homogeneous"), std::string::npos);
}

}  // namespace
}  // namespace scatter
