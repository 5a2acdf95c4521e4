// Whether a closed mesh is convex: then a ray from inside crosses it once, and a path or shadow ray
// that has left it never comes back, so the reference's kernels stop searching for crossings.
#pragma once

#include "scene/mesh.hpp"

namespace scatter {

// True when every edge is convex: the far vertex of the triangle across each edge lies on or
// behind the triangle's plane (within a tolerance relative to the mesh's size). A closed, connected
// and locally convex surface is convex. Vertices are matched by position, so meshes that repeat
// positions for flat normals (the box) count as closed.
bool is_convex(const Mesh& mesh);

}  // namespace scatter
