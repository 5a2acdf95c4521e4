#include "pipelines/reference/convex.hpp"

#include <algorithm>
#include <map>
#include <tuple>
#include <unordered_map>

namespace scatter {

bool is_convex(const Mesh& mesh) {
  // One id per distinct position.
  std::map<std::tuple<double, double, double>, uint32_t> ids;
  std::vector<uint32_t> id(mesh.positions.size());
  for (size_t i = 0; i < mesh.positions.size(); ++i) {
    const Vec3& p = mesh.positions[i];
    id[i] = ids.emplace(std::make_tuple(p.x, p.y, p.z), uint32_t(ids.size())).first->second;
  }
  const size_t tris = mesh.triangle_count();
  // Directed edge (a, b) -> the triangle that has it.
  std::unordered_map<uint64_t, uint32_t> edge;
  edge.reserve(3 * tris);
  auto key = [](uint32_t a, uint32_t b) { return (uint64_t(a) << 32) | b; };
  for (uint32_t t = 0; t < tris; ++t)
    for (int k = 0; k < 3; ++k)
      edge[key(id[mesh.indices[3 * t + k]], id[mesh.indices[3 * t + (k + 1) % 3]])] = t;
  Aabb box = mesh.bounds();
  Vec3 size = box.size();
  const double tolerance = 1e-9 * std::max({size.x, size.y, size.z});
  for (uint32_t t = 0; t < tris; ++t) {
    const Vec3& a = mesh.positions[mesh.indices[3 * t]];
    Vec3 n = cross(mesh.positions[mesh.indices[3 * t + 1]] - a,
                   mesh.positions[mesh.indices[3 * t + 2]] - a);
    double len = length(n);
    if (!(len > 0)) continue;  // a degenerate triangle has no plane to test
    n = n * (1 / len);
    for (int k = 0; k < 3; ++k) {
      auto twin =
          edge.find(key(id[mesh.indices[3 * t + (k + 1) % 3]], id[mesh.indices[3 * t + k]]));
      if (twin == edge.end()) return false;  // open: not a closed surface
      for (int m = 0; m < 3; ++m)
        if (dot(n, mesh.positions[mesh.indices[3 * twin->second + m]] - a) > tolerance)
          return false;
    }
  }
  return tris > 0;
}

}  // namespace scatter
