// Scenes parsed once and shared: shipped scenes by file (reparsed when the file, or a file it
// names, changes on disk) and inline scenes by their JSON. Requests and live sessions hold the
// same immutable Scene; a frame overrides camera, lights and size without copying the mesh.
// Thread safe. Bounded: the least recently used scenes go once their meshes pass `max_bytes`.
#pragma once

#include <filesystem>
#include <list>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "scene/scene.hpp"

namespace scatter::server {

class SceneLibrary {
 public:
  explicit SceneLibrary(size_t max_bytes = size_t(512) << 20) : max_bytes_(max_bytes) {}

  // The scene in `file`; `load_ms` is set to the milliseconds spent loading it (0 for a hit).
  // Throws what load_scene throws.
  std::shared_ptr<const Scene> load(const std::filesystem::path& file, const SceneLimits& limits,
                                    double* load_ms = nullptr);
  // An inline scene (asset ids already resolved to files); as parse_scene.
  std::shared_ptr<const Scene> parse(const nlohmann::json& scene,
                                     const std::filesystem::path& base_dir,
                                     const SceneLimits& limits, double* load_ms = nullptr);

  // The "file" fields of the scene in `file` (meshes, grids) whose files do not exist, as the
  // scene writes them (relative to its folder, or absolute).
  static std::vector<std::string> missing_files(const std::filesystem::path& file);

  struct Stats {
    size_t scenes = 0, bytes = 0;
    uint64_t hits = 0, loads = 0;
  };
  Stats stats() const;

 private:
  struct Entry {
    std::string key;
    std::vector<std::pair<std::filesystem::path, std::filesystem::file_time_type>> files;
    std::shared_ptr<const Scene> scene;
    size_t bytes = 0;
  };
  template <class Load>
  std::shared_ptr<const Scene> get(const std::string& key, std::vector<std::filesystem::path> files,
                                   double* load_ms, Load load);

  size_t max_bytes_;
  mutable std::mutex mutex_;
  std::list<Entry> entries_;  // most recently used first
  size_t bytes_ = 0;
  uint64_t hits_ = 0, loads_ = 0;
};

}  // namespace scatter::server
