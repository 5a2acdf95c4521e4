#include "scene/mesh.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <unordered_map>

#include "protocol/digest.hpp"

namespace scatter {

Aabb Mesh::bounds() const {
  Aabb b;
  for (const auto& p : positions) b.add(p);
  return b;
}

double Mesh::volume() const {
  double v = 0;
  for (size_t t = 0; t + 2 < indices.size(); t += 3) {
    const Vec3& a = positions[indices[t]];
    const Vec3& b = positions[indices[t + 1]];
    const Vec3& c = positions[indices[t + 2]];
    v += dot(a, cross(b, c));
  }
  return v / 6.0;
}

void Mesh::compute_normals() {
  normals.assign(positions.size(), Vec3{});
  for (size_t t = 0; t + 2 < indices.size(); t += 3) {
    uint32_t i0 = indices[t], i1 = indices[t + 1], i2 = indices[t + 2];
    Vec3 n = cross(positions[i1] - positions[i0], positions[i2] - positions[i0]);
    normals[i0] += n;
    normals[i1] += n;
    normals[i2] += n;
  }
  for (auto& n : normals) n = normalize(n);
}

void Mesh::transform(double scale, const Vec3& translate) {
  for (auto& p : positions) p = p * scale + translate;
}

void Mesh::orient_outwards() {
  if (volume() < 0)
    for (size_t t = 0; t + 2 < indices.size(); t += 3) std::swap(indices[t + 1], indices[t + 2]);
}

std::string WatertightReport::summary() const {
  return std::to_string(boundary_edges) + " boundary edges, " + std::to_string(nonmanifold_edges) +
         " non-manifold edges, " + std::to_string(misoriented_edges) +
         " inconsistently oriented edges";
}

WatertightReport check_watertight(const Mesh& mesh) {
  // Weld by exact position: importers may split vertices for normals or texture seams.
  std::map<std::array<double, 3>, uint32_t> ids;
  std::vector<uint32_t> weld(mesh.positions.size());
  for (size_t i = 0; i < mesh.positions.size(); ++i) {
    const Vec3& p = mesh.positions[i];
    weld[i] = ids.emplace(std::array<double, 3>{p.x, p.y, p.z}, static_cast<uint32_t>(ids.size()))
                  .first->second;
  }
  // For each undirected edge: how many triangles use it, and the sum of directions (+1 / -1).
  struct Use {
    int count = 0;
    int direction = 0;
  };
  std::unordered_map<uint64_t, Use> edges;
  WatertightReport report;
  for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    uint32_t v[3] = {weld[mesh.indices[t]], weld[mesh.indices[t + 1]], weld[mesh.indices[t + 2]]};
    if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) {
      ++report.degenerate_triangles;
      continue;
    }
    for (int e = 0; e < 3; ++e) {
      uint32_t a = v[e], b = v[(e + 1) % 3];
      uint64_t key = (uint64_t(std::min(a, b)) << 32) | std::max(a, b);
      Use& u = edges[key];
      ++u.count;
      u.direction += a < b ? 1 : -1;
    }
  }
  for (const auto& [key, u] : edges) {
    if (u.count == 1)
      ++report.boundary_edges;
    else if (u.count > 2)
      ++report.nonmanifold_edges;
    else if (u.direction != 0)
      ++report.misoriented_edges;
  }
  return report;
}

std::string mesh_digest(const Mesh& mesh) {
  std::string bytes(reinterpret_cast<const char*>(mesh.positions.data()),
                    mesh.positions.size() * sizeof(Vec3));
  bytes.append(reinterpret_cast<const char*>(mesh.indices.data()),
               mesh.indices.size() * sizeof(uint32_t));
  return sha256_hex(bytes);
}

}  // namespace scatter
