#include "scene/solid.hpp"

#include <algorithm>

namespace scatter {
namespace {

class ShapeSolid : public Solid {
 public:
  explicit ShapeSolid(const Shape& s) : shape_(s) {}
  Aabb bounds() const override { return shape_.bounds(); }
  void classify_column(double x, double y, const std::vector<double>& zs,
                       std::vector<char>& inside) const override {
    inside.resize(zs.size());
    for (size_t k = 0; k < zs.size(); ++k) inside[k] = shape_.inside({x, y, zs[k]});
  }

 private:
  Shape shape_;
};

// Triangles binned by their xy footprint into a uniform 2D grid, so that a column only tests the
// triangles of its own cell.
class MeshSolid : public Solid {
 public:
  explicit MeshSolid(const Mesh& mesh) : mesh_(mesh), bounds_(mesh.bounds()) {
    size_t tris = mesh.triangle_count();
    cells_ = std::clamp(static_cast<int>(std::sqrt(double(tris) / 4)), 1, 512);
    bins_.resize(size_t(cells_) * cells_);
    for (uint32_t t = 0; t < tris; ++t) {
      Aabb b;
      for (int k = 0; k < 3; ++k) b.add(mesh.positions[mesh.indices[3 * t + k]]);
      auto [i0, j0] = cell(b.lo.x, b.lo.y);
      auto [i1, j1] = cell(b.hi.x, b.hi.y);
      for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i) bins_[size_t(j) * cells_ + i].push_back(t);
    }
  }
  Aabb bounds() const override { return bounds_; }

  void classify_column(double x, double y, const std::vector<double>& zs,
                       std::vector<char>& inside) const override {
    std::vector<double> crossings;
    auto [i, j] = cell(x, y);
    for (uint32_t t : bins_[size_t(j) * cells_ + i]) crossing(t, x, y, crossings);
    std::sort(crossings.begin(), crossings.end());
    inside.resize(zs.size());
    for (size_t k = 0; k < zs.size(); ++k) {
      auto below = std::lower_bound(crossings.begin(), crossings.end(), zs[k]) - crossings.begin();
      inside[k] = (below % 2) == 1 && size_t(below) < crossings.size();
    }
  }

 private:
  std::pair<int, int> cell(double x, double y) const {
    Vec3 s = bounds_.size();
    auto idx = [&](double v, double lo, double extent) {
      int c = extent > 0 ? static_cast<int>((v - lo) / extent * cells_) : 0;
      return std::clamp(c, 0, cells_ - 1);
    };
    return {idx(x, bounds_.lo.x, s.x), idx(y, bounds_.lo.y, s.y)};
  }

  // Appends the z at which the vertical line through (x, y) crosses triangle t, if it does.
  // A line through a shared edge or vertex must be counted exactly once: the edge function is
  // evaluated with the edge's endpoints in a fixed (lexicographic) order, so the two triangles
  // sharing an edge compute bit-identical values of opposite sign, and a zero value is owned by
  // one side only (a top-left style rule that depends on the edge, not on the triangle).
  void crossing(uint32_t t, double x, double y, std::vector<double>& out) const {
    const Vec3& a = mesh_.positions[mesh_.indices[3 * t]];
    const Vec3& b = mesh_.positions[mesh_.indices[3 * t + 1]];
    const Vec3& c = mesh_.positions[mesh_.indices[3 * t + 2]];
    // Orientation of the triangle's projection, from its vertices alone.
    double area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
    if (area == 0) return;  // edge-on to the column
    double w0 = edge(b, c, x, y), w1 = edge(c, a, x, y), w2 = edge(a, b, x, y);
    if (!owns(w0, b, c, area) || !owns(w1, c, a, area) || !owns(w2, a, b, area)) return;
    double sum = w0 + w1 + w2;
    if (sum == 0) return;
    out.push_back((w0 * a.z + w1 * b.z + w2 * c.z) / sum);
  }

  static bool before(const Vec3& p, const Vec3& q) {
    return p.x < q.x || (p.x == q.x && p.y < q.y);
  }

  // Which side of the directed edge p -> q the point (x, y) lies on; antisymmetric bit for bit.
  static double edge(const Vec3& p, const Vec3& q, double x, double y) {
    if (before(q, p)) return -edge(q, p, x, y);
    return (q.x - p.x) * (y - p.y) - (q.y - p.y) * (x - p.x);
  }

  // Whether a point with edge value w is inside with respect to edge p -> q of a triangle whose
  // projection has orientation `area`. On the edge (w == 0) exactly one of the two triangles that
  // share it (seeing it as p -> q and q -> p) owns the point.
  static bool owns(double w, const Vec3& p, const Vec3& q, double area) {
    if (w != 0) return (w > 0) == (area > 0);
    return before(p, q) == (area > 0);
  }

  const Mesh& mesh_;
  Aabb bounds_;
  int cells_ = 1;
  std::vector<std::vector<uint32_t>> bins_;
};

}  // namespace

std::unique_ptr<Solid> make_mesh_solid(const Mesh& mesh) {
  return std::make_unique<MeshSolid>(mesh);
}
std::unique_ptr<Solid> make_shape_solid(const Shape& shape) {
  return std::make_unique<ShapeSolid>(shape);
}
std::unique_ptr<Solid> make_solid(const Scene& scene) {
  if (scene.shape) return make_shape_solid(*scene.shape);
  return make_mesh_solid(*scene.mesh);
}

}  // namespace scatter
