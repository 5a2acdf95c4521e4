// The single pipeline's bake kernels against CPU computations of the same quantities, the
// Gaussians' normalisation, the per-sample shading against the CPU, the image against the
// reference marcher, and the bake cache (byte-identical hits, corrupted files re-baked).
#include "pipelines/single/single_pipeline.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <random>

#include "../../test_util.hpp"
#include "bake/cache.hpp"
#include "pipelines/metrics.hpp"
#include "pipelines/reference/reference_pipeline.hpp"
#include "pipelines/single/sh.hpp"
#include "protocol/json_reader.hpp"
#include "single_fixture.hpp"

namespace scatter {
namespace {

using namespace single_test;

// Distance from p along unit d to the exit of the box [-h, h]^3 (p inside).
double box_exit(const Vec3& p, const Vec3& d, double h) {
  double t = 1e300;
  for (int a = 0; a < 3; ++a) {
    if (d[a] > 0) t = std::min(t, (h - p[a]) / d[a]);
    if (d[a] < 0) t = std::min(t, (-h - p[a]) / d[a]);
  }
  return t;
}

// A box whose faces lie on voxel boundaries: every voxel is all medium or all empty, so the
// optical depth through the voxels equals sigma_t times the exact chord.
Scene aligned_box(double sigma_t) {
  nlohmann::json j = test::minimal_scene();
  j["mesh"] = {{"shape", "box"}, {"size", {2, 2, 2}}};
  j["medium"] = {{"sigma_s", {0.5 * sigma_t, 0.7 * sigma_t, 0.9 * sigma_t}},
                 {"sigma_a", {0.5 * sigma_t, 0.3 * sigma_t, 0.1 * sigma_t}}};
  j["voxels"] = 16;
  return parse_scene(j, ".");
}

TEST(SingleBake, SampleDepthsMatchExactChords) {
  Scene box = aligned_box(2.0);
  VoxelGrid grid = voxelize(box, {.resolution = 16, .margin = kSingleGridMargin});
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-0.95, 0.95);
  std::vector<float> pos;
  for (int i = 0; i < 40; ++i) pos.insert(pos.end(), {float(u(rng)), float(u(rng)), float(u(rng))});
  auto dirs = sphere_directions(32);
  std::vector<float> tau = sample_depths(test::shared_gpu().cl(), grid, pos, dirs);
  for (int s = 0; s < 40; ++s)
    for (size_t k = 0; k < dirs.size(); ++k) {
      double chord = box_exit({pos[3 * s], pos[3 * s + 1], pos[3 * s + 2]}, dirs[k], 1.0);
      for (int c = 0; c < 3; ++c)
        ASSERT_NEAR(tau[(s * dirs.size() + k) * 3 + c], 2.0 * chord, 1e-4 * (1 + 2.0 * chord))
            << s << " " << k;
    }
}

// The slice sweep's first moment T(x) = sum_w exp(-tau(x, w)) w dOmega against the same sum with
// exact chords, at voxel centres of the aligned box. The sweep reads the upstream slice
// bilinearly, which smears tau a little; the moment is only a sampling-density guide.
TEST(SingleBake, FirstMomentMatchesCpuSum) {
  Scene box = aligned_box(1.5);
  VoxelGrid grid = voxelize(box, {.resolution = 16, .margin = kSingleGridMargin});
  auto dirs = sphere_directions(96);
  std::vector<float> T = first_moment(test::shared_gpu().cl(), grid, dirs);
  double worst_deep = 0, scale = 0, sq = 0;
  int n = 0;
  for (int k = 0; k < grid.nz; ++k)
    for (int j = 0; j < grid.ny; ++j)
      for (int i = 0; i < grid.nx; ++i) {
        size_t v = grid.index(i, j, k);
        if (!grid.inside[v]) continue;
        Vec3 x = grid.center(i, j, k), expected{};
        for (const Vec3& w : dirs)
          expected = expected + w * (std::exp(-1.5 * box_exit(x, w, 1.0)) * 4 * std::numbers::pi /
                                     dirs.size());
        Vec3 got{T[3 * v], T[3 * v + 1], T[3 * v + 2]};
        double e = length(got - expected);
        sq += e * e;
        ++n;
        scale = std::max(scale, length(expected));
        // Two voxels or more from every face: the bilinear upstream reads see no face there.
        if (std::max({std::abs(x.x), std::abs(x.y), std::abs(x.z)}) < 1 - 2 * grid.voxel)
          worst_deep = std::max(worst_deep, e);
      }
  ASSERT_GT(scale, 0.5);
  // Near faces and corners the trapezoid across a face-straddling upstream read errs by up to ~12 %
  // of the largest moment (the corner voxels); elsewhere it is close.
  EXPECT_LT(std::sqrt(sq / n), 0.03 * scale);
  EXPECT_LT(worst_deep, 0.03 * scale);
}

TEST(SingleBake, GaussiansSumToAboutOneInside) {
  SingleBake b = small_sphere_bake();
  ASSERT_EQ(b.count, 6000);
  EXPECT_NEAR(b.coverage_mean, 1.0, 0.02);
  // Away from the voxel centres too: random points inside the sphere, up to its surface.
  auto [mean, spread] = coverage(b);
  EXPECT_NEAR(mean, 1.0, 0.03);
  EXPECT_LT(spread, 0.12);
  // Without normalisation the sum would follow the sample density, which varies 64-fold here.
}

TEST(SingleBake, SigmaFitSharpensTheSplattedFieldAtLayerJumps) {
  Scene s = load_scene(test::source_path("scenes/layers.json"));  // sigma_s jumps 10x every 0.25
  s.voxels = 32;
  VoxelGrid grid = voxelize(s, {.resolution = s.voxels, .margin = kSingleGridMargin});
  auto error = [&](int passes) {
    SingleBakeParams p;
    p.samples = 6000;
    p.directions = 32;
    p.sigma_fit = passes;
    p.split = 0;  // the passes alone (single_split_test.cpp tests the split)
    return splatted_sigma_s_error(s, bake_single(test::shared_gpu().cl(), grid, p));
  };
  double mean_only = error(0), fitted = error(4);
  std::printf("splatted sigma_s: relative RMSE %.3f (mean) -> %.3f (4 passes)\n", mean_only,
              fitted);
  // Measured 0.51 -> 0.42: at 6000 samples the Gaussians are as wide as a quarter of a layer,
  // so much of the error is the jumps' unavoidable smoothing; the passes must cut at least 10 %.
  EXPECT_LT(fitted, 0.9 * mean_only);
}

TEST(SingleBake, SerializationRoundTripsAndRejectsDamage) {
  Scene s = small_sphere(32, 16);
  VoxelGrid grid = voxelize(s, {.resolution = s.voxels, .margin = kSingleGridMargin});
  SingleBakeParams p;
  p.samples = 500;
  p.directions = 16;
  p.sh_order = 3;
  SingleBake b = bake_single(test::shared_gpu().cl(), grid, p);
  std::string bytes = b.serialize();
  SingleBake c = SingleBake::deserialize(bytes);
  EXPECT_EQ(c.serialize(), bytes);
  EXPECT_EQ(c.sh.size(), size_t(500) * 3 * 9);
  EXPECT_THROW(SingleBake::deserialize(bytes.substr(0, bytes.size() - 3)), std::runtime_error);
  EXPECT_THROW(SingleBake::deserialize(bytes + "x"), std::runtime_error);
  EXPECT_THROW(SingleBake::deserialize("not a bake"), std::runtime_error);
}

// The compute shader's per-sample factor against the same sum on the CPU from the baked arrays.
TEST_F(SinglePipelineTest, ShadePassMatchesCpu) {
  Scene s = small_sphere();
  s.medium.g = 0.4;
  s.lights.push_back(
      {Light::Type::Spot, {-2, 3, 2}, normalize(Vec3{2, -3, -2}), {0.5, 1, 0.2}, 15, 10, 25});
  s.lights.push_back({Light::Type::Directional, {}, normalize(Vec3{0, -1, -1}), {1, 0.5, 0.5}, 2});
  pipeline().render(s, {Terms::Single, kQuick, nullptr});
  const SingleBake& b = *pipeline().current();
  std::vector<float> shaded = pipeline().read_shaded();
  ASSERT_EQ(shaded.size(), size_t(b.count) * 4);
  const int nc = int(b.coefficients());
  auto psi = [&](int i, int c, const Vec3& d) {
    double v = sh_eval(&b.sh[(size_t(i) * 3 + c) * nc], d, b.params.sh_order);
    return b.params.sh_depth ? std::exp(-std::max(0.0, v)) : std::clamp(v, 0.0, 1.0);
  };
  auto hg = [&](double cos_t) {
    double g = s.medium.g, d = 1 + g * g - 2 * g * cos_t;
    return (1 - g * g) / (4 * std::numbers::pi * d * std::sqrt(d));
  };
  int checked = 0;
  for (int i = 0; i < b.count; i += 97) {
    Vec3 x{b.position[3 * i], b.position[3 * i + 1], b.position[3 * i + 2]};
    Vec3 to_eye = normalize(s.camera.position - x);
    for (int c = 0; c < 3; ++c) {
      double in = 0;
      for (const Light& l : s.lights) {
        Vec3 wl;
        double e = (l.color * l.intensity)[c];
        if (l.type == Light::Type::Directional) {
          wl = l.direction * -1.0;
        } else {
          Vec3 to = l.position - x;
          wl = normalize(to);
          e *= spot_cone(l, wl * -1.0) / dot(to, to);  // a spot: its cone
        }
        in += e * psi(i, c, wl) * hg(dot(wl, to_eye * -1.0));
      }
      double expected = b.weight[i] * b.sigma_s[3 * i + c] * psi(i, c, to_eye) * in;
      // The shader sums the 25-term harmonics in float: where a transmittance is small the terms
      // cancel, and the worst sample of this bake is 1.5e-4 off relatively (a wrong factor is off
      // by far more).
      ASSERT_NEAR(shaded[4 * i + c], expected, 3e-4 * std::abs(expected) + 1e-9)
          << "sample " << i << " channel " << c;
    }
    ++checked;
  }
  EXPECT_GT(checked, 50);
}

// The image against the reference marcher on the same voxels. This bake (20000 samples, 64
// directions, 32^3 voxels, 64^2 pixels) measured 13.6 % relative RMSE, most of it at the rim where
// Gaussians straddle the surface, and a mean 0.4 % high; the bounds leave a little room for other
// devices. Figures for larger bakes are in docs/BENCHMARKS.md.
TEST_F(SinglePipelineTest, MatchesReferenceSingleTerm) {
  Scene s = small_sphere();
  Image single = pipeline().render(s, {Terms::Single, kQuick, nullptr}).image;
  Expected expected = reference_single(s);
  EXPECT_LT(relative_rmse(single, expected.image, expected.mask), 0.16);
  // The mean over the object, which the normalised Gaussians should get right more closely.
  EXPECT_NEAR(mean_ratio(single, expected.image), 1.0, 0.03);
}

// Measured: 22.8 % relative RMSE and a mean 5.9 % low (edges and corners, where 25 SH coefficients
// blur the transmittance most; the first light lies in the plane of the top face); with sh_depth 1
// the mean was about 45 % low, which is why the transmittance is the default.
TEST_F(SinglePipelineTest, MatchesReferenceOnABox) {
  Scene s = small_box();
  Image single = pipeline().render(s, {Terms::Single, kQuick, nullptr}).image;
  Expected expected = reference_single(s);
  EXPECT_LT(relative_rmse(single, expected.image, expected.mask), 0.27);
  EXPECT_NEAR(mean_ratio(single, expected.image), 1.0, 0.1);
}

// Lights add: eight copies of a light at an eighth of its intensity render the same image.
TEST_F(SinglePipelineTest, LightsAreLinear) {
  Scene one = small_sphere();
  Scene eight = one;
  eight.lights.assign(8, one.lights[0]);
  for (Light& l : eight.lights) l.intensity /= 8;
  Image a = pipeline().render(one, {Terms::Single, kQuick, nullptr}).image;
  Image b = pipeline().render(eight, {Terms::Single, kQuick, nullptr}).image;
  double scale = 0;
  for (float v : a.rgb) scale = std::max(scale, double(v));
  ASSERT_GT(scale, 0);
  for (size_t i = 0; i < a.rgb.size(); ++i) ASSERT_NEAR(a.rgb[i], b.rgb[i], 1e-4 * scale);
}

TEST_F(SinglePipelineTest, PlanNamesTheBakeAndItsReuse) {
  Scene s = small_sphere();
  pipeline().render(s, {Terms::Single, kQuick, nullptr});
  Plan p = pipeline().plan(s, {Terms::Single, kQuick, nullptr});
  ASSERT_GE(p.stages.size(), 2u);
  EXPECT_EQ(p.stages[1].name, "bake");
  EXPECT_FALSE(p.stages[1].run);
  EXPECT_NE(p.stages[1].reason.find("reusing"), std::string::npos);
  EXPECT_THROW(pipeline().plan(s, {Terms::Single, {{"samples", 3}}, nullptr}), ValidationError);
  EXPECT_THROW(pipeline().plan(s, {Terms::Single, {{"sh_order", 9}}, nullptr}), ValidationError);
  EXPECT_THROW(pipeline().plan(s, {Terms::All, {}, nullptr}), ValidationError);
}

// The samples and their data (not the stage times, which differ between bakes).
bool same_samples(const SingleBake& a, const SingleBake& b) {
  return a.position == b.position && a.sigma == b.sigma && a.weight == b.weight &&
         a.sigma_s == b.sigma_s && a.sh == b.sh;
}

TEST(SingleBakeCache, SecondBakeIsAByteIdenticalHitAndCorruptionIsRebaked) {
  auto dir = test::scratch_dir("single-bake-cache");
  Scene s = small_sphere(32, 16);
  RenderRequest request{Terms::Single, {{"samples", 800}, {"directions", 16}}, nullptr};
  std::string first_key, first_bytes;
  SingleBake first;
  {
    BakeCache cache(dir);
    SinglePipeline p(test::shared_gpu(), &cache);
    BakeResult r = p.bake(s, request);
    EXPECT_TRUE(r.needed);
    EXPECT_FALSE(r.cache_hit);
    first_key = r.key;
    first_bytes = p.current()->serialize();
    first = *p.current();
    // Same pipeline, same asset: no voxelization, no lookup.
    EXPECT_TRUE(p.bake(s, request).cache_hit);
  }
  {
    BakeCache cache(dir);  // a new process, as it were: only the disk holds the product
    SinglePipeline p(test::shared_gpu(), &cache);
    Scene again = small_sphere(32, 16);  // parsed anew: a new density object
    BakeResult r = p.bake(again, request);
    EXPECT_TRUE(r.cache_hit);
    EXPECT_EQ(r.key, first_key);
    EXPECT_EQ(p.current()->serialize(), first_bytes);
    EXPECT_EQ(cache.stats().disk_hits, 1u);
  }
  {
    // Flip a byte in the middle of the stored product.
    auto path = BakeCache(dir).file_path(first_key);
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    f.seekg(0, std::ios::end);
    auto size = static_cast<std::streamoff>(f.tellg());
    f.seekp(size / 2);
    char c = 0;
    f.seekg(size / 2);
    f.get(c);
    f.seekp(size / 2);
    f.put(static_cast<char>(c ^ 0x5a));
  }
  {
    BakeCache cache(dir);
    SinglePipeline p(test::shared_gpu(), &cache);
    BakeResult r = p.bake(small_sphere(32, 16), request);
    EXPECT_FALSE(r.cache_hit);
    EXPECT_EQ(cache.stats().corrupt, 1u);
    EXPECT_TRUE(same_samples(*p.current(), first));  // baked again, deterministically
  }
  {
    BakeCache cache(dir);
    SinglePipeline p(test::shared_gpu(), &cache);
    EXPECT_TRUE(p.bake(small_sphere(32, 16), request).cache_hit);  // the re-bake was stored
  }
}

// Many samples on a coarse grid: a box of 8^3 voxels at 12,000 samples, whose Poisson spacing
// would give Gaussians of sigma 0.2 voxels. The weights hold the sum of Gaussians at one at the
// voxel centres only, so sigma is kept at kMinSigmaVoxels of a voxel or more: 1.6 % from the
// reference marcher (21.8 % without the floor).
TEST_F(SinglePipelineTest, ManySamplesOnACoarseGridKeepTheirGaussiansWide) {
  nlohmann::json j = test::minimal_scene();
  j["mesh"] = {{"shape", "box"}, {"size", {2, 2, 2}}};  // voxel faces on the box's faces
  j["medium"] = {{"sigma_s", 0.2}, {"sigma_a", 0.05}, {"g", 0.3}};
  j["lights"] = {{{"type", "directional"}, {"direction", {0.3, -0.4, -1}}, {"irradiance", 1}}};
  j["camera"] = {{"position", {0.3, 0.6, 4}}, {"target", {0, 0, 0}}, {"fov_deg", 40}};
  j["image"] = {{"width", 24}, {"height", 24}};
  j["voxels"] = 8;
  Scene box = parse_scene(j, ".");
  const Settings s = {{"samples", 12000}, {"directions", 32}};
  RenderResult r = pipeline().render(box, {Terms::Single, s, nullptr});
  const SingleBake& bake = *pipeline().current();
  const double voxel = voxelize(box, {.resolution = box.voxels}).voxel;
  EXPECT_GE(*std::min_element(bake.sigma.begin(), bake.sigma.end()),
            float(kMinSigmaVoxels * voxel * (1 - 1e-6)));
  Expected ref = reference_single(box);
  EXPECT_LT(relative_rmse(r.image, ref.image, ref.mask), 0.05);
}

}  // namespace
}  // namespace scatter
