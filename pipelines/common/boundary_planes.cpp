#include "pipelines/common/boundary_planes.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace scatter {

namespace {

// The offset w at which the fraction `occ` of the cube [-1/2, 1/2]^3 (voxel units) lies on the
// side n . x <= w: the occ-quantile of n . x over a k^3 lattice of the cube's points.
double plane_offset(const Vec3& n, double occ) {
  constexpr int k = 8;
  std::array<double, k * k * k> proj;
  int m = 0;
  for (int z = 0; z < k; ++z)
    for (int y = 0; y < k; ++y)
      for (int x = 0; x < k; ++x) {
        Vec3 p{(x + 0.5) / k - 0.5, (y + 0.5) / k - 0.5, (z + 0.5) / k - 0.5};
        proj[m++] = dot(n, p);
      }
  std::sort(proj.begin(), proj.end());
  // Each lattice point stands for 1/k^3 of the volume, centred on its projection: between the
  // neighbours' projections the fraction moves linearly.
  const double f = std::clamp(occ * m - 0.5, 0.0, double(m - 1));
  const int i = std::min(int(f), m - 2);
  const double t = f - i;
  double w = proj[i] + t * (proj[i + 1] - proj[i]);
  // At the ends, out to the cube's corner (all of it or none of it on the side).
  const double reach = 0.5 * (std::abs(n.x) + std::abs(n.y) + std::abs(n.z));
  if (occ * m < 0.5) w = proj[0] - (0.5 - occ * m) * 2 * (proj[0] + reach);
  if (occ * m > m - 0.5) w = proj[m - 1] + (occ * m - (m - 0.5)) * 2 * (reach - proj[m - 1]);
  return std::clamp(w, -reach, reach);
}

}  // namespace

BoundedExtinction bounded_extinction(const VoxelGrid& g) {
  BoundedExtinction out;
  const size_t n = g.count();
  out.sigma_t.resize(3 * n);
  out.plane.assign(4 * n, 0.f);
  for (size_t v = 0; v < 3 * n; ++v) out.sigma_t[v] = g.sigma_s[v] + g.sigma_a[v];
  if (g.occupancy.size() != n) return out;
  auto occ_at = [&](int i, int j, int k) {
    if (i < 0 || j < 0 || k < 0 || i >= g.nx || j >= g.ny || k >= g.nz) return 0.0;
    return double(g.occupancy[g.index(i, j, k)]);
  };
  for (int k = 0; k < g.nz; ++k)
    for (int j = 0; j < g.ny; ++j)
      for (int i = 0; i < g.nx; ++i) {
        const size_t v = g.index(i, j, k);
        const double occ = g.occupancy[v];
        if (!(occ > 0) || occ >= 1) continue;
        // The outward normal: minus the occupancy's gradient, weighted towards the face
        // neighbours (a Sobel-like stencil over the 26).
        Vec3 grad{0, 0, 0};
        for (int dk = -1; dk <= 1; ++dk)
          for (int dj = -1; dj <= 1; ++dj)
            for (int di = -1; di <= 1; ++di) {
              const int l1 = std::abs(di) + std::abs(dj) + std::abs(dk);
              if (l1 == 0) continue;
              const double w = l1 == 1 ? 4 : l1 == 2 ? 2 : 1;
              grad = grad + Vec3{double(di), double(dj), double(dk)} *
                                (w * occ_at(i + di, j + dj, k + dk));
            }
        const double len = std::sqrt(dot(grad, grad));
        if (!(len > 1e-9)) continue;  // no direction: the voxel's mean stands
        const Vec3 nrm = grad * (-1.0 / len);
        const double w = plane_offset(nrm, occ);
        float* p = &out.plane[4 * v];
        p[0] = float(nrm.x);
        p[1] = float(nrm.y);
        p[2] = float(nrm.z);
        p[3] = float(w * g.voxel);
        for (int c = 0; c < 3; ++c) out.sigma_t[3 * v + c] = float(out.sigma_t[3 * v + c] / occ);
        ++out.planes;
      }
  return out;
}

Vec3 inside_bound(const VoxelGrid& g, const BoundedExtinction& bounded, const Vec3& p) {
  const Vec3 q = (p - g.origin) / g.voxel;
  const int i = int(std::floor(q.x)), j = int(std::floor(q.y)), k = int(std::floor(q.z));
  if (i < 0 || j < 0 || k < 0 || i >= g.nx || j >= g.ny || k >= g.nz) return p;
  const float* pl = &bounded.plane[4 * g.index(i, j, k)];
  const Vec3 n{pl[0], pl[1], pl[2]};
  const double over = dot(n, p - g.center(i, j, k)) - pl[3];
  if (!(over > 0)) return p;  // inside, or no plane (n zero)
  return p - n * (over + 1e-3 * g.voxel);
}

}  // namespace scatter
