// JSON for a live session's messages about its scene (server/ws_session.hpp, docs/API.md): the
// {"type": "scene"} message a hello with a request is answered with, and its parts.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>

#include "scene/scene.hpp"

namespace scatter {

nlohmann::json vec_json(const Vec3& v);
// A light as a scene's "lights" holds it (parse_lights reads it back to the same light).
nlohmann::json light_json(const Light& l);
nlohmann::json camera_json(const Camera& c);
// The scene names a client may ask for: the .json files of `dir`, sorted.
nlohmann::json scene_names(const std::filesystem::path& dir);
// What a client needs to edit the scene it sees: its JSON (the file of a shipped scene, or the
// inline scene as sent), its camera, lights and bounds, and the names of the shipped scenes.
nlohmann::json scene_message(const nlohmann::json& hello, const Scene& scene,
                             const std::filesystem::path& scenes_dir, long long request);

}  // namespace scatter
