// Volumes the lbl tests share: a box filled with one medium, and a ball with a density step and
// a blocker.
#pragma once

#include <cmath>

#include "pipelines/lbl/volume.hpp"

namespace scatter::lbl::test_volumes {

// An n^3 grid of voxels 1.6 / n wide (the box [-0.8, 0.8]^3) filled with one medium (n 1,
// no gradient).
inline Volume filled(float sigma_s, float sigma_t, int n = 16) {
  Volume v;
  v.nx = v.ny = v.nz = n;
  v.voxel = 1.6 / n;
  v.origin = {-0.8, -0.8, -0.8};
  v.sigma_s.assign(3 * v.count(), sigma_s);
  v.sigma_t.assign(3 * v.count(), sigma_t);
  v.n.assign(v.count(), 1.f);
  v.grad.assign(3 * v.count(), 0.f);
  return v;
}

// Whether voxel (i, j, k) of a 32^3 filled() grid lies in the ball of radius 0.65, and its
// density there: 1, twice that above z 0.2 (a density step), 0 in the absorbing blocker.
struct BallVoxel {
  bool inside = false, blocker = false;
  double density = 0, z = 0;
};
inline BallVoxel ball_voxel(const Volume& v, int i, int j, int k) {
  Vec3 p = v.origin + Vec3{i + 0.5, j + 0.5, k + 0.5} * v.voxel;
  BallVoxel b;
  b.z = p.z;
  b.inside = p.x * p.x + p.y * p.y + p.z * p.z <= 0.65 * 0.65;
  b.density = p.z > 0.2 ? 2 : 1;
  b.blocker = std::abs(p.x + 0.25) < 0.1 && std::abs(p.y) < 0.1 && std::abs(p.z) < 0.1;
  return b;
}

// A ball (radius 0.65) in a 32^3 grid of voxels 0.05 wide: sigma_s 2, sigma_t 2.05 (0.1 per
// voxel, as the shipped scenes at 64 voxels), twice as dense above z 0.2 (a density step), with
// an absorbing block that does not scatter (a blocker, sigma_t 100) inside.
inline Volume ball() {
  Volume v = filled(0, 0, 32);
  for (int k = 0; k < 32; ++k)
    for (int j = 0; j < 32; ++j)
      for (int i = 0; i < 32; ++i) {
        BallVoxel b = ball_voxel(v, i, j, k);
        if (!b.inside) continue;
        for (int c = 0; c < 3; ++c) {
          v.sigma_s[3 * v.index(i, j, k) + c] = b.blocker ? 0.f : float(2 * b.density);
          v.sigma_t[3 * v.index(i, j, k) + c] = b.blocker ? 100.f : float(2.05 * b.density);
        }
      }
  return v;
}

}  // namespace scatter::lbl::test_volumes
