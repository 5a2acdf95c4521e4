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
