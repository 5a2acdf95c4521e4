// Per voxel of the reference's grid, the mesh triangles that overlap it: the exit and first-hit
// queries of rays inside the medium walk the voxels with the transmittance's own DDA and test only
// the triangles listed for each voxel they enter (kernels/reference/boundary.cl, cell_search),
// instead of a BVH traversal per query. The lists are conservative: a triangle is listed for
// every voxel whose box, grown by a hundredth of a voxel on each side (the DDA's float32
// rounding), it overlaps by the separating-axis test.
#pragma once

#include <cstdint>
#include <vector>

#include "core/vec.hpp"
#include "scene/bvh.hpp"
#include "scene/voxelizer.hpp"

namespace scatter {

struct CellTriangles {
  // Per voxel (x fastest) and one more: where its list starts in `triangles`; voxel v's list is
  // triangles[first[v], first[v + 1]).
  std::vector<int32_t> first;
  // Triangle indices into FlatBvh::triangles (12 floats each).
  std::vector<int32_t> triangles;
  // Per voxel, how far (in voxels, any direction) a ray from any point of it goes without
  // entering a voxel with a list: the Chebyshev distance to the nearest such voxel less one,
  // capped at 255; the walk jumps that far.
  std::vector<uint8_t> skip;
};

// The lists over `grid`'s voxels for the triangles of `bvh` (in its leaf order).
CellTriangles cell_triangles(const VoxelGrid& grid, const FlatBvh& bvh);

// Whether the lists answer the path tracer's queries faster than the BVH, as measured
// (docs/BENCHMARKS.md, ref22): on a mesh of 1000 triangles or more whose listed voxels hold 8 or
// fewer on average. The 9024-triangle sphere at 64 voxels (3.8 a voxel) gains; the 12-triangle
// cube (whose BVH is a few boxes) and the 70k-triangle bunny (12.6 a voxel) lose.
bool uses_cell_lists(const CellTriangles& cells, const FlatBvh& bvh);
// The least triangles of a mesh on which uses_cell_lists may say yes (below, the lists need not
// be built to know).
inline constexpr size_t kCellListsMinTriangles = 1000;

// Whether triangle (a, b, c) and the box [lo, hi] share a point (Akenine-Moller's
// separating-axis test: the box's three axes, the triangle's normal, the nine edge cross
// products); touching counts as overlapping.
bool triangle_box_overlap(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& lo,
                          const Vec3& hi);

}  // namespace scatter
