// A live session's hello (server/ws_session.hpp), read and checked apart from the session: the
// render spec (as POST /api/render's, scene loaded), the session-only fields (keep_view, request,
// medium, composite) and the scene message that answers it. Runs on the worker pool: loading a
// scene may take seconds.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>

#include "server/api.hpp"
#include "server/refine.hpp"

namespace scatter::server {

struct Hello {
  Api::RenderSpec spec;
  std::optional<Composite> composite;  // the multiple term still frames add
  bool keep_view = false;
  nlohmann::json scene_message;  // {"type": "scene", ...} (protocol/session_messages.hpp)
};

// Throws ValidationError naming the hello's field (or std::exception for a server-side
// problem); `request` is set as soon as it is read, so that an error can echo it.
Hello read_hello_message(const nlohmann::json& msg, const ApiOptions& options, SceneLibrary& scenes,
                         long long& request);

}  // namespace scatter::server
