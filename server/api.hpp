// The REST API as plain request -> response logic, apart from the network code so that it can be
// tested without sockets (and, for the routes that do not render, without a GPU).
//
//   GET  /api/health     {"status": "ok", "version", "uptime_s", "queue_depth"}
//   GET  /api/pipelines  {"pipelines": [...]}
//   GET  /api/devices    OpenCL devices and the OpenGL renderer (asked on the render thread)
//   POST /api/render     {"scene": {...} | "scene_name": "bunny", "pipeline": "auto",
//                         "terms": "single", "format": "png"|"jpg"|"exr"|"json",
//                         "settings": {"spp": 64}, "exposure": 1}
//   GET  /metrics        Prometheus text
//
// Errors are JSON {"error": "...", "field": "..."} with 400, 401, 404, 405, 413 or 503.
#pragma once

#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

#include "server/metrics.hpp"
#include "server/render_queue.hpp"

namespace scatter::server {

struct ApiOptions {
  std::string token;                 // when set, every request needs "Authorization: Bearer TOKEN"
  std::filesystem::path scenes_dir;  // where scene_name and relative mesh files are looked up
  int max_image = 2048;              // pixels per side for a render request
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

  static HttpResponse error(int status, const std::string& message, const std::string& field = "");

 private:
  HttpResponse route(const HttpRequest& request, std::string& route_name);
  HttpResponse health();
  HttpResponse devices();
  HttpResponse render(const std::string& body);

  ApiOptions options_;
  RenderQueue& queue_;
  Metrics& metrics_;
  std::chrono::steady_clock::time_point started_ = std::chrono::steady_clock::now();
};

}  // namespace scatter::server
