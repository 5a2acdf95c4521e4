// Triangle meshes: the boundary of a translucent object. Loaded through assimp or tessellated from
// a procedural shape; checked for watertightness before anything is voxelized from them.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "core/vec.hpp"

namespace scatter {

struct Mesh {
  std::vector<Vec3> positions;
  std::vector<Vec3> normals;      // one per position, unit length
  std::vector<uint32_t> indices;  // three per triangle, counter-clockwise seen from outside

  size_t triangle_count() const { return indices.size() / 3; }
  Aabb bounds() const;
  // Signed volume by the divergence theorem; positive when triangles face outwards.
  double volume() const;
  // Smooth vertex normals from the triangles (area weighted).
  void compute_normals();
  void transform(double scale, const Vec3& translate);
  // Reverses every triangle's winding if the mesh is inside-out (negative volume).
  void orient_outwards();
};

// SHA-256 of the positions and indices: the mesh's identity.
std::string mesh_digest(const Mesh& mesh);

struct WatertightReport {
  size_t boundary_edges = 0;     // edges used by one triangle only (holes)
  size_t nonmanifold_edges = 0;  // edges used by more than two triangles
  size_t misoriented_edges = 0;  // edges whose two triangles traverse them the same way
  size_t degenerate_triangles = 0;
  bool watertight() const {
    return boundary_edges == 0 && nonmanifold_edges == 0 && misoriented_edges == 0;
  }
  std::string summary() const;
};

// Welds vertices at identical positions, then counts how each edge is shared.
WatertightReport check_watertight(const Mesh& mesh);

struct MeshLimits {
  size_t max_triangles = 5'000'000;
  size_t max_bytes = size_t(1) << 30;  // of the file itself
};

// Imports OBJ, PLY, STL, OFF, glTF (self-contained: .glb or data URIs) and the other formats
// assimp reads, chosen by the file's extension; all meshes in the file are merged into one. The
// importer sees the file's bytes only: references to other files (an OBJ's mtllib, a glTF's
// external buffers) are not followed. Throws std::runtime_error naming the file and the problem:
// the importer's message, a malformed OFF file, a face naming a vertex that does not exist, no
// triangles, too many, or a coordinate that is not finite or beyond 1e6.
Mesh load_mesh(const std::filesystem::path& path, const MeshLimits& limits = {});

// The same for a file's bytes held in memory; `format` is its extension ("obj", "off", ...) and
// `name` is what messages call it.
Mesh load_mesh_bytes(std::string_view bytes, std::string_view format, const std::string& name,
                     const MeshLimits& limits = {});

}  // namespace scatter
