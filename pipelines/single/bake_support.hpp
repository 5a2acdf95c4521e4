// Pieces shared by the single bake's stages (single_bake.cpp, single_gaussians.cpp): threads over
// index ranges, and the voxels a Gaussian touches. Internal to pipelines/single.
#pragma once

#include <algorithm>
#include <cmath>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "pipelines/single/single_bake.hpp"
#include "scene/voxelizer.hpp"

namespace scatter::single_detail {

constexpr double kCutoff = 3.0;  // Gaussians end at 3 sigma

inline size_t thread_count(size_t n) {
  return std::min<size_t>(std::max(1u, std::thread::hardware_concurrency()),
                          std::max<size_t>(1, n / 64));
}

// Runs f(begin, end, thread) over [0, n) on `threads` threads; an exception in one is rethrown
// after all have joined.
template <class F>
void parallel_for(size_t n, F&& f, size_t threads = 0) {
  if (threads == 0) threads = thread_count(n);
  std::vector<std::jthread> pool;
  std::exception_ptr error;
  std::mutex m;
  for (size_t t = 0; t < threads; ++t)
    pool.emplace_back([&, t] {
      try {
        f(n * t / threads, n * (t + 1) / threads, t);
      } catch (...) {
        std::lock_guard lock(m);
        if (!error) error = std::current_exception();
      }
    });
  pool.clear();  // joins
  if (error) std::rethrow_exception(error);
}

// The channel-mean extinction of voxel v.
inline double extinction(const VoxelGrid& g, size_t v) {
  return (g.sigma_s[3 * v] + g.sigma_a[3 * v] + g.sigma_s[3 * v + 1] + g.sigma_a[3 * v + 1] +
          g.sigma_s[3 * v + 2] + g.sigma_a[3 * v + 2]) /
         3.0;
}

// The voxel holding p (clamped to the grid).
inline size_t voxel_at(const VoxelGrid& g, const Vec3& p) {
  return g.index(std::clamp(int((p.x - g.origin.x) / g.voxel), 0, g.nx - 1),
                 std::clamp(int((p.y - g.origin.y) / g.voxel), 0, g.ny - 1),
                 std::clamp(int((p.z - g.origin.z) / g.voxel), 0, g.nz - 1));
}

// Voxel index range a Gaussian at p with cutoff radius R touches.
struct Box {
  int i0, i1, j0, j1, k0, k1;
};
inline Box support(const VoxelGrid& g, const Vec3& p, double R) {
  auto lo = [&](double x, double o) {
    return std::max(0, int(std::floor((x - R - o) / g.voxel - 0.5)));
  };
  auto hi = [&](double x, double o, int n) {
    return std::min(n - 1, int(std::ceil((x + R - o) / g.voxel - 0.5)));
  };
  return {lo(p.x, g.origin.x),       hi(p.x, g.origin.x, g.nx), lo(p.y, g.origin.y),
          hi(p.y, g.origin.y, g.ny), lo(p.z, g.origin.z),       hi(p.z, g.origin.z, g.nz)};
}

template <class F>
void for_support(const VoxelGrid& g, const Vec3& p, double s, F&& f) {
  const double R = kCutoff * s, inv = 1 / (2 * s * s);
  Box b = support(g, p, R);
  for (int k = b.k0; k <= b.k1; ++k)
    for (int j = b.j0; j <= b.j1; ++j)
      for (int i = b.i0; i <= b.i1; ++i) {
        Vec3 d = g.center(i, j, k) - p;
        double r2 = dot(d, d);
        if (r2 > R * R) continue;
        f(g.index(i, j, k), std::exp(-r2 * inv));
      }
}

// Step 4 of the bake: each sample's Gaussian weight, normalised so that the Gaussians sum to one
// over the medium and all but the outermost of the `shell` layers (`layer`: 0 medium, d the d-th
// shell layer, 255 outside), the coverage statistics, and each sample's sigma_s (the weighted
// mean, then `sigma_fit` passes). `report` gets the fraction done.
// Step 4b (pipelines/single/single_split.cpp): splits the samples (the shell's too) whose support
// crosses an extinction jump above `ratio` (<= 1: none) into two pieces clipped by the interface
// plane; fills bake.plane (4 per piece, n . x <= d; zeros for an unclipped one) and returns the
// number of samples split (bake.count grows by as many). `medium` gets each piece's range of
// extinction per unit medium (2 per piece, lo and hi): the voxels its sigma_s is taken from (its
// own side's medium: within `ratio` of the extinction per unit medium of its own voxel, for the
// centre's piece, or of the nearest voxel across the jump, for the new one; everything for an
// unsplit sample).
int split_at_jumps(const VoxelGrid& g, const std::vector<uint8_t>& layer, double ratio,
                   SingleBake& bake, std::vector<float>& medium);

// The pieces' planes in the frame of their anchors (4 per piece, as bake.plane): a shell
// sample's anchor is its position moved into the medium, and its pieces' one-sided differences
// (kernels/single/shade.cl) are tested against its planes moved the same way. The splat clips
// with bake.plane itself. The k-th split sample's new piece is piece count - split + k.
std::vector<float> depth_frame_planes(const SingleBake& b);

void make_gaussians(const VoxelGrid& g, const std::vector<uint8_t>& layer, int shell,
                    const SingleBakeParams& p, SingleBake& bake,
                    const std::function<void(double)>& report);

}  // namespace scatter::single_detail
