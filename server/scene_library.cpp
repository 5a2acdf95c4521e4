#include "server/scene_library.hpp"

#include <chrono>
#include <fstream>

#include "bake/cache.hpp"
#include "protocol/json_reader.hpp"

namespace scatter::server {
namespace {

// The files a scene's JSON names ("file" fields: meshes, grids), as written.
void named_files(const nlohmann::json& j, int depth, std::vector<std::string>& out) {
  if (depth > kMaxJsonDepth) return;
  if (j.is_object()) {
    for (const auto& [key, value] : j.items()) {
      if (key == "file" && value.is_string()) out.push_back(value.get<std::string>());
      named_files(value, depth + 1, out);
    }
  } else if (j.is_array()) {
    for (const auto& v : j) named_files(v, depth + 1, out);
  }
}

// The same, relative to `base`.
void named_files(const nlohmann::json& j, const std::filesystem::path& base,
                 std::vector<std::filesystem::path>& out) {
  std::vector<std::string> names;
  named_files(j, 0, names);
  for (const std::string& name : names) {
    std::filesystem::path f = name;
    out.push_back(f.is_absolute() ? f : base / f);
  }
}

nlohmann::json read_json_file(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::string text((std::istreambuf_iterator<char>(in)), {});
  return nlohmann::json::parse(text, nullptr, false);
}

size_t bytes_of(const Scene& s) {
  return s.mesh->positions.size() * sizeof(Vec3) * 2 + s.mesh->indices.size() * sizeof(uint32_t) +
         4096;
}

std::string limits_key(const SceneLimits& l) {
  return std::to_string(l.max_image) + "," + std::to_string(l.max_voxels) + "," +
         std::to_string(l.max_lights);
}

}  // namespace

template <class Load>
std::shared_ptr<const Scene> SceneLibrary::get(const std::string& key,
                                               std::vector<std::filesystem::path> files,
                                               double* load_ms, Load load) {
  std::vector<std::pair<std::filesystem::path, std::filesystem::file_time_type>> stamps;
  for (auto& f : files) {
    std::error_code ec;
    stamps.emplace_back(f, std::filesystem::last_write_time(f, ec));
  }
  if (load_ms) *load_ms = 0;
  {
    std::lock_guard lock(mutex_);
    for (auto it = entries_.begin(); it != entries_.end(); ++it) {
      if (it->key != key) continue;
      if (it->files == stamps) {
        entries_.splice(entries_.begin(), entries_, it);
        ++hits_;
        return it->scene;
      }
      bytes_ -= it->bytes;  // changed on disk: load again
      entries_.erase(it);
      break;
    }
  }
  // Loaded outside the lock: a slow import does not hold other requests.
  auto start = std::chrono::steady_clock::now();
  auto scene = std::make_shared<const Scene>(load());
  if (load_ms)
    *load_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  std::lock_guard lock(mutex_);
  ++loads_;
  for (auto it = entries_.begin(); it != entries_.end(); ++it)
    if (it->key == key) {  // loaded meanwhile by another request
      bytes_ -= it->bytes;
      entries_.erase(it);
      break;
    }
  Entry e{key, std::move(stamps), scene, bytes_of(*scene)};
  bytes_ += e.bytes;
  entries_.push_front(std::move(e));
  while (bytes_ > max_bytes_ && entries_.size() > 1) {
    bytes_ -= entries_.back().bytes;
    entries_.pop_back();
  }
  return scene;
}

std::shared_ptr<const Scene> SceneLibrary::load(const std::filesystem::path& file,
                                                const SceneLimits& limits, double* load_ms) {
  std::vector<std::filesystem::path> files{file};
  if (nlohmann::json j = read_json_file(file); !j.is_discarded())
    named_files(j, file.parent_path(), files);
  return get("file:" + limits_key(limits) + ":" + file.string(), std::move(files), load_ms,
             [&] { return load_scene(file, limits); });
}

std::shared_ptr<const Scene> SceneLibrary::parse(const nlohmann::json& scene,
                                                 const std::filesystem::path& base_dir,
                                                 const SceneLimits& limits, double* load_ms) {
  std::vector<std::filesystem::path> files;
  named_files(scene, base_dir, files);
  return get(
      "json:" + sha256_hex(limits_key(limits) + ":" + base_dir.string() + ":" + scene.dump()),
      std::move(files), load_ms, [&] { return parse_scene(scene, base_dir, limits); });
}

std::vector<std::string> SceneLibrary::missing_files(const std::filesystem::path& file) {
  nlohmann::json j = read_json_file(file);
  std::vector<std::string> names, missing;
  if (!j.is_discarded()) named_files(j, 0, names);
  for (const std::string& name : names) {
    std::filesystem::path f = name;
    std::error_code ec;
    if (!std::filesystem::is_regular_file(f.is_absolute() ? f : file.parent_path() / f, ec))
      missing.push_back(name);
  }
  return missing;
}

SceneLibrary::Stats SceneLibrary::stats() const {
  std::lock_guard lock(mutex_);
  return {entries_.size(), bytes_, hits_, loads_};
}

}  // namespace scatter::server
