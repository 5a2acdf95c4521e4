// Pieces the Api's route files share (server/api*.cpp); not part of the Api's interface.
#pragma once

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "server/api.hpp"

namespace scatter::server {

inline HttpResponse json_response(const nlohmann::json& j, int status = 200) {
  return {status, "application/json", j.dump(), {}};
}

// The query parameters of a target ("/a?x=1&y=%2B" -> {x: "1", y: "+"}), percent-decoded ("+" is
// a space); a parameter without "=" or with a malformed escape is left out; the first of a
// repeated name wins.
std::map<std::string, std::string> parse_query(std::string_view target);

// Replaces every {"asset": ID} field of an inline scene by {"file": PATH} of the uploaded file in
// `dir`; throws ValidationError naming the field for a malformed or unknown id.
void resolve_assets(nlohmann::json& j, const std::string& path, const std::filesystem::path& dir);

}  // namespace scatter::server
