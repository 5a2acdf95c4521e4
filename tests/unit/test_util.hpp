// Helpers shared by the unit tests: scratch files, and the GPU contexts made once per process.
#pragma once

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "gpu/gpu.hpp"

namespace scatter::test {

// A fresh directory under the build tree for one test.
inline std::filesystem::path scratch_dir(const std::string& name) {
  auto dir = std::filesystem::path(SCATTER_TEST_TMP) / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

inline std::filesystem::path write_file(const std::filesystem::path& path,
                                        const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

inline std::filesystem::path source_path(const std::string& rel) {
  return std::filesystem::path(SCATTER_SOURCE_DIR) / rel;
}

// One Gpu for the whole test binary: EGL and OpenCL contexts are costly to create.
inline gpu::Gpu& shared_gpu() {
  static gpu::Gpu gpu;
  return gpu;
}

// A minimal valid scene: a unit sphere lit from the camera side.
inline nlohmann::json minimal_scene() {
  return nlohmann::json::parse(R"({
    "mesh": {"shape": "sphere", "radius": 1.0},
    "medium": {"sigma_s": [1, 1, 1], "sigma_a": [0.1, 0.1, 0.1]},
    "lights": [{"type": "directional", "direction": [0, 0, -1], "irradiance": 1.0}],
    "camera": {"position": [0, 0, 4], "target": [0, 0, 0], "up": [0, 1, 0], "fov_deg": 40},
    "image": {"width": 64, "height": 64}
  })");
}

}  // namespace scatter::test
