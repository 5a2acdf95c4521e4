// Real spherical harmonics up to band 7 (64 functions), orthonormal on the unit sphere, in the
// order l = 0..7, m = -l..l. shaders/single/shade.comp evaluates the same basis; keep them equal.
#pragma once

#include <array>
#include <vector>

#include "core/vec.hpp"

namespace scatter {

constexpr int kMaxShBands = 8;  // bands l = 0..7: 64 coefficients (the paper: up to 25)
constexpr int sh_count(int bands) {
  return bands * bands;
}

// Y_i(d) for i < bands^2, d a unit vector.
void sh_basis(const Vec3& d, int bands, float* out);
// sum_i c[i] Y_i(d).
float sh_eval(const float* c, const Vec3& d, int bands);

// n directions spread evenly over the sphere (a spherical Fibonacci lattice), each standing for
// a solid angle of 4 pi / n.
std::vector<Vec3> sphere_directions(int n);

// Projects f sampled at `dirs` (equal solid angles) onto the basis: c_i = 4 pi / n sum_k f_k
// Y_i(d_k).
std::vector<float> sh_project(const std::vector<Vec3>& dirs, const std::vector<float>& f,
                              int bands);

}  // namespace scatter
