// Procedural solids: sphere, box, torus. Each has an exact inside test (used by the voxelizer, so
// volumes do not suffer from tessellation error), an analytic volume, and a tessellation for
// raster.
#pragma once

#include <string>

#include "protocol/json_reader.hpp"
#include "scene/mesh.hpp"

namespace scatter {

struct Shape {
  enum class Kind { Sphere, Box, Torus };
  Kind kind = Kind::Sphere;
  Vec3 center;
  double radius = 1.0;         // sphere
  Vec3 size{2, 2, 2};          // box: full edge lengths
  double major_radius = 0.6;   // torus: centre of the tube from the axis
  double minor_radius = 0.25;  // torus: tube radius
  Vec3 axis{0, 1, 0};          // torus: unit axis of symmetry

  bool inside(const Vec3& p) const;
  Aabb bounds() const;
  double volume() const;
  // Watertight, outward-facing triangles; `detail` scales the number of segments.
  Mesh tessellate(int detail = 64) const;

  // Reads {"shape": "sphere"|"box"|"torus", ...}; the caller calls finish().
  static Shape parse(JsonObject& obj);
};

}  // namespace scatter
