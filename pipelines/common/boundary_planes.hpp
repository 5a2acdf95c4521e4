// The mesh inside a boundary voxel as a plane, for optical depths summed through the voxels
// (kernels/common/dda.cl, optical_depth3_bounded). The voxelizer stores each voxel's coefficients
// averaged over the whole voxel (its medium fraction times the medium's), which is right for the
// voxel's mean but not for a ray: in a dense medium (sigma_t x voxel 30) a view ray grazing a
// face sees the mesh's sliver at the full density for many mean free paths, the voxel's mean a
// tenth of it. A pipeline that clips its medium at the mesh (single's splat, by depth peeling)
// and takes sigma_s per unit medium needs the optical depth of the same medium: the coefficients
// over the occupancy, counted on the voxel's inside of a plane whose side holds the voxel's
// occupied fraction (the plane's normal the occupancy's outward gradient over the 26 neighbours).
#pragma once

#include <vector>

#include "scene/voxelizer.hpp"

namespace scatter {

struct BoundedExtinction {
  // Per voxel, 3 channels: sigma_s + sigma_a, per unit medium where the voxel has a plane, else
  // the voxelizer's mean (interior and empty voxels, and boundary voxels whose occupancy has no
  // gradient).
  std::vector<float> sigma_t;
  // Per voxel, 4 floats (n, w): the medium is where n . (x - c) <= w, c the voxel's centre, n a
  // unit normal; zeros: the whole voxel.
  std::vector<float> plane;
  int planes = 0;  // voxels with a plane
};

BoundedExtinction bounded_extinction(const VoxelGrid& grid);

// `p` itself where it lies in the bounded medium or in a voxel without a plane; else its
// projection onto its voxel's plane, a thousandth of a voxel inside: where a point of a
// boundary voxel outside the mesh (a sample placed in the voxel's empty part) measures its
// optical depths from.
Vec3 inside_bound(const VoxelGrid& grid, const BoundedExtinction& bounded, const Vec3& p);

}  // namespace scatter
