#include "pipelines/reference/cell_triangles.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "pipelines/reference/inside_grid.hpp"

namespace scatter {
namespace {

// The projections of the triangle's vertices (relative to the box centre) and the box's radius
// on `axis` do not overlap.
bool separates(const Vec3& axis, const std::array<Vec3, 3>& v, const Vec3& half) {
  double p0 = dot(axis, v[0]), p1 = dot(axis, v[1]), p2 = dot(axis, v[2]);
  double r = half.x * std::abs(axis.x) + half.y * std::abs(axis.y) + half.z * std::abs(axis.z);
  return std::min({p0, p1, p2}) > r || std::max({p0, p1, p2}) < -r;
}

Vec3 vertex(const FlatBvh& bvh, size_t t, int k) {
  const float* p = bvh.triangles.data() + 12 * t + 4 * k;
  return {p[0], p[1], p[2]};
}

}  // namespace

bool triangle_box_overlap(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& lo,
                          const Vec3& hi) {
  const Vec3 centre = (lo + hi) * 0.5, half = (hi - lo) * 0.5;
  const std::array<Vec3, 3> v = {a - centre, b - centre, c - centre};
  const std::array<Vec3, 3> e = {v[1] - v[0], v[2] - v[1], v[0] - v[2]};
  const std::array<Vec3, 3> axes = {Vec3{1, 0, 0}, Vec3{0, 1, 0}, Vec3{0, 0, 1}};
  for (const Vec3& u : axes)
    if (separates(u, v, half)) return false;
  if (separates(cross(e[0], e[1]), v, half)) return false;
  for (const Vec3& u : axes)
    for (const Vec3& edge : e)
      if (separates(cross(u, edge), v, half)) return false;
  return true;
}

bool uses_cell_lists(const CellTriangles& cells, const FlatBvh& bvh) {
  size_t listed = 0;
  for (size_t v = 0; v + 1 < cells.first.size(); ++v) listed += cells.first[v + 1] > cells.first[v];
  return bvh.triangles.size() / 12 >= kCellListsMinTriangles && listed > 0 &&
         double(cells.triangles.size()) <= 8.0 * double(listed);
}

CellTriangles cell_triangles(const VoxelGrid& grid, const FlatBvh& bvh) {
  const size_t count = bvh.triangles.size() / 12;
  const double pad = 1e-2 * grid.voxel;
  const int dims[3] = {grid.nx, grid.ny, grid.nz};
  // Each triangle's voxels, found over its padded bounding box; then the lists by voxel.
  std::vector<std::pair<int64_t, int32_t>> pairs;
  for (size_t t = 0; t < count; ++t) {
    const Vec3 a = vertex(bvh, t, 0), b = vertex(bvh, t, 1), c = vertex(bvh, t, 2);
    int lo[3], hi[3];
    for (int k = 0; k < 3; ++k) {
      double mn = std::min({a[k], b[k], c[k]}) - pad, mx = std::max({a[k], b[k], c[k]}) + pad;
      lo[k] = std::max(0, int(std::floor((mn - grid.origin[k]) / grid.voxel)));
      hi[k] = std::min(dims[k] - 1, int(std::floor((mx - grid.origin[k]) / grid.voxel)));
    }
    for (int z = lo[2]; z <= hi[2]; ++z)
      for (int y = lo[1]; y <= hi[1]; ++y)
        for (int x = lo[0]; x <= hi[0]; ++x) {
          const Vec3 corner = grid.origin + Vec3{double(x), double(y), double(z)} * grid.voxel;
          const Vec3 box_lo = corner - Vec3{pad, pad, pad},
                     box_hi = corner + Vec3{grid.voxel + pad, grid.voxel + pad, grid.voxel + pad};
          if (triangle_box_overlap(a, b, c, box_lo, box_hi))
            pairs.push_back({int64_t(grid.index(x, y, z)), int32_t(t)});
        }
  }
  std::sort(pairs.begin(), pairs.end());
  CellTriangles out;
  out.first.assign(grid.count() + 1, 0);
  out.triangles.reserve(pairs.size());
  for (const auto& [v, t] : pairs) {
    ++out.first[size_t(v) + 1];
    out.triangles.push_back(t);
  }
  for (size_t v = 0; v < grid.count(); ++v) out.first[v + 1] += out.first[v];
  // A point in voxel v moving k < D voxels stays in voxels within D - 1 of v, D the distance.
  std::vector<int> d(grid.count());
  for (size_t v = 0; v < d.size(); ++v) d[v] = out.first[v + 1] > out.first[v] ? 0 : 256;
  chebyshev_distance(grid, d);
  out.skip.resize(d.size());
  for (size_t v = 0; v < d.size(); ++v) out.skip[v] = uint8_t(std::clamp(d[v] - 1, 0, 255));
  return out;
}

}  // namespace scatter
