#include "pipelines/lbl/escape.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "pipelines/common/cl_library.hpp"
#include "pipelines/common/cl_scene.hpp"

namespace scatter::lbl {

std::vector<float> exact_escape(gpu::ClContext& cl, const Volume& v, double g, int directions) {
  // Directions on a Fibonacci spiral (evenly spread, no axis preferred).
  std::vector<float> dirs;
  const double golden = std::numbers::pi * (3 - std::sqrt(5.0));
  for (int k = 0; k < directions; ++k) {
    double z = 1 - (k + 0.5) * 2 / directions, r = std::sqrt(std::max(0.0, 1 - z * z));
    dirs.insert(dirs.end(),
                {float(r * std::cos(golden * k)), float(r * std::sin(golden * k)), float(z)});
  }
  std::vector<float> scaled(v.sigma_t.size());
  for (size_t i = 0; i < scaled.size(); ++i)
    scaled[i] = static_cast<float>(v.sigma_t[i] - g * v.sigma_s[i]);
  cl::Buffer st = upload(cl, scaled), ss = upload(cl, v.sigma_s), d = upload(cl, dirs);
  cl::Buffer out(cl.context(), CL_MEM_WRITE_ONLY, scaled.size() * sizeof(float));
  cl::Kernel k(cl.program(with_cl_library({"kernels/lbl/escape.cl"})), "escape_exact");
  cl_float3 origin{{float(v.origin.x), float(v.origin.y), float(v.origin.z)}};
  gpu::set_args(k, origin, float(v.voxel), v.nx, v.ny, v.nz, st, ss, d, directions, out);
  cl.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(v.nx, v.ny, v.nz));
  std::vector<float> p(scaled.size());
  cl.queue().enqueueReadBuffer(out, CL_TRUE, 0, p.size() * sizeof(float), p.data());
  return p;
}

std::vector<float> lattice_escape(const LatticeCoefficients& c) {
  const int dims[3] = {c.nx, c.ny, c.nz};
  const size_t stride[3] = {1, size_t(c.nx), size_t(c.nx) * c.ny};
  std::vector<double> sum(c.pt.size(), 0.0);
  // Along each axis line, a packet leaving node i towards +: the product of (1 - pt) over the
  // nodes after i (suffix products); towards -: over the nodes before i (prefix products).
  for (int axis = 0; axis < 3; ++axis) {
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    for (int u = 0; u < dims[a1]; ++u)
      for (int w = 0; w < dims[a2]; ++w) {
        size_t base = u * stride[a1] + w * stride[a2];
        for (int ch = 0; ch < 3; ++ch) {
          double keep = 1;
          for (int i = 0; i < dims[axis]; ++i) {  // prefix: nodes before i
            size_t node = base + i * stride[axis];
            sum[3 * node + ch] += keep;
            keep *= 1 - c.pt[3 * node + ch];
          }
          keep = 1;
          for (int i = dims[axis] - 1; i >= 0; --i) {  // suffix: nodes after i
            size_t node = base + i * stride[axis];
            sum[3 * node + ch] += keep;
            keep *= 1 - c.pt[3 * node + ch];
          }
        }
      }
  }
  std::vector<float> p(sum.size());
  for (size_t i = 0; i < p.size(); ++i) p[i] = static_cast<float>(sum[i] / 6);
  return p;
}

std::vector<float> escape_factor(const std::vector<float>& exact,
                                 const std::vector<float>& lattice) {
  std::vector<float> m(exact.size(), 1.f);
  for (size_t i = 0; i < m.size(); ++i) {
    double stay_lattice = 1 - double(lattice[i]);
    if (stay_lattice > 1e-6)
      m[i] = static_cast<float>(std::max(0.0, (1 - double(exact[i])) / stay_lattice));
  }
  return m;
}

}  // namespace scatter::lbl
