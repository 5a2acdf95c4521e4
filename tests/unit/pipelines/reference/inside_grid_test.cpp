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
