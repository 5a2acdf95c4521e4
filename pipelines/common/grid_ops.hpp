// Voxel-grid operations that run in OpenCL (kernels/common/grid.cl), on the voxelizer's grid.
#pragma once

#include <vector>

#include "gpu/cl_context.hpp"
#include "pipelines/common/boundary_planes.hpp"
#include "scene/voxelizer.hpp"

namespace scatter {

struct BrickGrid {
  int brick = 8;  // voxels per brick side
  int bx = 0, by = 0, bz = 0;
  std::vector<float> majorant;  // per brick, x fastest: max extinction over brick + apron
};

// Per-brick extinction majorants for delta tracking; empty bricks get 0 and can be skipped.
BrickGrid brick_majorants(gpu::ClContext& cl, const VoxelGrid& grid, int brick = 8);

// The RGB optical depths of rays (7 floats each: origin, unit direction, length) through the
// mesh-bounded medium `bounded` of `grid` (kernels/common/depth_query.cl, 3 floats a ray): what
// single's exact transmittance sums.
std::vector<float> bounded_optical_depths(gpu::ClContext& cl, const VoxelGrid& grid,
                                          const BoundedExtinction& bounded,
                                          const std::vector<float>& rays);

}  // namespace scatter
