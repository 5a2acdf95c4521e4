// Shared by the fuzz targets: a scratch folder with a few small valid assets for scenes to name
// (a cube mesh, a grid), made once per process, and the checks a parsed mesh must pass.
#pragma once

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include "protocol/json_reader.hpp"
#include "scene/mesh.hpp"

namespace scatter::fuzz {

inline void write(const std::filesystem::path& p, std::string_view bytes) {
  std::ofstream(p, std::ios::binary)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// The unit cube as OBJ.
inline std::string cube_obj() {
  return "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
         "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\n"
         "f 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n";
}

// A folder per process: cube.obj, grid.json + grid.raw (2x2x2) for scenes that name files, and the
// scene corpus's scenes (the shipped ones, the bunny replaced by the cube) for requests that name
// a scene. Removed at exit by its owner's destructor (an atexit handler registered while the
// static path was being built ran after the path's own destructor, so every run left its folder
// in /tmp).
struct AssetsDir {
  std::filesystem::path path;
  AssetsDir()
      : path(std::filesystem::temp_directory_path() /
             ("scatter-fuzz-" + std::to_string(::getpid()))) {
    std::filesystem::create_directories(path);
    write(path / "cube.obj", cube_obj());
    float values[8] = {0, 1, 2, 3, 4, 5, 6, 7};
    write(path / "grid.raw",
          std::string_view(reinterpret_cast<const char*>(values), sizeof values));
    write(path / "grid.json", R"({"dims": [2, 2, 2], "data": "grid.raw", "format": "float32",
                               "bounds": {"min": [-1, -1, -1], "max": [1, 1, 1]}})");
    for (const auto& e : std::filesystem::directory_iterator(SCATTER_FUZZ_CORPUS "/scene"))
      std::filesystem::copy_file(e.path(), path / e.path().filename(),
                                 std::filesystem::copy_options::overwrite_existing);
  }
  ~AssetsDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path, ignored);
  }
};

inline const std::filesystem::path& assets_dir() {
  static const AssetsDir dir;
  return dir.path;
}

// parse_json, as the server calls it on bodies, messages and scene files; false when it rejects the
// text (a ValidationError: malformed, too deep, or a number past a double's range, which it once
// let through as nlohmann's out_of_range and the server answered with a 500).
inline bool parse(std::string_view text, nlohmann::json& out) {
  try {
    out = parse_json(text, "fuzz");
    return true;
  } catch (const std::runtime_error&) {
  }
  return false;
}

// What every mesh that an importer hands back must satisfy; a violation aborts the run.
inline void check_mesh(const Mesh& m) {
  if (m.indices.size() % 3 != 0 || m.normals.size() != m.positions.size()) std::abort();
  for (uint32_t i : m.indices)
    if (i >= m.positions.size()) std::abort();
  for (const Vec3& p : m.positions)
    for (int a = 0; a < 3; ++a)
      if (!std::isfinite(p[a]) || std::abs(p[a]) > 1e6) std::abort();
}

}  // namespace scatter::fuzz
