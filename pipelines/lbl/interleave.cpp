#include "pipelines/lbl/interleave.hpp"

#include "pipelines/common/cl_library.hpp"

namespace scatter::lbl {

InterleaveResult march_interleaved(gpu::ClContext& cl, const ClVolume& v, const cl::Buffer& rays,
                                   int count, bool bend, double step, double cutoff, double g,
                                   cl::Buffer& deposit, cl::Buffer& source, Lattice& lattice, int k,
                                   int lattice_steps, cl::Buffer* flow) {
  InterleaveResult r;
  if (count == 0) return r;
  auto& queue = cl.queue();
  cl::Program& program =
      cl.program(with_cl_library({"kernels/lbl/common.cl", "kernels/lbl/march.cl"}));
  cl::Buffer state(cl.context(), CL_MEM_READ_WRITE, size_t(count) * 16 * sizeof(float));
  cl::Buffer alive(cl.context(), CL_MEM_READ_WRITE, sizeof(cl_int));
  cl::Kernel start(program, "march_start"), round(program, "march_round");
  gpu::set_args(start, v.origin, v.voxel, v.nx, v.ny, v.nz, v.n, rays, count, float(cutoff), state);
  queue.enqueueNDRangeKernel(start, cl::NullRange, cl::NDRange(size_t(count)));
  gpu::set_args(round, v.origin, v.voxel, v.nx, v.ny, v.nz, v.sigma_s, v.sigma_t, v.n, v.grad,
                count, bend ? 1 : 0, float(step), k, float(g), state, deposit, source,
                flow ? *flow : deposit, flow ? 1 : 0, alive);
  // A ray crosses the grid's diagonal in at most this many rounds (bent ones a few times more).
  const int bound = static_cast<int>(4.0 * (v.nx + v.ny + v.nz) * v.voxel / step / k) + 8;
  cl_int live = 1;
  while (live > 0 && r.rounds < bound) {
    queue.enqueueFillBuffer(alive, cl_int(0), 0, sizeof(cl_int));
    queue.enqueueNDRangeKernel(round, cl::NullRange, cl::NDRange(size_t(count)));
    queue.enqueueReadBuffer(alive, CL_TRUE, 0, sizeof(cl_int), &live);
    ++r.rounds;
    lattice.set_source(source);
    r.lattice_steps += lattice.step(lattice_steps);
  }
  return r;
}

}  // namespace scatter::lbl
