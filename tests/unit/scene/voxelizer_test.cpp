#include "scene/voxelizer.hpp"

#include <gtest/gtest.h>

#include "../test_util.hpp"
#include "scene/solid.hpp"

namespace scatter {
namespace {

Scene scene_with(const nlohmann::json& mesh, const nlohmann::json& density = {{"type", "constant"}}) {
  nlohmann::json s = test::minimal_scene();
  s["mesh"] = mesh;
  s["medium"]["density"] = density;
  return parse_scene(s, ".");
}

TEST(Voxelizer, SphereVolumeWithinOnePercentAt128) {
  Scene s = scene_with({{"shape", "sphere"}, {"radius", 0.9}});
  VoxelGrid g = voxelize(s, {.resolution = 128});
  double exact = 4.0 / 3 * M_PI * 0.9 * 0.9 * 0.9;
  EXPECT_NEAR(g.volume() / exact, 1.0, 0.01);
  EXPECT_EQ(g.nx, 130);
}

TEST(Voxelizer, TorusVolumeWithinOnePercentAt128) {
  Scene s = scene_with({{"shape", "torus"}, {"major_radius", 0.7}, {"minor_radius", 0.25},
                        {"axis", {0.3, 1, 0.2}}});
  VoxelGrid g = voxelize(s, {.resolution = 128});
  double exact = 2 * M_PI * M_PI * 0.7 * 0.25 * 0.25;
  EXPECT_NEAR(g.volume() / exact, 1.0, 0.01);
}

// The mesh path (parity along columns) on concave meshes: a tessellated torus and the bunny.
TEST(Voxelizer, ConcaveMeshesMatchTheirPolyhedralVolume) {
  Shape t;
  t.kind = Shape::Kind::Torus;
  t.axis = normalize(Vec3{1, 1, 0});
  Mesh torus = t.tessellate(96);
  auto solid = make_mesh_solid(torus);
  // The z axis lies in the torus's plane: outside in the hole, inside the tube at |z| = R, outside
  // beyond it.
  Vec3 u = normalize(cross(Vec3{0, 0, 1}, t.axis));
  std::vector<char> in;
  solid->classify_column(0, 0, {-0.6, 0.0, 0.6, 1.0}, in);
  EXPECT_EQ(in, (std::vector<char>{1, 0, 1, 0}));
  Vec3 tube = u * t.major_radius, above = tube + t.axis * 0.3;  // 0.3 > minor radius
  solid->classify_column(tube.x, tube.y, {tube.z}, in);
  EXPECT_EQ(in, std::vector<char>{1});
  solid->classify_column(above.x, above.y, {above.z}, in);
  EXPECT_EQ(in, std::vector<char>{0});

  Scene bunny = scene_with({{"file", "/usr/share/glmark2/models/bunny.obj"}, {"fit", 2.0}});
  VoxelGrid g = voxelize(bunny, {.resolution = 128});
  EXPECT_NEAR(g.volume() / bunny.mesh.volume(), 1.0, 0.01);
}

TEST(Voxelizer, CoefficientsFollowDensityAndBlocker) {
  nlohmann::json box = {{"shape", "box"}, {"size", {2, 2, 2}}};
  nlohmann::json blocker = {{"type", "blocker"}, {"sigma_a", 500},
                            {"shape", {{"shape", "sphere"}, {"radius", 0.5}}},
                            {"inner", {{"type", "constant"}, {"value", 2.0}}}};
  Scene s = scene_with(box, blocker);
  VoxelGrid g = voxelize(s, {.resolution = 32});
  auto at = [&](Vec3 p) {
    Vec3 q = (p - g.origin) / g.voxel;
    return g.index(int(q.x), int(q.y), int(q.z));
  };
  size_t centre = at({0.01, 0.01, 0.01}), medium = at({0.8, 0.01, 0.01}), outside = at({1.02, 0, 0});
  EXPECT_FLOAT_EQ(g.sigma_a[3 * centre], 500.f);
  EXPECT_FLOAT_EQ(g.sigma_s[3 * centre], 0.f);
  EXPECT_FLOAT_EQ(g.sigma_s[3 * medium], 2.f);  // sigma_s 1 times density 2
  EXPECT_FLOAT_EQ(g.sigma_a[3 * medium], 0.2f);
  EXPECT_FLOAT_EQ(g.occupancy[medium], 1.f);
  EXPECT_EQ(g.inside[outside], 0);
  EXPECT_FLOAT_EQ(g.sigma_s[3 * outside], 0.f);
  // Total mass of scatterers: density 2 over the box minus the blocker ball.
  double mass = 0;
  for (size_t v = 0; v < g.count(); ++v) mass += g.sigma_s[3 * v];
  mass *= g.voxel * g.voxel * g.voxel;
  EXPECT_NEAR(mass / (2.0 * (8 - 4.0 / 3 * M_PI * 0.125)), 1.0, 0.01);
}

TEST(Voxelizer, ThreadCountDoesNotChangeTheGrid) {
  Scene s = scene_with({{"shape", "torus"}}, {{"type", "noise"}});
  VoxelGrid a = voxelize(s, {.resolution = 24, .threads = 1});
  VoxelGrid b = voxelize(s, {.resolution = 24, .threads = 3});
  EXPECT_EQ(a.sigma_s, b.sigma_s);
  EXPECT_EQ(a.occupancy, b.occupancy);
}

}  // namespace
}  // namespace scatter
