#include "scene/voxelizer.hpp"

#include <gtest/gtest.h>

#include "../test_util.hpp"
#include "scene/solid.hpp"

namespace scatter {
namespace {

Scene scene_with(const nlohmann::json& mesh,
                 const nlohmann::json& density = {{"type", "constant"}}) {
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
  Scene s = scene_with(
      {{"shape", "torus"}, {"major_radius", 0.7}, {"minor_radius", 0.25}, {"axis", {0.3, 1, 0.2}}});
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
  EXPECT_NEAR(g.volume() / bunny.mesh->volume(), 1.0, 0.01);
}

TEST(Voxelizer, CoefficientsFollowDensityAndBlocker) {
  nlohmann::json box = {{"shape", "box"}, {"size", {2, 2, 2}}};
  nlohmann::json blocker = {{"type", "blocker"},
                            {"sigma_a", 500},
                            {"shape", {{"shape", "sphere"}, {"radius", 0.5}}},
                            {"inner", {{"type", "constant"}, {"value", 2.0}}}};
  Scene s = scene_with(box, blocker);
  VoxelGrid g = voxelize(s, {.resolution = 32});
  auto at = [&](Vec3 p) {
    Vec3 q = (p - g.origin) / g.voxel;
    return g.index(int(q.x), int(q.y), int(q.z));
  };
  size_t centre = at({0.01, 0.01, 0.01}), medium = at({0.8, 0.01, 0.01}),
         outside = at({1.02, 0, 0});
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

namespace scatter {
namespace {

Vec3 rotate(const Vec3& v, const Vec3& axis, double angle) {
  Vec3 k = normalize(axis);
  return v * std::cos(angle) + cross(k, v) * std::sin(angle) +
         k * dot(k, v) * (1 - std::cos(angle));
}

// Columns through the exact xy of vertices and edge midpoints: the line crosses shared edges and
// vertices, and each crossing must count once, or parity flips inside and outside.
TEST(MeshSolid, ColumnsThroughEdgesAndVerticesCountEachCrossingOnce) {
  Shape sphere;
  Mesh m = sphere.tessellate(32);
  for (auto& p : m.positions) p = rotate(p, {0.3, 0.5, 0.8}, 0.7);
  auto solid = make_mesh_solid(m);
  std::vector<Vec3> probes;
  for (size_t t = 0; t < m.indices.size(); t += 3)
    for (int e = 0; e < 3; ++e) {
      const Vec3& a = m.positions[m.indices[t + e]];
      const Vec3& b = m.positions[m.indices[t + (e + 1) % 3]];
      probes.push_back(a);
      probes.push_back((a + b) * 0.5);
    }
  int wrong = 0, tested = 0;
  std::vector<char> in;
  for (const Vec3& p : probes) {
    double r = std::hypot(p.x, p.y);
    if (r > 0.9) continue;  // near the silhouette the tessellation and the sphere differ
    solid->classify_column(p.x, p.y, {-2.0, 0.0, 2.0}, in);
    wrong += in != std::vector<char>{0, 1, 0};
    ++tested;
  }
  EXPECT_GT(tested, 1000);
  EXPECT_EQ(wrong, 0);
  // An axis-aligned box: the column x = y = 0 runs along the diagonal both caps are split on.
  Shape box;
  box.kind = Shape::Kind::Box;
  Mesh bm = box.tessellate();
  auto bs = make_mesh_solid(bm);
  bs->classify_column(0, 0, {-2.0, 0.0, 2.0}, in);
  EXPECT_EQ(in, (std::vector<char>{0, 1, 0}));
  bs->classify_column(1.0, 1.0, {0.0}, in);  // a corner edge of the box: on the boundary
  bs->classify_column(0.5, -0.5, {0.0, 1.5}, in);
  EXPECT_EQ(in, (std::vector<char>{1, 0}));
}

}  // namespace
}  // namespace scatter
