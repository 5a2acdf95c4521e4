// Inside/outside queries for the voxelizer, answered a column (fixed x, y) at a time so that a mesh
// intersects each column once and classifies any number of points along it by parity.
#pragma once

#include <memory>
#include <vector>

#include "scene/scene.hpp"

namespace scatter {

class Solid {
 public:
  virtual ~Solid() = default;
  virtual Aabb bounds() const = 0;
  // inside[k] = whether (x, y, zs[k]) lies inside the solid.
  virtual void classify_column(double x, double y, const std::vector<double>& zs,
                               std::vector<char>& inside) const = 0;
};

// A watertight triangle mesh; the parity of crossings along +z decides (concave meshes included).
// The solid keeps a reference: `mesh` must outlive it.
std::unique_ptr<Solid> make_mesh_solid(const Mesh& mesh);
// An analytic shape's exact inside test.
std::unique_ptr<Solid> make_shape_solid(const Shape& shape);
// The scene's solid: the exact shape when there is one, else its mesh (`scene` must outlive it).
std::unique_ptr<Solid> make_solid(const Scene& scene);

}  // namespace scatter
