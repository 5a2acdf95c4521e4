// Bounding-volume hierarchy over a mesh's triangles, flattened for the OpenCL kernels that need
// ray-surface intersections (the dielectric boundary). Built on the CPU by splitting at the
// median centroid along the widest axis; leaves hold up to 4 triangles.
#pragma once

#include <cstdint>
#include <vector>

#include "scene/mesh.hpp"

namespace scatter {

struct FlatBvh {
  // Per node: 8 floats (lo.xyz, pad, hi.xyz, pad) and 2 ints: for an inner node (second child,
  // 0) with the first child next in the array; for a leaf (first triangle, count).
  std::vector<float> bounds;
  std::vector<int32_t> links;
  // Per triangle, in leaf order: 12 floats (v0.xyz, pad, v1.xyz, pad, v2.xyz, pad).
  std::vector<float> triangles;
  size_t node_count() const { return links.size() / 2; }
};

FlatBvh build_bvh(const Mesh& mesh);

// Moller-Trumbore: where o + t d meets triangle `tri` (12 floats of FlatBvh::triangles), or a
// negative value when it misses (as the kernels' triangle_hit).
double triangle_ray_hit(const float* tri, const Vec3& o, const Vec3& d);

// Closest hit of o + t d, t in (t_min, t_max), for testing the flattened layout on the CPU;
// returns the distance or a negative value. The kernels implement the same traversal.
double bvh_closest_hit(const FlatBvh& bvh, const Vec3& o, const Vec3& d, double t_min,
                       double t_max);

}  // namespace scatter
