// Per light, for a convex mesh: the mesh's triangles that face the light, binned over a plane:
// the plane normal to a directional light, or, for a point or spot light with the whole mesh in
// front of it, the plane a unit along its axis in perspective from it. A shadow ray from inside a
// convex mesh crosses it once, leaving through the light-facing triangle whose projection holds
// the ray's: the path tracer tests the triangles of the ray's cell (kernels/reference/path.cl,
// next_event) instead of walking the voxels' lists or the BVH to the surface. The same triangle
// test finds the same exit; a ray whose cell holds no hit (rounding at a silhouette, a point just
// outside) takes the mesh query as before.
#pragma once

#include <cstdint>
#include <vector>

#include "scene/bvh.hpp"
#include "scene/scene.hpp"

namespace scatter {

inline constexpr int kExitMapFloats = 16;

struct ExitMaps {
  // Per light, kExitMapFloats floats: e1.xyz, e2.xyz (the plane's orthonormal axes; its normal
  // w = e1 x e2 points towards a directional light, from a point light to the mesh), u0, v0 (the
  // map's corner in them), 1 / cell, nu, nv (cells per axis; 0: no map for this light), where
  // the light's cells start in `first` (an int32's bits: a float would round past 2^24 cells), the
  // light's position and 1 for a point or spot light (a point p projects to ((p - L) . e1, (p - L)
  // . e2) / ((p - L) . w)), 0 for a directional one.
  std::vector<float> header;
  // Per cell of every map (u fastest) and one more: where its list starts in `triangles`.
  std::vector<int32_t> first;
  std::vector<int32_t> triangles;  // indices into FlatBvh::triangles (12 floats each)
  bool empty() const { return triangles.empty(); }
  int lights() const {  // how many lights have a map
    int n = 0;
    for (size_t i = 9; i < header.size(); i += kExitMapFloats) n += header[i] > 0;
    return n;
  }
};

// The maps for `lights` over the triangles of `bvh` (the scene's mesh, which must be convex:
// convex.hpp). About four cells per light-facing triangle, at most 1024 x 1024 a light.
ExitMaps exit_maps(const FlatBvh& bvh, const std::vector<Light>& lights);

// The exit of o + t d (d the direction towards the light) found as the kernel finds it: the
// first hit, t > 0, among the triangles of o's cell (from inside a convex mesh, the only one); a
// negative value when there is none. For tests on the CPU.
double exit_map_hit(const ExitMaps& maps, const FlatBvh& bvh, int light, const Vec3& o);

}  // namespace scatter
