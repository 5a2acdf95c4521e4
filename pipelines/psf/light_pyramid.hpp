// The `psf` pipeline's per-light precomputation on the device (Algorithm 1): the light volume
// (kernels/psf/light.cl) and the Gaussian pyramid of its scattered source (kernels/psf/pyramid.cl).
#pragma once

#include <vector>

#include "gpu/cl_context.hpp"
#include "pipelines/common/cl_scene.hpp"

namespace scatter::psf {

// The kernels of the psf pipeline, one program.
cl::Program& program(gpu::ClContext& cl);

struct Pyramid {
  cl::Buffer data;              // all levels, float4 per voxel, level after level
  cl::Buffer levels;            // int4 (offset in voxels, nx, ny, nz) per level
  cl::Buffer widths;            // float total blur width per level, world units
  std::vector<cl_int4> layout;  // the same, on the host
  std::vector<float> width;     // the same, on the host
  size_t voxels = 0;            // total over the levels
};

// Levels from (nx, ny, nz) halving (rounded up) until the longest side is at most 2.
std::vector<cl_int4> pyramid_layout(int nx, int ny, int nz);

// Builds the pyramid over `level0` (float4 per voxel, nx * ny * nz) whose voxels measure `voxel`.
Pyramid build_pyramid(gpu::ClContext& cl, const cl::Buffer& level0, int nx, int ny, int nz,
                      float voxel);

struct LightVolume {
  cl::Buffer l0, path, tau;  // see kernels/psf/light.cl
  Pyramid pyramid;
  double light_ms = 0, pyramid_ms = 0;  // what building it took
};

LightVolume build_light_volume(gpu::ClContext& cl, const ClMedium& medium, const cl::Buffer& lights,
                               int light);

}  // namespace scatter::psf
