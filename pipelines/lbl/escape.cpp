#include "pipelines/lbl/escape.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "pipelines/common/cl_library.hpp"
#include "pipelines/common/cl_scene.hpp"

namespace scatter::lbl {

namespace {

bool scatters(const Volume& v, size_t voxel) {
  const float* s = &v.sigma_s[3 * voxel];
  return s[0] > 0 || s[1] > 0 || s[2] > 0;
}

// A sample stands for a voxel when it scatters and its medium is within kSimilar of the voxel's
// (sum of sigma_t' over channels): P is smooth inside one medium, not across a surface, a
// blocker or a density step.
constexpr double kSimilar = 0.25;

// The samples with weight in voxel c's interpolation: (sample index, its voxel), or false when
// one falls outside the grid.
bool corners_of(const Volume& v, const std::array<int, 3>& n, int stride, const int (&c)[3],
                std::vector<std::pair<size_t, size_t>>& out) {
  const int dims[3] = {v.nx, v.ny, v.nz};
  out.clear();
  for (int corner = 0; corner < 8; ++corner) {
    int s[3], q[3];
    bool weighted = true, inside = true;
    for (int a = 0; a < 3; ++a) {
      int up = (corner >> a) & 1;
      weighted = weighted && !(up && c[a] % stride == 0);
      s[a] = c[a] / stride + up;
      q[a] = stride * s[a];
      inside = inside && s[a] < n[a] && q[a] < dims[a];
    }
    if (!weighted) continue;
    if (!inside) return false;
    out.push_back({(size_t(s[2]) * n[1] + s[1]) * n[0] + s[0], v.index(q[0], q[1], q[2])});
  }
  return true;
}

}  // namespace

EscapeSampling escape_sampling(const Volume& v, const std::vector<float>& scaled, int stride) {
  EscapeSampling e;
  e.n = {(v.nx - 1) / stride + 1, (v.ny - 1) / stride + 1, (v.nz - 1) / stride + 1};
  e.mode.assign(v.count(), 0);
  auto medium = [&](size_t i) {
    return double(scaled[3 * i]) + scaled[3 * i + 1] + scaled[3 * i + 2];
  };
  std::vector<std::pair<size_t, size_t>> corners;
  for (int k = 0; k < v.nz; ++k)
    for (int j = 0; j < v.ny; ++j)
      for (int i = 0; i < v.nx; ++i) {
        const size_t voxel = v.index(i, j, k);
        if (!scatters(v, voxel)) continue;
        const double own = medium(voxel);
        bool all = corners_of(v, e.n, stride, {i, j, k}, corners);
        for (auto [sample, at] : corners)
          all = all && scatters(v, at) && std::abs(medium(at) - own) <= kSimilar * own;
        e.mode[voxel] = all ? 1 : 2;
      }
  std::vector<char> need(static_cast<size_t>(e.n[0]) * e.n[1] * e.n[2], 0);
  for (int k = 0; k < v.nz; ++k)
    for (int j = 0; j < v.ny; ++j)
      for (int i = 0; i < v.nx; ++i)
        if (e.mode[v.index(i, j, k)] == 1) {
          corners_of(v, e.n, stride, {i, j, k}, corners);
          for (auto [sample, at] : corners) need[sample] = 1;
        }
  for (size_t i = 0; i < need.size(); ++i)
    if (need[i]) e.samples.push_back(static_cast<cl_int>(i));
  return e;
}

std::vector<float> fibonacci_directions(int count) {
  // Evenly spread over the sphere, no axis preferred.
  std::vector<float> dirs;
  const double golden = std::numbers::pi * (3 - std::sqrt(5.0));
  for (int k = 0; k < count; ++k) {
    double z = 1 - (k + 0.5) * 2 / count, r = std::sqrt(std::max(0.0, 1 - z * z));
    dirs.insert(dirs.end(),
                {float(r * std::cos(golden * k)), float(r * std::sin(golden * k)), float(z)});
  }
  return dirs;
}

std::vector<float> coarse_sigma(const Volume& v, const std::vector<float>& scaled) {
  const int cx = (v.nx + 1) / 2, cy = (v.ny + 1) / 2, cz = (v.nz + 1) / 2;
  std::vector<double> sum(3 * size_t(cx) * cy * cz, 0.0);
  for (int k = 0; k < v.nz; ++k)
    for (int j = 0; j < v.ny; ++j)
      for (int i = 0; i < v.nx; ++i) {
        size_t cell = (size_t(k / 2) * cy + j / 2) * cx + i / 2, voxel = v.index(i, j, k);
        for (int ch = 0; ch < 3; ++ch) sum[3 * cell + ch] += scaled[3 * voxel + ch] / 8.0;
      }
  return std::vector<float>(sum.begin(), sum.end());
}

std::vector<float> exact_escape(gpu::ClContext& cl, const Volume& v, double g, int directions,
                                int stride, double far) {
  if (stride < 1) throw std::invalid_argument("escape stride must be at least 1");
  std::vector<float> dirs = fibonacci_directions(directions);
  std::vector<float> scaled(v.sigma_t.size());
  for (size_t i = 0; i < scaled.size(); ++i)
    scaled[i] = static_cast<float>(v.sigma_t[i] - g * v.sigma_s[i]);
  cl::Buffer st = upload(cl, scaled), ss = upload(cl, v.sigma_s), d = upload(cl, dirs);
  cl::Buffer out(cl.context(), CL_MEM_WRITE_ONLY, scaled.size() * sizeof(float));
  cl::Program& program = cl.program(with_cl_library({"kernels/lbl/escape.cl"}));
  cl_float3 origin{{float(v.origin.x), float(v.origin.y), float(v.origin.z)}};
  if (stride == 1) {
    cl::Kernel k(program, "escape_exact");
    gpu::set_args(k, origin, float(v.voxel), v.nx, v.ny, v.nz, st, ss, d, directions, out);
    cl.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(v.nx, v.ny, v.nz));
  } else {
    EscapeSampling e = escape_sampling(v, scaled, stride);
    cl::Buffer coarse = far > 0 ? upload(cl, coarse_sigma(v, scaled)) : st;
    cl::Buffer samples(cl.context(), CL_MEM_READ_WRITE,
                       std::max<size_t>(1, 3 * size_t(e.n[0]) * e.n[1] * e.n[2]) * sizeof(float));
    if (!e.samples.empty()) {
      cl::Buffer listed(cl.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                        e.samples.size() * sizeof(cl_int), e.samples.data());
      cl::Kernel k(program, "escape_samples");
      gpu::set_args(k, origin, float(v.voxel), v.nx, v.ny, v.nz, st, coarse, float(far), d,
                    directions, stride, e.n[0], e.n[1], listed, cl_int(e.samples.size()), samples);
      cl.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(e.samples.size()));
    }
    cl::Buffer mode(cl.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, e.mode.size(),
                    e.mode.data());
    cl::Kernel k(program, "escape_interpolate");
    gpu::set_args(k, origin, float(v.voxel), v.nx, v.ny, v.nz, st, coarse, float(far), mode, d,
                  directions, stride, e.n[0], e.n[1], samples, out);
    cl.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(v.nx, v.ny, v.nz));
  }
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
