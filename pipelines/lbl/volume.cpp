#include "pipelines/lbl/volume.hpp"

#include <algorithm>
#include <cmath>

#include "pipelines/common/cl_scene.hpp"

namespace scatter::lbl {
namespace {

int round_up(int v, int block) {
  return (v + block - 1) / block * block;
}

// One pass of a 1D Gaussian along `axis` with clamped edges.
std::vector<float> blur_axis(const Volume& v, const std::vector<float>& in, int axis,
                             const std::vector<double>& kernel) {
  const int r = static_cast<int>(kernel.size()) - 1;
  const int dims[3] = {v.nx, v.ny, v.nz};
  std::vector<float> out(in.size());
  for (int k = 0; k < v.nz; ++k)
    for (int j = 0; j < v.ny; ++j)
      for (int i = 0; i < v.nx; ++i) {
        int c[3] = {i, j, k};
        double s = 0;
        for (int o = -r; o <= r; ++o) {
          int q[3] = {c[0], c[1], c[2]};
          q[axis] = std::clamp(c[axis] + o, 0, dims[axis] - 1);
          s += kernel[std::abs(o)] * in[v.index(q[0], q[1], q[2])];
        }
        out[v.index(i, j, k)] = static_cast<float>(s);
      }
  return out;
}

}  // namespace

Volume make_volume(const VoxelGrid& grid, double ior, double smooth_voxels, int block) {
  Volume v;
  v.nx = round_up(grid.nx, block);
  v.ny = round_up(grid.ny, block);
  v.nz = round_up(grid.nz, block);
  v.origin = grid.origin;
  v.voxel = grid.voxel;
  v.sigma_s.assign(3 * v.count(), 0.f);
  v.sigma_t.assign(3 * v.count(), 0.f);
  v.occupancy.assign(v.count(), 0.f);
  for (int k = 0; k < grid.nz; ++k)
    for (int j = 0; j < grid.ny; ++j)
      for (int i = 0; i < grid.nx; ++i) {
        size_t s = grid.index(i, j, k), d = v.index(i, j, k);
        v.occupancy[d] = grid.occupancy[s];
        for (int c = 0; c < 3; ++c) {
          v.sigma_s[3 * d + c] = grid.sigma_s[3 * s + c];
          v.sigma_t[3 * d + c] = grid.sigma_s[3 * s + c] + grid.sigma_a[3 * s + c];
        }
      }
  std::vector<float> n(v.count());
  for (size_t i = 0; i < n.size(); ++i) n[i] = static_cast<float>(1 + (ior - 1) * v.occupancy[i]);
  set_index(v, std::move(n), smooth_voxels);
  return v;
}

void set_index(Volume& v, std::vector<float> n, double smooth_voxels) {
  v.constant_n = true;
  for (float x : n) v.constant_n = v.constant_n && x == n[0];
  if (smooth_voxels > 0 && !v.constant_n) {
    const int r = static_cast<int>(std::ceil(3 * smooth_voxels));
    std::vector<double> kernel(r + 1);
    double total = 0;
    for (int o = 0; o <= r; ++o) {
      kernel[o] = std::exp(-0.5 * o * o / (smooth_voxels * smooth_voxels));
      total += o == 0 ? kernel[o] : 2 * kernel[o];
    }
    for (double& k : kernel) k /= total;
    for (int axis = 0; axis < 3; ++axis) n = blur_axis(v, n, axis, kernel);
  }
  v.n = std::move(n);
  v.grad.assign(3 * v.count(), 0.f);
  if (v.constant_n) return;
  const int dims[3] = {v.nx, v.ny, v.nz};
  for (int k = 0; k < v.nz; ++k)
    for (int j = 0; j < v.ny; ++j)
      for (int i = 0; i < v.nx; ++i) {
        int c[3] = {i, j, k};
        for (int axis = 0; axis < 3; ++axis) {
          int lo[3] = {i, j, k}, hi[3] = {i, j, k};
          lo[axis] = std::max(c[axis] - 1, 0);
          hi[axis] = std::min(c[axis] + 1, dims[axis] - 1);
          double span = (hi[axis] - lo[axis]) * v.voxel;
          double d = v.n[v.index(hi[0], hi[1], hi[2])] - v.n[v.index(lo[0], lo[1], lo[2])];
          v.grad[3 * v.index(i, j, k) + axis] = span > 0 ? static_cast<float>(d / span) : 0.f;
        }
      }
}

LatticeCoefficients lattice_coefficients(const Volume& v, double g) {
  LatticeCoefficients c;
  c.nx = v.nx;
  c.ny = v.ny;
  c.nz = v.nz;
  for (auto* a : {&c.pt, &c.ps, &c.w, &c.pt_diag, &c.ps_diag, &c.w_diag}) a->resize(3 * v.count());
  auto fill = [&](double length, std::vector<float>& pt_out, std::vector<float>& ps_out,
                  std::vector<float>& w_out) {
    for (size_t i = 0; i < pt_out.size(); ++i) {
      double ss = v.sigma_s[i], sa = v.sigma_t[i] - ss;
      double ssr = (1 - g) * ss, str = ssr + sa;
      double x = str * length;
      double pt = -std::expm1(-x);
      // Mean path before a collision, (1 - exp(-x)) / sigma_t', tends to the length.
      double path = x > 1e-6 ? pt / str : length;
      pt_out[i] = static_cast<float>(pt);
      ps_out[i] = static_cast<float>(str > 0 ? pt * ssr / str : 0.0);
      w_out[i] = static_cast<float>(ss * path);
    }
  };
  fill(v.voxel, c.pt, c.ps, c.w);
  fill(std::sqrt(2.0) * v.voxel, c.pt_diag, c.ps_diag, c.w_diag);
  return c;
}

ClVolume upload_volume(gpu::ClContext& cl, const Volume& v) {
  ClVolume d;
  d.sigma_s = upload(cl, v.sigma_s);
  d.sigma_t = upload(cl, v.sigma_t);
  d.n = upload(cl, v.n);
  d.grad = upload(cl, v.grad);
  d.origin = {{float(v.origin.x), float(v.origin.y), float(v.origin.z)}};
  d.voxel = float(v.voxel);
  d.nx = v.nx;
  d.ny = v.ny;
  d.nz = v.nz;
  return d;
}

}  // namespace scatter::lbl
