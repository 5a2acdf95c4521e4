// The psf pipeline: its single term against a closed form and the reference marcher, its multiple
// term against a CPU evaluation of the same formulas on a box's axis, what it keeps between frames,
// and what it refuses.
#include "pipelines/psf/psf_pipeline.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "../../test_util.hpp"
#include "../axis_box.hpp"
#include "pipelines/metrics.hpp"
#include "protocol/json_reader.hpp"
#include "scene/voxelizer.hpp"

namespace scatter {
namespace {

constexpr double kPi = std::numbers::pi;

using test::axis_box;

float centre(const Image& im, int c) {
  return im.rgb[3 * (4 * 9 + 4) + c];
}

TEST(PsfPipeline, SingleTermOnTheAxisMatchesClosedForm) {
  const double ss = 0.8, sa = 0.2, g = 0.3;
  PsfPipeline p(test::shared_gpu());
  RenderResult r = p.render(axis_box(ss, sa, g), {Terms::Single, {}});
  // Light and view both travel depth s (tests/unit/pipelines/axis_box.hpp).
  double expected = test::axis_box_radiance(ss, sa, g);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(centre(r.image, c), expected, 0.01 * expected);
}

TEST(PsfPipeline, MultipleTermOnTheAxisMatchesTheModelOnTheCpu) {
  // With a shift larger than any path's scattering events the blur width is zero, so the march
  // reads the unblurred source and the term is, on the axis (theta = pi, l = 2 b s, S = 2 s):
  //   int_0^2 e^(-c s) b E e^(-c s) P_MS(l, pi) exp(-alpha pi^2 / l) ds     (atten 1)
  // and atten 0 multiplies the integrand by e^(-c s) once more (the light segment's extinction).
  const double ss = 0.8, sa = 0.2, g = 0.3, st = ss + sa, E = 2.0;
  psf::PmsTable t = psf::pms_table(g);
  const double alpha = psf::curvature_alpha(g);
  for (int atten : {0, 1}) {
    double sum = 0;
    const int n = 20000;
    for (int i = 0; i < n; ++i) {
      double s = (i + 0.5) * 2.0 / n, ell = 2 * ss * s;
      double f = std::exp(-2 * st * s) * ss * E * psf::pms(t, ell, kPi) *
                 std::exp(-alpha * kPi * kPi / ell);
      sum += f * (atten == 0 ? std::exp(-st * s) : 1.0) * (2.0 / n);
    }
    PsfPipeline p(test::shared_gpu());
    RenderResult r = p.render(
        axis_box(ss, sa, g),
        {Terms::Multiple, {{"model", 0}, {"shift", 100}, {"atten", atten}, {"step", 0.25}}});
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(centre(r.image, c), sum, 0.02 * sum) << "atten " << atten;
  }
}

Scene small_sphere() {
  Scene s = load_scene(test::source_path("scenes/sphere.json"));
  s.width = s.height = 32;
  s.voxels = 32;
  return s;
}

TEST(PsfPipeline, SingleTermAgreesWithTheReferenceMarcher) {
  Scene s = small_sphere();
  PsfPipeline p(test::shared_gpu());
  Image mine = p.render(s, {Terms::Single, {}}).image;
  // Against the reference on the same voxelized medium (voxel_boundary: psf's staircase too): the
  // light volume is read trilinearly between voxel centres instead of marched exactly.
  Image ref = make_pipeline("reference", test::shared_gpu())
                  ->render(s, {Terms::Single, {{"voxel_boundary", 1}}})
                  .image;
  EXPECT_LT(relative_rmse(mine, ref, coverage_mask(s, voxelize(s, {.resolution = s.voxels}))),
            0.02);
}

// The march reports its progress in bands of rows, so that a cancel (a progress that throws)
// stops it within a band, and the banded image is the one-pass image.
TEST(PsfPipeline, MarchStopsWithinABandOfRows) {
  Scene s = small_sphere();
  s.width = s.height = 64;
  PsfPipeline p(test::shared_gpu());
  Image whole = p.render(s, {Terms::All, {}}).image;
  std::vector<double> seen;
  Image banded = p.render(s, {Terms::All, {}, [&](double f) { seen.push_back(f); }}).image;
  ASSERT_GE(seen.size(), 8u);  // 64 rows in bands of 8, one light
  for (size_t i = 1; i < seen.size(); ++i) EXPECT_GT(seen[i], seen[i - 1]);
  EXPECT_DOUBLE_EQ(seen.back(), 1.0);
  EXPECT_EQ(banded.rgb, whole.rgb);
  int calls = 0;
  struct Stop {};
  EXPECT_THROW(p.render(s, {Terms::All,
                            {},
                            [&](double) {
                              if (++calls == 2) throw Stop{};
                            }}),
               Stop);
  EXPECT_EQ(calls, 2);  // no band after the one that stopped it
}

// The orders model (model 1, the default) against the reference path tracer's multiple term on a
// small sphere, and the paper's (model 0) as far off as docs/BENCHMARKS.md says it is.
TEST(PsfPipeline, SphereMultipleTermIsNearTheReference) {
  Scene s = small_sphere();
  s.width = s.height = 24;
  RenderResult ref =
      make_pipeline("reference", test::shared_gpu())->render(s, {Terms::Multiple, {{"spp", 3072}}});
  auto mask = coverage_mask(s, voxelize(s, {.resolution = s.voxels}));
  EXPECT_LT(relative_norm(*ref.std_error, ref.image, mask), 0.05);
  PsfPipeline p(test::shared_gpu());
  RenderResult orders = p.render(s, {Terms::Multiple, {}});
  EXPECT_NE(orders.plan.stages[3].reason.find("model 1"), std::string::npos);
  EXPECT_NE(orders.plan.stages[3].reason.find("collisions conserved"), std::string::npos);
  for (float x : orders.image.rgb) ASSERT_TRUE(std::isfinite(x) && x >= 0.f);
  const double error = relative_rmse(orders.image, ref.image, mask);
  std::printf("orders: relative RMSE %.4f\n", error);
  EXPECT_LT(error, 0.15);  // measured 0.091 (24^2 pixels, 32 voxels)
  Image paper = p.render(s, {Terms::Multiple, {{"model", 0}}}).image;
  EXPECT_GT(relative_rmse(paper, ref.image, mask), 0.3);
  // A homogeneous medium: conserve's scale is one but where the coarse cells and the mesh part.
  Image capped = p.render(s, {Terms::Multiple, {{"conserve", 0}}}).image;
  EXPECT_LT(relative_rmse(capped, orders.image, mask), 0.01);
}

TEST(PsfPipeline, LayersMultipleTermIsNearTheReference) {
  // Thin dense and sparse layers (b 4 and 0.4): conserve lets the sparse layers carry the light
  // that the capped orders lost there.
  Scene s = load_scene(test::source_path("scenes/layers.json"));
  s.width = s.height = 24;
  s.voxels = 32;
  RenderResult ref =
      make_pipeline("reference", test::shared_gpu())->render(s, {Terms::Multiple, {{"spp", 2048}}});
  auto mask = coverage_mask(s, voxelize(s, {.resolution = s.voxels}));
  EXPECT_LT(relative_norm(*ref.std_error, ref.image, mask), 0.05);
  PsfPipeline p(test::shared_gpu());
  const double conserve = relative_rmse(p.render(s, {Terms::Multiple, {}}).image, ref.image, mask);
  const double capped =
      relative_rmse(p.render(s, {Terms::Multiple, {{"conserve", 0}}}).image, ref.image, mask);
  std::printf("layers: relative RMSE conserve %.4f, capped %.4f\n", conserve, capped);
  EXPECT_LT(conserve, 0.25);
  EXPECT_LT(conserve, capped - 0.05);
}

TEST(PsfPipeline, MultipleTermIsFiniteAndNonNegativeOnInhomogeneousScenes) {
  for (const char* name : {"sphere", "layers"}) {
    Scene s = load_scene(test::source_path(std::string("scenes/") + name + ".json"));
    s.width = s.height = 24;
    s.voxels = 24;
    PsfPipeline p(test::shared_gpu());
    Image m = p.render(s, {Terms::Multiple, {}}).image;
    double sum = 0;
    for (float v : m.rgb) {
      ASSERT_TRUE(std::isfinite(v)) << name;
      ASSERT_GE(v, 0.f) << name;
      sum += v;
    }
    EXPECT_GT(sum, 0) << name;
  }
}

TEST(PsfPipeline, KeepsLightVolumesAcrossCameraMovesAndRebuildsOnlyMovedLights) {
  Scene s = small_sphere();
  s.lights.push_back(s.lights[0]);
  s.lights[1].position = {-3, 2, 1};
  PsfPipeline p(test::shared_gpu());
  RenderResult first = p.render(s, {Terms::All, {}});
  EXPECT_EQ(p.light_builds(), 2);
  s.camera.position = {0.5, 0.2, 4};  // camera only
  RenderResult second = p.render(s, {Terms::All, {}});
  EXPECT_EQ(p.light_builds(), 2);
  ASSERT_GE(second.plan.stages.size(), 3u);
  EXPECT_EQ(second.plan.stages[0].name, "voxelize");
  EXPECT_FALSE(second.plan.stages[0].run);
  EXPECT_FALSE(second.plan.stages[1].run);  // light_volume
  EXPECT_FALSE(second.plan.stages[2].run);  // pyramid
  s.lights[1].position = {-3, 2, 2};        // one light moves
  RenderResult third = p.render(s, {Terms::All, {}});
  EXPECT_EQ(p.light_builds(), 3);
  EXPECT_NE(third.plan.stages[1].reason.find("1 of 2 lights"), std::string::npos)
      << third.plan.stages[1].reason;
  // The same frame from a fresh pipeline: reusing volumes changes nothing.
  PsfPipeline fresh(test::shared_gpu());
  Image again = fresh.render(s, {Terms::All, {}}).image;
  ASSERT_EQ(again.rgb.size(), third.image.rgb.size());
  for (size_t i = 0; i < again.rgb.size(); ++i) ASSERT_FLOAT_EQ(again.rgb[i], third.image.rgb[i]);
}

// The plan's orders stage says what render() does with model 1's orders: built for a light that
// has a volume but no orders yet (a single-term frame first), reused for a camera-only change,
// built again when an order setting changed.
TEST(PsfPipeline, ThePlanSaysWhenTheOrdersAreBuilt) {
  Scene s = small_sphere();
  PsfPipeline p(test::shared_gpu());
  auto orders = [](const RenderResult& r) {
    for (const StagePlan& st : r.plan.stages)
      if (st.name == "orders") return st;
    return StagePlan{};
  };
  p.render(s, {Terms::Single, {}});  // the light's volume, no orders
  StagePlan first = orders(p.render(s, {Terms::Multiple, {}}));
  EXPECT_TRUE(first.run) << first.reason;
  EXPECT_NE(first.reason.find("1 of 1 lights"), std::string::npos) << first.reason;
  StagePlan kept = orders(p.render(s, {Terms::Multiple, {}}));
  EXPECT_FALSE(kept.run) << kept.reason;
  StagePlan other = orders(p.render(s, {Terms::Multiple, {{"flights", 1}}}));
  EXPECT_TRUE(other.run) << other.reason;
}

TEST(PsfPipeline, SpotLightsLightOnlyInsideTheirCone) {
  Scene s = small_sphere();
  Light spot;
  spot.type = Light::Type::Spot;
  spot.position = {0, 0, 3};
  spot.intensity = 20;
  spot.inner_deg = 10;
  spot.outer_deg = 15;
  auto total = [&](Vec3 direction) {
    s.lights = {spot};
    s.lights[0].direction = direction;
    PsfPipeline p(test::shared_gpu());
    double sum = 0;
    for (float v : p.render(s, {Terms::All, {}}).image.rgb) sum += v;
    return sum;
  };
  double at = total({0, 0, -1}), away = total({0, 0, 1});
  EXPECT_GT(at, 0);
  EXPECT_EQ(away, 0);  // the cone misses the sphere: no light reaches any voxel
  // A point light of the same intensity at the same place lights at least as much.
  s.lights = {spot};
  s.lights[0].type = Light::Type::Point;
  PsfPipeline p(test::shared_gpu());
  double point = 0;
  for (float v : p.render(s, {Terms::All, {}}).image.rgb) point += v;
  EXPECT_GT(point, at);
}

TEST(PsfPipeline, SkipsTheMultipleTermInAnOpticallyThinMedium) {
  Scene s = small_sphere();
  s.medium.sigma_s = {0.005, 0.005, 0.005};
  PsfPipeline p(test::shared_gpu());
  RenderResult r = p.render(s, {Terms::Multiple, {}});
  bool said = false;
  for (const auto& st : r.plan.stages)
    if (st.name == "march_multiple")
      said = !st.run && st.reason.find("optically thin") != std::string::npos;
  EXPECT_TRUE(said);
  for (float v : r.image.rgb) ASSERT_EQ(v, 0.f);
  EXPECT_LT(p.scattering_thickness(), 0.05);
}

TEST(PsfPipeline, RefusesWhatItCannotRender) {
  Scene s = small_sphere();
  PsfPipeline p(test::shared_gpu());
  EXPECT_THROW(p.render(s, {Terms::Surface, {}}), ValidationError);
  EXPECT_THROW(p.render(s, {Terms::All, {{"atten", 3}}}), ValidationError);
  EXPECT_THROW(p.render(s, {Terms::All, {{"spp", 4}}}), ValidationError);
  EXPECT_THROW(p.render(s, {Terms::All, {{"step", 0}}}), ValidationError);
  // 512^3 voxels and 16 lights: about 160 GiB of volumes; refused before anything is allocated
  // (by render(): plan() is pure and knows no device).
  s.voxels = 512;
  s.lights.assign(16, s.lights[0]);
  EXPECT_NO_THROW(p.plan(s, {Terms::All, {}}));
  try {
    p.render(s, {Terms::All, {}});
    FAIL() << "no error";
  } catch (const ValidationError& e) {
    EXPECT_NE(std::string(e.what()).find("device memory"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace scatter
