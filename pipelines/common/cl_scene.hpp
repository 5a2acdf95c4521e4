// A scene's pieces in the layout the OpenCL kernels read (kernels/common/: lights.cl, camera.cl,
// dda.cl): lights (16 floats each), the camera (12 floats), and the voxel medium with per-brick
// majorants.
#pragma once

#include <vector>

#include "gpu/cl_context.hpp"
#include "pipelines/common/grid_ops.hpp"
#include "scene/scene.hpp"
#include "scene/voxelizer.hpp"

namespace scatter {

std::vector<float> pack_lights(const std::vector<Light>& lights);
// position, forward, right * tan(fov/2) * aspect, up * tan(fov/2).
std::vector<float> pack_camera(const Camera& camera, int width, int height);

struct ClMedium {
  cl::Buffer sigma_s, sigma_t, majorant;  // RGB interleaved per voxel; one majorant per brick
  BrickGrid bricks;
  cl_float3 origin{};
  float voxel = 0;
  int nx = 0, ny = 0, nz = 0;
};

ClMedium upload_medium(gpu::ClContext& cl, const VoxelGrid& grid, int brick = 8);

// A read-only device copy of host floats.
cl::Buffer upload(gpu::ClContext& cl, const std::vector<float>& data);

}  // namespace scatter
