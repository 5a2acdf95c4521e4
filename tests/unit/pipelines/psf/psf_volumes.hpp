// Random RGB volumes for the psf tests, and their upload as float4 per voxel.
#pragma once

#include <random>

#include "gpu/cl_context.hpp"
#include "pipelines/psf/psf_model.hpp"

namespace scatter::psf::test_volumes {

inline Volume3 random_volume(int nx, int ny, int nz, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0, 1);
  Volume3 v{nx, ny, nz, {}};
  v.rgb.resize(size_t(nx) * ny * nz * 3);
  for (float& x : v.rgb) x = u(rng);
  return v;
}

inline cl::Buffer upload4(gpu::ClContext& cl, const Volume3& v) {
  std::vector<cl_float4> d(v.rgb.size() / 3);
  for (size_t i = 0; i < d.size(); ++i)
    d[i] = cl_float4{{v.rgb[3 * i], v.rgb[3 * i + 1], v.rgb[3 * i + 2], 0}};
  return cl::Buffer(cl.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                    d.size() * sizeof(cl_float4), d.data());
}

}  // namespace scatter::psf::test_volumes
