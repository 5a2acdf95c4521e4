#include "pipelines/psf/light_pyramid.hpp"

#include <algorithm>
#include <chrono>

#include "pipelines/common/cl_library.hpp"
#include "pipelines/psf/psf_model.hpp"

namespace scatter::psf {
namespace {

double ms_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

cl::Buffer float4_buffer(gpu::ClContext& cl, size_t voxels) {
  return cl::Buffer(cl.context(), CL_MEM_READ_WRITE,
                    std::max<size_t>(voxels, 1) * sizeof(cl_float4));
}

cl::NDRange range(int nx, int ny, int nz) {
  return cl::NDRange(size_t(nx), size_t(ny), size_t(nz));
}

}  // namespace

cl::Program& program(gpu::ClContext& cl) {
  return cl.program(with_cl_library({"kernels/psf/light.cl", "kernels/psf/pyramid.cl",
                                     "kernels/psf/march.cl", "kernels/psf/orders.cl"}));
}

std::vector<cl_int4> pyramid_layout(int nx, int ny, int nz) {
  std::vector<cl_int4> out;
  int offset = 0;
  while (true) {
    out.push_back(cl_int4{{offset, nx, ny, nz}});
    offset += nx * ny * nz;
    if (std::max({nx, ny, nz}) <= 2) break;
    nx = (nx + 1) / 2;
    ny = (ny + 1) / 2;
    nz = (nz + 1) / 2;
  }
  return out;
}

Pyramid build_pyramid(gpu::ClContext& cl, const cl::Buffer& level0, int nx, int ny, int nz,
                      float voxel) {
  Pyramid p;
  p.layout = pyramid_layout(nx, ny, nz);
  const cl_int4& top = p.layout.back();
  p.voxels = size_t(top.s[0]) + size_t(top.s[1]) * top.s[2] * top.s[3];
  p.data = float4_buffer(cl, p.voxels);
  auto& queue = cl.queue();
  auto bytes = [](const cl_int4& l) {
    return size_t(l.s[1]) * l.s[2] * l.s[3] * sizeof(cl_float4);
  };
  queue.enqueueCopyBuffer(level0, p.data, 0, 0, bytes(p.layout[0]));
  cl::Kernel down(program(cl), "downsample_tent"), blur(program(cl), "blur_axis");
  cl::Buffer prev = level0;
  for (size_t k = 1; k < p.layout.size(); ++k) {
    const cl_int4 &f = p.layout[k - 1], &c = p.layout[k];
    size_t n = size_t(c.s[1]) * c.s[2] * c.s[3];
    cl::Buffer a = float4_buffer(cl, n), b = float4_buffer(cl, n);
    gpu::set_args(down, prev, f.s[1], f.s[2], f.s[3], a, c.s[1], c.s[2], c.s[3]);
    queue.enqueueNDRangeKernel(down, cl::NullRange, range(c.s[1], c.s[2], c.s[3]));
    std::vector<cl_float4> taps;  // the same Gaussian for every channel
    for (float t : gaussian_taps(level_sigma(static_cast<int>(k))))
      taps.push_back(cl_float4{{t, t, t, t}});
    cl::Buffer tap_buf(cl.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                       taps.size() * sizeof(cl_float4), taps.data());
    for (int axis = 0; axis < 3; ++axis) {
      gpu::set_args(blur, a, c.s[1], c.s[2], c.s[3], axis, tap_buf,
                    static_cast<int>(taps.size()) - 1, b);
      queue.enqueueNDRangeKernel(blur, cl::NullRange, range(c.s[1], c.s[2], c.s[3]));
      std::swap(a, b);
    }
    queue.enqueueCopyBuffer(a, p.data, 0, size_t(c.s[0]) * sizeof(cl_float4),
                            n * sizeof(cl_float4));
    prev = a;
  }
  for (size_t k = 0; k < p.layout.size(); ++k)
    p.width.push_back(static_cast<float>(level_width(static_cast<int>(k)) * voxel));
  p.levels = cl::Buffer(cl.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                        p.layout.size() * sizeof(cl_int4), p.layout.data());
  p.widths = cl::Buffer(cl.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                        p.width.size() * sizeof(float), p.width.data());
  queue.finish();
  return p;
}

LightVolume build_light_volume(gpu::ClContext& cl, const ClMedium& medium, const cl::Buffer& lights,
                               int light) {
  auto start = std::chrono::steady_clock::now();
  LightVolume v;
  const size_t n = size_t(medium.nx) * medium.ny * medium.nz;
  v.l0 = float4_buffer(cl, n);
  v.path = float4_buffer(cl, n);
  v.tau = float4_buffer(cl, n);
  auto& queue = cl.queue();
  cl::Kernel k(program(cl), "light_volume");
  gpu::set_args(k, medium.origin, medium.voxel, medium.nx, medium.ny, medium.nz, medium.sigma_s,
                medium.sigma_t, lights, light, v.l0, v.path, v.tau);
  queue.enqueueNDRangeKernel(k, cl::NullRange, range(medium.nx, medium.ny, medium.nz));
  cl::Buffer source = float4_buffer(cl, n);
  cl::Kernel src(program(cl), "scatter_source");
  gpu::set_args(src, static_cast<int>(n), medium.sigma_s, v.l0, source);
  queue.enqueueNDRangeKernel(src, cl::NullRange, cl::NDRange(n));
  queue.finish();
  v.light_ms = ms_since(start);
  start = std::chrono::steady_clock::now();
  v.pyramid = build_pyramid(cl, source, medium.nx, medium.ny, medium.nz, medium.voxel);
  v.pyramid_ms = ms_since(start);
  return v;
}

}  // namespace scatter::psf
