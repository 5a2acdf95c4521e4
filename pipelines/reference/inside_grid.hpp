// The reference's medium: the density grid inside the mesh. The voxelizer stores each voxel's
// coefficients averaged over the whole voxel (the medium's fraction times its mean density, plus a
// blocker's absorption times its fraction); the reference bounds the medium by the mesh itself
// (kernels/reference/boundary.cl), so it needs the mean over the voxel's part inside the mesh:
// the coefficients over the occupancy. The values are piecewise constant (each voxel's own, no
// trilinear interpolation). Voxels the mesh may still reach but that hold none of it (occupancy 0
// next to an occupied voxel: a sliver the supersampling missed) take their occupied neighbours'
// mean, so that the medium the mesh bounds has no holes.
#pragma once

#include <cstdint>
#include <vector>

#include "scene/voxelizer.hpp"

namespace scatter {

// In place: sigma_s and sigma_a become the means over each voxel's part inside the mesh.
void restrict_to_mesh(VoxelGrid& grid);

}  // namespace scatter

namespace scatter {

// Per voxel, how far the mesh is at least, in voxels: the Chebyshev distance to the nearest voxel
// not wholly inside the mesh (occupancy < 1), less two (one for a sliver of surface in a voxel
// counted full), capped at 255; 0 for the voxels the mesh
// may cross. Within that many voxels of any point of the voxel the medium has no boundary, so a
// free flight or shadow ray tracks that far without asking the mesh.
std::vector<uint8_t> interior_depth(const VoxelGrid& grid);

// In place, over `grid`'s voxels: d[v] becomes the least of d[v] and, for every voxel u,
// d[u] plus the Chebyshev distance from v to u (so the distance to the nearest voxel holding 0,
// where the others start high); the voxels past the grid count as 0.
void chebyshev_distance(const VoxelGrid& grid, std::vector<int>& d);

}  // namespace scatter

namespace scatter {

// Per brick of `brick`^3 voxels (x fastest), the index of a voxel whose sigma_s and sigma_a (to
// float32 rounding, 1e-6 relative) every voxel of the brick that a segment may cross shares, or
// -1: then tracking and transmittance in the brick need no voxel walk (its optical depth is
// sigma_t times the length); -2 where no segment may cross any of its voxels. With
// `mesh_bounds` only voxels inside the mesh or next to it count (those restrict_to_mesh gave
// values), since the medium's segments lie inside the mesh; otherwise every voxel does.
std::vector<int32_t> uniform_bricks(const VoxelGrid& grid, int brick, bool mesh_bounds);

// From uniform_bricks' answer: the index of a voxel whose coefficients every voxel a segment may
// cross shares (a constant density inside the mesh: then a segment's tracking and optical depth
// need no walk at all), or -1.
int32_t homogeneous_voxel(const VoxelGrid& grid, const std::vector<int32_t>& uniform);

}  // namespace scatter
