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
//                           201 {"id" (SHA-256 of the content), "kind", "bytes", ...}; 200 if
//                           known; scenes then name it: "mesh": {"asset": ID}, density {"type":
//                           "grid", "asset": ID}
//   GET    /api/assets      {"assets": [{"id", "kind", "bytes", ...}]}
//   POST   /api/bakes       {"scene": {...} | "scene_name", "pipeline": "single", "settings":
//   {...}}
//                           202 and the job's status (a new job), or 200 and the existing job's
//   GET    /api/bakes       {"bakes": [status, ...]}
//   GET    /api/bakes/{id}  {"id", "state", "stage", "progress" 0-1, "timings_ms", "error", ...}
//   DELETE /api/bakes/{id}  cancels a queued or running job (202); 409 once it has finished
//   GET  /metrics        Prometheus text
//
// Errors are JSON {"error": "...", "field": "..."} with 400, 401, 404, 405, 409, 413 or 503 (a
// server-side problem: no GPU, a shipped scene whose files are missing, a full queue).
#pragma once

#include <atomic>
#include <chrono>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "bake/jobs.hpp"
#include "protocol/json_reader.hpp"
#include "scene/scene.hpp"
#include "server/metrics.hpp"
#include "server/render_job.hpp"
#include "server/render_queue.hpp"
#include "server/scene_library.hpp"

namespace scatter::server {

struct ApiOptions {
  std::string token;                 // when set, every request needs "Authorization: Bearer TOKEN"
  std::filesystem::path scenes_dir;  // where scene_name and relative mesh files are looked up
  int max_image = 2048;              // pixels per side for a render request
  size_t max_message_bytes = 64 << 20;  // largest WebSocket message
  int max_sessions = 16;                // live WebSocket sessions at once
  int idle_refine_ms = 200;             // a still view is refined after this (server/refine.hpp)
  double refine_pass_s = 1.0;           // what one reference pass of a still view aims to take
  int refine_max_passes = 64;           // reference passes of a still view, at most
  double session_idle_s = 120;          // a live session that sends nothing for this long is closed
  double max_request_mb = 2048;      // estimated host + device memory one render or bake may take
  double max_render_s = 120;         // estimated (and enforced) seconds one render may take
  std::filesystem::path assets_dir;  // uploaded assets; empty: uploads are refused (503)
};

struct HttpRequest {
  std::string method;
  std::string target;
  std::string body;
  std::string authorization;
  std::shared_ptr<CancelToken> cancel;  // set by the connection: cancelled when the client goes
};

struct HttpResponse {
  int status = 200;
  std::string content_type = "application/json";
  std::string body;
  std::vector<std::pair<std::string, std::string>> headers;
};

class Api {
 public:
  using Respond = std::function<void(HttpResponse)>;
  // Runs a piece of CPU work (image encoding) somewhere other than the render thread.
  using Offload = std::function<void(std::function<void()>)>;

  // `bakes`: the queue bake jobs run on (null: the render queue). `offload`: where encoding runs
  // (empty: inline, on the render thread's callback).
  Api(ApiOptions options, RenderQueue& queue, Metrics& metrics, RenderQueue* bakes = nullptr,
      Offload offload = {});
  // Answers `request` through `respond`, exactly once, and never waits on the render thread:
  // routes that render queue a job and respond from its completion.
  void handle(const HttpRequest& request, Respond respond);
  // Waits for the answer: for tests and tools, never for the daemon's threads.
  HttpResponse handle(const HttpRequest& request);
  // Requests answered from memory at once (health, metrics, pipelines, bake status, asset list,
  // the web client): a network thread may run them inline.
  static bool quick(const HttpRequest& request);
  // Whether the request carries the token (header "Authorization: Bearer T", or "?token=T",
  // percent-decoded, for WebSocket clients, which cannot set headers); true when no token is set.
  bool authorized(const HttpRequest& request) const;

  // Takes a live-session slot; false when --max-sessions are in use. release_session() gives it
  // back.
  bool acquire_session();
  void release_session();
  int sessions() const { return sessions_; }

  RenderQueue& queue() { return queue_; }
  Metrics& metrics() { return metrics_; }
  const ApiOptions& options() const { return options_; }
  SceneLibrary& scenes() { return scenes_; }
  // Cancels every bake job (shutdown).
  void cancel_bakes();

  static HttpResponse error(int status, const std::string& message, const std::string& field = "");

  // What a render request asks for; shared by POST /api/render and WebSocket hello messages.
  struct RenderSpec {
    std::shared_ptr<const Scene> scene;
    std::string pipeline = "auto", terms, format = "png";
    Settings settings;
    double exposure = 1.0;
    double scene_load_ms = 0;  // > 0 when this request loaded the scene (not a library hit)
    // "quality": {"max_error": E, "refine_floor": F}: the error the client accepts (relative
    // RMSE against the reference), and where a still live view stops refining.
    std::optional<double> max_error;
    double refine_floor = 0.01;
  };
  // Reads the fields of `r` (an object over `json`): scene or scene_name, pipeline, terms, format,
  // settings, exposure, quality. Leaves other fields for the caller; throws ValidationError. An
  // inline scene's "asset" fields become the uploaded files' paths; shipped scenes come from
  // `library`.
  static RenderSpec read_render_spec(JsonObject& r, const nlohmann::json& json,
                                     const ApiOptions& options, SceneLibrary& library);
  // Throws ValidationError for an unknown pipeline, terms it cannot render (unless `terms` is
  // empty) or a setting it rejects, from the registry alone: no instance, no GPU.
  static void check_pipeline(const std::string& pipeline, const std::string& terms,
                             const Settings& settings);
  // Throws RequestTooCostly (413) when rendering (or baking) `scene` as asked is estimated past
  // --max-request-mb or --max-render-s; the message names the field and the limit.
  static void check_cost(const ApiOptions& options, const std::string& pipeline, const Scene& scene,
                         const std::string& terms, const Settings& settings, bool bake,
                         std::optional<double> max_error = std::nullopt);

 private:
  void route(const HttpRequest& request, std::string& route_name, const Respond& respond);
  HttpResponse health();
  HttpResponse metrics_text();
  void devices(const Respond& respond);
  void render(const HttpRequest& request, const Respond& respond);
  HttpResponse bakes(const HttpRequest& request, const std::string& path);
  HttpResponse assets(const HttpRequest& request);
  HttpResponse create_bake(const std::string& body);

  ApiOptions options_;
  RenderQueue& queue_;
  RenderQueue& bake_queue_;
  Metrics& metrics_;
  Offload offload_;
  std::chrono::steady_clock::time_point started_ = std::chrono::steady_clock::now();
  std::atomic<int> sessions_{0};
  BakeJobs bakes_;
  SceneLibrary scenes_;
};

}  // namespace scatter::server
