// REST bodies (POST /api/render, POST /api/bakes, the WebSocket "hello"): the body parsed as the
// server parses it (parse_json, depth-bounded), then Api::read_render_spec with the server's own
// options (scenes folder, assets folder) and a scene library, finish() (unknown fields), and the
// request's cost estimate (Api::check_cost), all of which need no GPU; and the bytes as a query
// string (parse_query, percent-decoding).
#include <cstddef>
#include <cstdint>
#include <stdexcept>

#include "fuzz_util.hpp"
#include "server/api.hpp"
#include "server/api_util.hpp"
#include "server/scene_library.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view body(reinterpret_cast<const char*>(data), size);
  static const scatter::server::ApiOptions options = [] {
    scatter::server::ApiOptions o;
    o.scenes_dir = scatter::fuzz::assets_dir();
    o.assets_dir = scatter::fuzz::assets_dir();
    return o;
  }();
  static scatter::server::SceneLibrary library(64 << 20);
  // The same bytes as a request target's query string (crashes and sanitizer reports are the
  // finding).
  (void)scatter::server::parse_query("/api/assets?" + std::string(body));
  nlohmann::json request;
  if (!scatter::fuzz::parse(body, request)) return 0;
  try {
    scatter::JsonObject r(request, "");
    auto spec = scatter::server::Api::read_render_spec(r, request, options, library);
    r.finish();
    scatter::fuzz::check_mesh(*spec.scene->mesh);
    scatter::server::Api::check_cost(options, spec.pipeline, *spec.scene, spec.terms, spec.settings,
                                     false);
  } catch (const std::runtime_error&) {
  }
  return 0;
}
