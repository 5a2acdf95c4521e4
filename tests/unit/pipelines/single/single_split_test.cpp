// The single bake's weight solve (weight_fit) and its split at extinction jumps (split,
// pipelines/single/single_split.cpp), on the layers scene (sigma_s jumps 10x every 0.25 along y).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "../../test_util.hpp"
#include "pipelines/single/bake_support.hpp"
#include "scene/scene.hpp"
#include "single_fixture.hpp"

namespace scatter {
namespace {

using namespace single_test;

Scene layers(int voxels = 32) {
  Scene s = load_scene(test::source_path("scenes/layers.json"));
  s.voxels = voxels;
  return s;
}

SingleBake bake_layers(const VoxelGrid& grid, double split, int sigma_fit = 0,
                       int weight_fit = 20) {
  SingleBakeParams p;
  p.samples = 6000;
  p.directions = 32;
  p.split = split;
  p.sigma_fit = sigma_fit;
  p.weight_fit = weight_fit;
  return bake_single(test::shared_gpu().cl(), grid, p);
}

bool on_side(const SingleBake& b, int i, const Vec3& x) {
  const float* pl = &b.plane[4 * size_t(i)];
  return pl[0] * x.x + pl[1] * x.y + pl[2] * x.z <= pl[3];
}

std::vector<Vec3> interior_points(int n) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.9, 0.9);
  std::vector<Vec3> points(n);
  for (Vec3& x : points) x = {u(rng), u(rng), u(rng)};
  return points;
}

// The least-squares iterations make the Gaussians' sum flatter than the multiplicative passes.
TEST(SingleSplit, WeightFitFlattensTheSum) {
  Scene s = small_sphere(32, 32);
  VoxelGrid grid = voxelize(s, {.resolution = s.voxels, .margin = kSingleGridMargin});
  SingleBakeParams p;
  p.samples = 6000;
  p.directions = 16;
  p.weight_fit = 0;
  SingleBake passes = bake_single(test::shared_gpu().cl(), grid, p);
  p.weight_fit = 20;
  SingleBake fitted = bake_single(test::shared_gpu().cl(), grid, p);
  std::printf("coverage spread %.4f (passes) -> %.4f (weight_fit 20)\n", passes.coverage_spread,
              fitted.coverage_spread);
  EXPECT_NEAR(fitted.coverage_mean, 1.0, 0.02);
  // Measured on scenes/layers.json's box at 64^3: 0.089 -> 0.064.
  EXPECT_LT(fitted.coverage_spread, 0.9 * passes.coverage_spread);
}

// Split pieces come in pairs with opposite planes, so the sum of the Gaussians is unchanged, and
// the layers' planes are the layers' interfaces (normal along y).
TEST(SingleSplit, PiecesPartitionEachGaussianAlongTheInterface) {
  Scene s = layers();
  VoxelGrid grid = voxelize(s, {.resolution = s.voxels, .margin = kSingleGridMargin});
  SingleBake whole = bake_layers(grid, 0), split = bake_layers(grid, 2);
  ASSERT_EQ(whole.count, 6000);
  ASSERT_GT(split.split, 1000);  // most samples lie within 3 sigma of an interface
  ASSERT_EQ(split.count, 6000 + split.split);
  ASSERT_EQ(split.plane.size(), size_t(split.count) * 4);
  int along_y = 0, planes = 0;
  for (int i = 0; i < 6000; ++i) {
    const float* pl = &split.plane[4 * size_t(i)];
    if (pl[0] == 0 && pl[1] == 0 && pl[2] == 0) continue;
    ++planes;
    EXPECT_NEAR(pl[0] * pl[0] + pl[1] * pl[1] + pl[2] * pl[2], 1.0, 1e-5);
    Vec3 c{split.position[3 * i], split.position[3 * i + 1], split.position[3 * i + 2]};
    EXPECT_TRUE(on_side(split, i, c)) << "a sample keeps its own centre's side";
    if (std::abs(pl[1]) > 0.995) {
      ++along_y;
      // The interfaces lie at multiples of 0.25 (scenes/layers.json), within a voxel.
      double y =
          (pl[3] - pl[0] * c.x - pl[2] * c.z) / pl[1];  // the plane's height above the centre
      EXPECT_NEAR(y, std::round(y / 0.25) * 0.25, 2.0 / 32) << "sample " << i;
    }
  }
  EXPECT_EQ(planes, split.split);
  EXPECT_GT(along_y, 0.9 * planes);
  for (const Vec3& x : interior_points(200))
    EXPECT_NEAR(gaussian_sum(split, x), gaussian_sum(whole, x), 1e-4)
        << x.x << " " << x.y << " " << x.z;
}

// Each side keeps its own scattering coefficient: the splatted field follows the jumps far
// better than one Gaussian carrying a mean across them (no sigma_fit passes in either).
TEST(SingleSplit, SplattedFieldKeepsTheJumps) {
  Scene s = layers();
  VoxelGrid grid = voxelize(s, {.resolution = s.voxels, .margin = kSingleGridMargin});
  auto error = [&](double split) { return splatted_sigma_s_error(s, bake_layers(grid, split)); };
  double whole = error(0), split = error(2);
  std::printf("splatted sigma_s: relative RMSE %.3f (whole) -> %.3f (split)\n", whole, split);
  EXPECT_LT(split, 0.7 * whole);
}

// The rendered term: the split (with the splat's clip at each piece's plane) is closer to the
// reference marcher than whole Gaussians; a clip on the wrong side would lose half the light.
TEST_F(SinglePipelineTest, SplitBringsLayersCloserToTheReference) {
  Scene s = layers();
  s.width = s.height = 64;
  Expected expected = reference_single(s);
  auto error = [&](double split) {
    Settings set = {{"samples", 6000}, {"directions", 32}, {"split", split}};
    Image img = pipeline().render(s, {Terms::Single, set, nullptr}).image;
    EXPECT_NEAR(mean_ratio(img, expected.image), 1.0, 0.1) << "split " << split;
    return relative_rmse(img, expected.image, expected.mask);
  };
  double whole = error(0), split = error(2);
  std::printf("layers 32^3 at 6000 samples: relative RMSE %.4f (whole) -> %.4f (split)\n", whole,
              split);
  EXPECT_LT(split, 0.9 * whole);
}

// One-voxel layers of density 1, 0, 0.001, 0.5 (10 mean free paths a voxel in the densest), the
// stress suite's mixed/102, sampled coarser than the layers (200 samples, 8^3 voxels): Gaussians
// a voxel and a half wide reach across two interfaces. The empty layer must stay nearly empty:
// a piece on its side takes sigma_s only from its own side's medium (not the dense layer beyond),
// samples centred in it and the shell's samples split too, and the planes lie along the layers.
TEST(SingleSplit, EmptyLayerStaysEmptyUnderCoarseSamples) {
  const nlohmann::json j = {
      {"mesh", {{"shape", "box"}, {"size", {2, 2, 2}}}},
      {"medium",
       {{"sigma_s", 20},
        {"sigma_a", 20},
        {"g", 0},
        {"density",
         {{"type", "layers"},
          {"axis", {0, 1, 0}},
          {"thickness", 0.25},
          {"values", {1, 0, 0.001, 0.5}}}}}},
      {"lights", {{{"type", "directional"}, {"direction", {0, 0, -1}}, {"irradiance", 1}}}},
      {"camera", {{"position", {0, 0, 4}}, {"target", {0, 0, 0}}}},
      {"image", {{"width", 16}, {"height", 16}}},
      {"voxels", 8}};
  Scene s = parse_scene(j, ".");
  VoxelGrid grid = voxelize(s, {.resolution = s.voxels, .margin = kSingleGridMargin});
  SingleBakeParams p;
  p.samples = 200;
  p.directions = 8;
  SingleBake b = bake_single(test::shared_gpu().cl(), grid, p);
  ASSERT_GT(b.split, 0);
  // The empty layers (values[1], y in [-0.75, -0.5] and [0.25, 0.5]) away from their interfaces.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.95, 0.95), v(0.05, 0.2);
  double empty = 0, dense = 0;
  for (int k = 0; k < 400; ++k) {
    const double y0 = k % 2 ? -0.75 : 0.25;
    empty += splatted_sigma_s(b, {u(rng), y0 + v(rng), u(rng)});
    dense += splatted_sigma_s(b, {u(rng), y0 - 0.25 + v(rng), u(rng)});  // values[0]
  }
  std::printf("splatted sigma_s: empty layers %.4f, dense layers %.4f (truth 0, 20)\n", empty / 400,
              dense / 400);
  EXPECT_GT(dense / 400, 0.6 * 20);
  // Before the empty layer's own split and the pieces' own media: 3.15 (16 % of the dense
  // layer's), now 0.74.
  EXPECT_LT(empty / 400, 0.06 * 20);
  // Every piece measures its transmittance from inside the medium (a shell sample's new piece
  // moves with its anchor), on its own side of its plane in its anchor's frame (where the shading
  // tests its differences), and a medium sample's plane lies along the layers (a shell sample's,
  // outside an edge of the box, sees few voxels; the mesh clips it anyway).
  const std::vector<float> frame = single_detail::depth_frame_planes(b);
  int medium_planes = 0, along = 0;
  for (int i = 0; i < b.count; ++i) {
    const Vec3 a{b.depth_at[3 * size_t(i)], b.depth_at[3 * size_t(i) + 1],
                 b.depth_at[3 * size_t(i) + 2]};
    EXPECT_GT(grid.occupancy[single_detail::voxel_at(grid, a)], 0.f) << "piece " << i;
    const float* pl = &b.plane[4 * size_t(i)];
    if (pl[0] == 0 && pl[1] == 0 && pl[2] == 0) continue;
    const float* f = &frame[4 * size_t(i)];
    EXPECT_LE(f[0] * a.x + f[1] * a.y + f[2] * a.z, f[3] + 1e-4) << "piece " << i;
    const Vec3 c{b.position[3 * size_t(i)], b.position[3 * size_t(i) + 1],
                 b.position[3 * size_t(i) + 2]};
    if (std::max({std::abs(c.x), std::abs(c.y), std::abs(c.z)}) < 1) {
      ++medium_planes;
      if (std::abs(pl[1]) > 0.995) ++along;
    }
  }
  EXPECT_GT(medium_planes, b.split / 2);
  EXPECT_GE(along, 0.9 * medium_planes);
}

}  // namespace
}  // namespace scatter
