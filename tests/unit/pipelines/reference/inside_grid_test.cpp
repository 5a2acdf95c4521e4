#include "pipelines/reference/inside_grid.hpp"

#include <gtest/gtest.h>

namespace scatter {
namespace {

VoxelGrid row_of_three() {
  VoxelGrid g;
  g.nx = 3;
  g.ny = g.nz = 1;
  g.voxel = 1;
  g.occupancy = {1.0f, 0.25f, 0.0f};
  g.sigma_s = {2, 2, 2, 0.5f, 0.25f, 1, 0, 0, 0};
  g.sigma_a = {0.1f, 0.1f, 0.1f, 0.25f, 0.25f, 0.25f, 0, 0, 0};
  g.inside = {1, 0, 0};
  return g;
}

// A voxel's coefficients become their mean over its part inside the mesh; a full voxel keeps its
// own, and an empty one next to the mesh takes its occupied neighbours' mean.
TEST(RestrictToMesh, DividesByTheOccupancyAndFillsEmptyNeighbours) {
  VoxelGrid g = row_of_three();
  restrict_to_mesh(g);
  EXPECT_FLOAT_EQ(g.sigma_s[0], 2);
  EXPECT_FLOAT_EQ(g.sigma_s[3], 2);
  EXPECT_FLOAT_EQ(g.sigma_s[4], 1);
  EXPECT_FLOAT_EQ(g.sigma_s[5], 4);
  EXPECT_FLOAT_EQ(g.sigma_a[3], 1);
  // The empty voxel sees only the partly occupied one (its one occupied neighbour).
  EXPECT_FLOAT_EQ(g.sigma_s[6], 2);
  EXPECT_FLOAT_EQ(g.sigma_s[8], 4);
  EXPECT_FLOAT_EQ(g.sigma_a[7], 1);
  EXPECT_EQ(g.occupancy[2], 0.0f);  // the occupancy itself is not touched
}

}  // namespace
}  // namespace scatter

namespace scatter {
namespace {

// A 9^3 block of full voxels in an 11^3 grid with one partly occupied voxel in it: the centre is 3
// voxels (Chebyshev) from it, so 1 is safe (less one for the gap, one for a missed sliver).
TEST(InteriorDepth, IsTheChebyshevDistanceToTheBoundaryLessTwo) {
  VoxelGrid g;
  g.nx = g.ny = g.nz = 11;
  g.voxel = 1;
  g.occupancy.assign(g.count(), 0.0f);
  for (int k = 1; k < 10; ++k)
    for (int j = 1; j < 10; ++j)
      for (int i = 1; i < 10; ++i) g.occupancy[g.index(i, j, k)] = 1.0f;
  g.occupancy[g.index(5, 5, 2)] = 0.5f;  // a boundary voxel inside, below the centre
  std::vector<uint8_t> d = interior_depth(g);
  EXPECT_EQ(d[g.index(5, 5, 5)], 1);  // 3 voxels to (5, 5, 2)
  EXPECT_EQ(d[g.index(5, 5, 7)], 1);  // 3 to the outside at z = 10
  EXPECT_EQ(d[g.index(5, 5, 8)], 0);  // 2 to it
  EXPECT_EQ(d[g.index(1, 1, 1)], 0);
  EXPECT_EQ(d[g.index(0, 0, 0)], 0);
  EXPECT_EQ(d[g.index(5, 5, 3)], 0);
}

}  // namespace
}  // namespace scatter

namespace scatter {
namespace {

// An n^3 grid (4: of 2^3 bricks): a cube of medium in voxels 0-2 (the 3^3 corner), the rest
// empty.
VoxelGrid corner_cube(float sigma_s, int n = 4) {
  VoxelGrid g;
  g.nx = g.ny = g.nz = n;
  g.voxel = 1;
  g.occupancy.assign(g.count(), 0.0f);
  g.sigma_s.assign(3 * g.count(), 0.0f);
  g.sigma_a.assign(3 * g.count(), 0.0f);
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i) {
        size_t v = g.index(i, j, k);
        g.occupancy[v] = 1.0f;
        for (int c = 0; c < 3; ++c) {
          g.sigma_s[3 * v + c] = sigma_s;
          g.sigma_a[3 * v + c] = 0.1f;
        }
      }
  return g;
}

// Bounded by the mesh, a brick is uniform when the voxels a segment inside can reach (those
// inside or next to it) agree; the voxelized medium alone counts the empty voxels too.
TEST(UniformBricks, NameAVoxelOfTheBricksOneCoefficient) {
  VoxelGrid g = corner_cube(2.0f);
  std::vector<int32_t> mesh = uniform_bricks(g, 2, true);
  ASSERT_EQ(mesh.size(), 8u);
  EXPECT_EQ(mesh[0], 0);  // brick (0, 0, 0): all inside, voxel 0's coefficients
  // Brick (1, 0, 0) holds voxels x 2-3: x 2 inside, x 3 next to it but empty (0): not uniform.
  EXPECT_EQ(mesh[1], -1);
  // Brick (1, 1, 1) holds voxel (2, 2, 2) inside and empty ones next to it.
  EXPECT_EQ(mesh[7], -1);
  // Once restrict_to_mesh has filled the empty neighbours, the medium is one coefficient.
  restrict_to_mesh(g);
  mesh = uniform_bricks(g, 2, true);
  for (int32_t u : mesh) EXPECT_GE(u, 0);
  // Without the mesh, the empty voxels far from it are medium too (zero) and differ.
  VoxelGrid bare = corner_cube(2.0f);
  std::vector<int32_t> voxels = uniform_bricks(bare, 2, false);
  EXPECT_EQ(voxels[0], 0);
  EXPECT_EQ(voxels[7], -1);
  // One voxel a float32 rounding apart still counts as the same; one 1e-4 apart does not.
  bare.sigma_s[3 * bare.index(1, 1, 1)] = 2.0f * (1 + 2e-7f);
  EXPECT_EQ(uniform_bricks(bare, 2, false)[0], 0);
  bare.sigma_s[3 * bare.index(1, 1, 1)] = 2.0f * (1 + 1e-4f);
  EXPECT_EQ(uniform_bricks(bare, 2, false)[0], -1);
}

// The whole medium is one coefficient when every brick a segment may reach is uniform with the
// same one; bricks no segment reaches (-2) do not count.
TEST(UniformBricks, AConstantMediumInsideTheMeshIsHomogeneous) {
  VoxelGrid g = corner_cube(2.0f);
  EXPECT_EQ(homogeneous_voxel(g, uniform_bricks(g, 2, true)), -1);  // empty voxels next to it
  restrict_to_mesh(g);
  EXPECT_EQ(homogeneous_voxel(g, uniform_bricks(g, 2, true)), 0);
  VoxelGrid bare = corner_cube(2.0f);  // without the mesh the empty voxels are medium (zero)
  EXPECT_EQ(homogeneous_voxel(bare, uniform_bricks(bare, 2, false)), -1);
  // In a 6^3 grid, bricks of one voxel: (5, 5, 5) is three voxels from the cube, so no segment
  // inside reaches it.
  VoxelGrid big = corner_cube(2.0f, 6);
  restrict_to_mesh(big);
  std::vector<int32_t> single = uniform_bricks(big, 1, true);
  EXPECT_EQ(single[big.index(5, 5, 5)], -2);
  EXPECT_EQ(homogeneous_voxel(big, single), 0);
  // Another coefficient in one voxel inside: two media.
  big.sigma_s[3 * big.index(1, 1, 1)] = 3.0f;
  EXPECT_EQ(homogeneous_voxel(big, uniform_bricks(big, 2, true)), -1);
  EXPECT_EQ(homogeneous_voxel(big, uniform_bricks(big, 1, true)), -1);
}

}  // namespace
}  // namespace scatter
