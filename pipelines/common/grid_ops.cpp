#include "pipelines/common/grid_ops.hpp"

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

}  // namespace scatter
