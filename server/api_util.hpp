// Pieces the Api's route files share (server/api*.cpp); not part of the Api's interface.
#pragma once

#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "server/api.hpp"

namespace scatter::server {

inline HttpResponse json_response(const nlohmann::json& j, int status = 200) {
  return {status, "application/json", j.dump(), {}};
}

// Replaces every {"asset": ID} field of an inline scene by {"file": PATH} of the uploaded file in
// `dir`; throws ValidationError naming the field for a malformed or unknown id.
void resolve_assets(nlohmann::json& j, const std::string& path, const std::filesystem::path& dir);

}  // namespace scatter::server
