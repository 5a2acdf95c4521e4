// Voxelizer: a scene's solid and medium to a regular grid of extinction coefficients.
#pragma once

#include <cstdint>
#include <vector>

#include "scene/scene.hpp"

namespace scatter {

struct VoxelGrid {
  int nx = 0, ny = 0, nz = 0;
  Vec3 origin;                 // world position of the corner of voxel (0, 0, 0)
  double voxel = 0;            // edge length of a (cubic) voxel
  std::vector<float> sigma_s;  // 3 per voxel (RGB), per scene unit
  std::vector<float> sigma_a;  // 3 per voxel (RGB), per scene unit
  std::vector<float>
      occupancy;                // fraction of the voxel inside the mesh, supersampled at boundaries
  std::vector<uint8_t> inside;  // voxel centre inside the mesh

  size_t count() const { return size_t(nx) * ny * nz; }
  size_t index(int i, int j, int k) const { return (size_t(k) * ny + j) * nx + i; }
  Vec3 center(int i, int j, int k) const {
    return origin + Vec3{i + 0.5, j + 0.5, k + 0.5} * voxel;
  }
  // Sum of occupancy times the voxel volume: the solid's volume.
  double volume() const;
};

struct VoxelizeOptions {
  int resolution = 64;  // voxels along the longest side of the solid's bounding box
  int supersample = 4;  // k: boundary voxels are classified at k^3 points
  int threads = 0;      // 0: hardware concurrency
  int margin = 1;       // empty voxels around the solid's bounding box on each side
};

// The grid covers the solid's bounding box plus `margin` voxels on each side.
VoxelGrid voxelize(const Scene& scene, const VoxelizeOptions& options);

}  // namespace scatter
