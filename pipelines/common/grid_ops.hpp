// Voxel-grid operations that run in OpenCL (kernels/common/grid.cl), on the voxelizer's grid.
#pragma once

#include <vector>

#include "gpu/cl_context.hpp"
#include "scene/voxelizer.hpp"

namespace scatter {

struct BrickGrid {
  int brick = 8;  // voxels per brick side
  int bx = 0, by = 0, bz = 0;
  std::vector<float> majorant;  // per brick, x fastest: max extinction over brick + apron
};

// Per-brick extinction majorants for delta tracking; empty bricks get 0 and can be skipped.
BrickGrid brick_majorants(gpu::ClContext& cl, const VoxelGrid& grid, int brick = 8);

}  // namespace scatter
