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

// Inline scenes may only name files inside the scenes folder: throws ValidationError (naming the
// field) for an absolute path or "..", or JSON nested deeper than kMaxJsonDepth.
void check_file_fields(const nlohmann::json& j, const std::string& path, int depth = 0);

// A message for the client: the server's own folders (assets, scenes) are not its business.
std::string without_paths(std::string m, const ApiOptions& o);

// The 503 text for a full render queue.
std::string busy_message(const RenderQueue& q);

}  // namespace scatter::server
