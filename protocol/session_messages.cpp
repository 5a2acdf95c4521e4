#include "protocol/session_messages.hpp"

#include <algorithm>
#include <fstream>
#include <string>
#include <vector>

namespace scatter {

nlohmann::json vec_json(const Vec3& v) {
  return nlohmann::json::array({v.x, v.y, v.z});
}

nlohmann::json light_json(const Light& l) {
  static const char* kTypes[] = {"point", "directional", "spot"};
  nlohmann::json j = {{"type", kTypes[static_cast<int>(l.type)]}, {"color", vec_json(l.color)}};
  if (l.type != Light::Type::Directional) j["position"] = vec_json(l.position);
  if (l.type != Light::Type::Point) j["direction"] = vec_json(l.direction);
  j[l.type == Light::Type::Directional ? "irradiance" : "intensity"] = l.intensity;
  if (l.type == Light::Type::Spot) {
    j["inner_deg"] = l.inner_deg;
    j["outer_deg"] = l.outer_deg;
  }
  return j;
}

nlohmann::json scene_names(const std::filesystem::path& dir) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec))
    if (e.path().extension() == ".json") names.push_back(e.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

nlohmann::json scene_message(const nlohmann::json& hello, const Scene& scene,
                             const std::filesystem::path& scenes_dir, long long request) {
  nlohmann::json source;
  if (hello.contains("scene")) {
    source = hello["scene"];
  } else if (hello.contains("scene_name") && hello["scene_name"].is_string()) {
    std::ifstream in(scenes_dir / (hello["scene_name"].get<std::string>() + ".json"));
    if (in) source = nlohmann::json::parse(in, nullptr, false);
    if (source.is_discarded()) source = nullptr;
  }
  nlohmann::json lights = nlohmann::json::array();
  for (const Light& l : scene.lights) lights.push_back(light_json(l));
  Aabb b = scene.mesh->bounds();
  return {{"type", "scene"},
          {"request", request},
          {"scene_name", hello.value("scene_name", "")},
          {"source", source},
          {"camera", camera_json(scene.camera)},
          {"lights", lights},
          {"bounds", {{"min", vec_json(b.lo)}, {"max", vec_json(b.hi)}}},
          {"scenes", scene_names(scenes_dir)}};
}

nlohmann::json camera_json(const Camera& c) {
  return {{"position", vec_json(c.position)},
          {"target", vec_json(c.target)},
          {"up", vec_json(c.up)},
          {"fov_deg", c.fov_deg}};
}

}  // namespace scatter
