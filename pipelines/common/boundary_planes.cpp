#include "pipelines/common/boundary_planes.hpp"

#include <algorithm>
#include <cmath>

namespace scatter {

namespace {

// The fraction of the cube [-1/2, 1/2]^3 (voxel units) on the side n . x <= w: along the axis a
// of n's largest component each column of the cube is cut at one point, so its fraction is
// exact; the columns are summed over a 16 x 16 lattice of the other two axes (the sum is
// piecewise linear in them: exact for a normal along an axis).
double side_fraction(const Vec3& n, double w) {
  int a = 0;
  for (int k = 1; k < 3; ++k)
    if (std::abs(n[k]) > std::abs(n[a])) a = k;
  const int b = (a + 1) % 3, c = (a + 2) % 3;
  constexpr int k = 16;
  double sum = 0;
  for (int j = 0; j < k; ++j)
    for (int i = 0; i < k; ++i) {
      const double y = (i + 0.5) / k - 0.5, z = (j + 0.5) / k - 0.5;
      // n_a x_a <= w - n_b y - n_c z: the column's part below (n_a > 0) or above that x_a.
      const double cut = (w - n[b] * y - n[c] * z) / n[a];
      sum += n[a] > 0 ? std::clamp(cut + 0.5, 0.0, 1.0) : std::clamp(0.5 - cut, 0.0, 1.0);
    }
  return sum / (k * k);
}

// The offset w at which the fraction `occ` of the cube lies on the side n . x <= w (bisection:
// the fraction grows with w, from 0 at -reach to 1 at reach).
double plane_offset(const Vec3& n, double occ) {
  const double reach = 0.5 * (std::abs(n.x) + std::abs(n.y) + std::abs(n.z));
  double lo = -reach, hi = reach;
  for (int it = 0; it < 40; ++it) {
    const double mid = 0.5 * (lo + hi);
    (side_fraction(n, mid) < occ ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
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
  // Kept in the voxel (near a corner the plane's foot may lie outside it).
  const Vec3 lo = g.origin + Vec3{double(i), double(j), double(k)} * g.voxel, e{1e-3, 1e-3, 1e-3};
  const Vec3 q2 = p - n * (over + 1e-3 * g.voxel), hi = lo + Vec3{1, 1, 1} * g.voxel;
  return {std::clamp(q2.x, lo.x + e.x * g.voxel, hi.x - e.x * g.voxel),
          std::clamp(q2.y, lo.y + e.y * g.voxel, hi.y - e.y * g.voxel),
          std::clamp(q2.z, lo.z + e.z * g.voxel, hi.z - e.z * g.voxel)};
}

}  // namespace scatter
