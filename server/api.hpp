// The REST API as plain request -> response logic, apart from the network code so that it can be
// tested without sockets (and, for the routes that do not render, without a GPU).
//
//   GET  /api/health     {"status": "ok", "version", "uptime_s", "queue_depth"}
//   GET  /api/pipelines  {"pipelines": [...]}
//   GET  /api/devices    OpenCL devices and the OpenGL renderer (asked on the render thread)
//   POST /api/render     {"scene": {...} | "scene_name": "bunny", "pipeline": "auto",
//                         "terms": "single", "format": "png"|"jpg"|"exr"|"json",
//                         "settings": {"spp": 64}, "exposure": 1}
//   POST   /api/assets?kind=mesh&format=obj|ply|stl|glb|off   the file as the body
//   POST   /api/assets?kind=grid&dims=X,Y,Z&bounds=x0,y0,z0,x1,y1,z1   raw float32, x fastest
//                           201 {"id" (SHA-256 of the content), "kind", "bytes", ...}; 200 if known;
//                           scenes then name it: "mesh": {"asset": ID}, density {"type": "grid",
//                           "asset": ID}
//   GET    /api/assets      {"assets": [{"id", "kind", "bytes", ...}]}
//   POST   /api/bakes       {"scene": {...} | "scene_name", "pipeline": "single", "settings": {...}}
//                           202 and the job's status (a new job), or 200 and the existing job's
//   GET    /api/bakes       {"bakes": [status, ...]}
//   GET    /api/bakes/{id}  {"id", "state", "stage", "progress" 0-1, "timings_ms", "error", ...}
//   DELETE /api/bakes/{id}  cancels a queued or running job (202); 409 once it has finished
//   GET  /metrics        Prometheus text
//
// Errors are JSON {"error": "...", "field": "..."} with 400, 401, 404, 405, 409, 413 or 503.
#pragma once

#include <atomic>
#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

#include "bake/jobs.hpp"
#include "protocol/json_reader.hpp"
#include "scene/scene.hpp"
#include "server/metrics.hpp"
#include "server/render_queue.hpp"

namespace scatter::server {

struct ApiOptions {
  std::string token;                 // when set, every request needs "Authorization: Bearer TOKEN"
  std::filesystem::path scenes_dir;  // where scene_name and relative mesh files are looked up
  int max_image = 2048;              // pixels per side for a render request
  size_t max_message_bytes = 64 << 20;  // largest WebSocket message
  int max_sessions = 16;                // live WebSocket sessions at once
  int idle_refine_ms = 200;             // a still view is re-rendered at full size after this
  std::filesystem::path assets_dir;     // uploaded assets; empty: uploads are refused (503)
};

struct HttpRequest {
  std::string method;
  std::string target;
  std::string body;
  std::string authorization;
};

struct HttpResponse {
  int status = 200;
  std::string content_type = "application/json";
  std::string body;
  std::vector<std::pair<std::string, std::string>> headers;
};

class Api {
 public:
  Api(ApiOptions options, RenderQueue& queue, Metrics& metrics);
  HttpResponse handle(const HttpRequest& request);
  // Whether the request carries the token (header "Authorization: Bearer T", or "?token=T" for
  // WebSocket clients, which cannot set headers); true when no token is set.
  bool authorized(const HttpRequest& request) const;

  // Takes a live-session slot; false when --max-sessions are in use. release_session() gives it back.
  bool acquire_session();
  void release_session();
  int sessions() const { return sessions_; }

  RenderQueue& queue() { return queue_; }
  Metrics& metrics() { return metrics_; }
  const ApiOptions& options() const { return options_; }

  static HttpResponse error(int status, const std::string& message, const std::string& field = "");

  // What a render request asks for; shared by POST /api/render and WebSocket hello messages.
  struct RenderSpec {
    Scene scene;
    std::string pipeline = "auto", terms, format = "png";
    Settings settings;
    double exposure = 1.0;
  };
  // Reads the fields of `r` (an object over `json`): scene or scene_name, pipeline, terms, format,
  // settings, exposure. Leaves other fields for the caller; throws ValidationError. An inline
  // scene's "asset" fields become the uploaded files' paths.
  static RenderSpec read_render_spec(JsonObject& r, const nlohmann::json& json, const ApiOptions& options);
  // Renders on the render thread and records the metrics; waits for the result.
  static RenderResult render_on_queue(RenderQueue& queue, Metrics& metrics, const Scene& scene,
                                      const std::string& pipeline, const std::string& terms,
                                      const Settings& settings);

 private:
  HttpResponse route(const HttpRequest& request, std::string& route_name);
  HttpResponse health();
  HttpResponse devices();
  HttpResponse render(const std::string& body);
  HttpResponse bakes(const HttpRequest& request, const std::string& path);
  HttpResponse assets(const HttpRequest& request);
  HttpResponse create_bake(const std::string& body);

  ApiOptions options_;
  RenderQueue& queue_;
  Metrics& metrics_;
  std::chrono::steady_clock::time_point started_ = std::chrono::steady_clock::now();
  std::atomic<int> sessions_{0};
  BakeJobs bakes_;
};

}  // namespace scatter::server
