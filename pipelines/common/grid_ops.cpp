#include "pipelines/common/grid_ops.hpp"

#include "pipelines/common/cl_library.hpp"

namespace scatter {

BrickGrid brick_majorants(gpu::ClContext& cl, const VoxelGrid& grid, int brick) {
  BrickGrid out;
  out.brick = brick;
  out.bx = (grid.nx + brick - 1) / brick;
  out.by = (grid.ny + brick - 1) / brick;
  out.bz = (grid.nz + brick - 1) / brick;
  size_t bricks = size_t(out.bx) * out.by * out.bz;
  out.majorant.resize(bricks);
  auto& ctx = cl.context();
  // The grid is only read by the kernel; copy it in at creation.
  cl::Buffer ss(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, grid.sigma_s.size() * sizeof(float),
                const_cast<float*>(grid.sigma_s.data()));
  cl::Buffer sa(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, grid.sigma_a.size() * sizeof(float),
                const_cast<float*>(grid.sigma_a.data()));
  cl::Buffer maj(ctx, CL_MEM_WRITE_ONLY, bricks * sizeof(float));
  cl::Kernel kernel(cl.program({"kernels/common/grid.cl"}), "brick_majorant");
  gpu::set_args(kernel, ss, sa, grid.nx, grid.ny, grid.nz, brick, out.bx, out.by, out.bz, maj);
  cl.queue().enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(bricks));
  cl.queue().enqueueReadBuffer(maj, CL_TRUE, 0, bricks * sizeof(float), out.majorant.data());
  return out;
}

std::vector<float> bounded_optical_depths(gpu::ClContext& cl, const VoxelGrid& grid,
                                          const BoundedExtinction& bounded,
                                          const std::vector<float>& rays) {
  const int count = int(rays.size() / 7);
  std::vector<float> out(3 * size_t(count));
  if (count == 0) return out;
  auto& ctx = cl.context();
  auto in = [&](const std::vector<float>& v) {
    return cl::Buffer(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, v.size() * sizeof(float),
                      const_cast<float*>(v.data()));
  };
  cl::Buffer st = in(bounded.sigma_t), bound = in(bounded.plane), ray = in(rays);
  cl::Buffer depths(ctx, CL_MEM_WRITE_ONLY, out.size() * sizeof(float));
  cl::Kernel kernel(cl.program(with_cl_library({"kernels/common/depth_query.cl"})),
                    "bounded_depths");
  cl_float3 origin{{float(grid.origin.x), float(grid.origin.y), float(grid.origin.z)}};
  gpu::set_args(kernel, origin, float(grid.voxel), grid.nx, grid.ny, grid.nz, st, bound, ray, count,
                depths);
  cl.queue().enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(size_t(count)));
  cl.queue().enqueueReadBuffer(depths, CL_TRUE, 0, out.size() * sizeof(float), out.data());
  return out;
}

}  // namespace scatter
