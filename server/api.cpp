#include "server/api.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cctype>
#include <future>
#include <map>
#include <optional>

#include "bake/cache.hpp"
#include "core/errors.hpp"
#include "gpu/embedded_sources.hpp"
#include "pipelines/budget/planner.hpp"
#include "pipelines/registry.hpp"
#include "protocol/json_reader.hpp"
#include "scene/scene.hpp"
#include "server/api_util.hpp"

namespace scatter::server {
namespace {

// GET /api/pipelines: every pipeline's description and settings table (pipelines/registry.hpp).
const nlohmann::json& pipelines_json() {
  static const nlohmann::json j = [] {
    nlohmann::json list = nlohmann::json::array();
    for (const PipelineInfo* p : registry()) list.push_back(*p);
    return nlohmann::json{{"pipelines", list}};
  }();
  return j;
}

// Percent-decoding of one query value ("a%2Bb" -> "a+b", "+" -> " "); nullopt if malformed.
std::optional<std::string> percent_decode(std::string_view s) {
  std::string out;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '+') {
      out += ' ';
    } else if (s[i] != '%') {
      out += s[i];
    } else {
      if (i + 2 >= s.size() || !std::isxdigit(static_cast<unsigned char>(s[i + 1])) ||
          !std::isxdigit(static_cast<unsigned char>(s[i + 2])))
        return std::nullopt;
      out += static_cast<char>(std::stoi(std::string(s.substr(i + 1, 2)), nullptr, 16));
      i += 2;
    }
  }
  return out;
}

// Compares without an early exit, so that the time taken does not tell how much of a guess matched.
bool same_secret(std::string_view a, std::string_view b) {
  unsigned char diff = a.size() == b.size() ? 0 : 1;
  for (size_t i = 0; i < a.size(); ++i)
    diff |= static_cast<unsigned char>(a[i] ^ (i < b.size() ? b[i] : 0));
  return diff == 0;
}

// The browser client's file for a GET path ("/" is index.html): web/ files compiled into the
// binary, looked up by name (never on disk), of the kinds a page loads; null for anything else.
struct WebFile {
  std::string_view body;
  const char* type;
};
std::optional<WebFile> web_file(const std::string& path) {
  static const std::map<std::string, const char*> kTypes = {
      {".html", "text/html; charset=utf-8"},
      {".js", "text/javascript; charset=utf-8"},
      {".css", "text/css; charset=utf-8"}};
  std::string rel = path == "/" ? "index.html" : path.substr(1);
  if (path.empty() || path[0] != '/' || rel.empty() || rel.size() > 200 ||
      rel.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-_./") !=
          std::string::npos ||
      rel.find("..") != std::string::npos || rel.find("//") != std::string::npos || rel[0] == '.')
    return std::nullopt;
  auto dot = rel.rfind('.');
  auto type = kTypes.find(dot == std::string::npos ? "" : rel.substr(dot));
  if (type == kTypes.end()) return std::nullopt;
  const auto& files = gpu::embedded_sources();
  auto f = files.find("web/" + rel);
  if (f == files.end()) return std::nullopt;
  return WebFile{f->second, type->second};
}

}  // namespace

void check_file_fields(const nlohmann::json& j, const std::string& path, int depth) {
  if (depth > kMaxJsonDepth)
    throw ValidationError(path, "nests deeper than " + std::to_string(kMaxJsonDepth) + " levels");
  if (j.is_object()) {
    for (const auto& [key, value] : j.items()) {
      std::string p = path + "." + key;
      if (key == "file" && value.is_string()) {
        std::filesystem::path f = value.get<std::string>();
        bool escapes = f.is_absolute();
        for (const auto& part : f) escapes = escapes || part == "..";
        if (escapes)
          throw ValidationError(p,
                                "must be a path inside the server's scene folder (no absolute "
                                "paths, no \"..\")");
      }
      check_file_fields(value, p, depth + 1);
    }
  } else if (j.is_array()) {
    for (size_t i = 0; i < j.size(); ++i)
      check_file_fields(j[i], path + "[" + std::to_string(i) + "]", depth + 1);
  }
}

std::string without_paths(std::string m, const ApiOptions& o) {
  for (const auto& [dir, name] :
       {std::pair{o.assets_dir, std::string("asset ")}, std::pair{o.scenes_dir, std::string()}}) {
    if (dir.empty()) continue;
    for (std::string prefix : {dir.string() + "/", dir.string()})
      for (size_t at; !prefix.empty() && (at = m.find(prefix)) != std::string::npos;)
        m.replace(at, prefix.size(), name);
  }
  return m;
}

std::string busy_message(const RenderQueue& q) {
  return "the render queue is full (" + std::to_string(q.max_depth()) +
         " jobs waiting); try again shortly";
}

Api::Api(ApiOptions options, RenderQueue& queue, Metrics& metrics, RenderQueue* bakes,
         Offload offload)
    : options_(std::move(options)),
      queue_(queue),
      bake_queue_(bakes ? *bakes : queue),
      metrics_(metrics),
      offload_(offload ? std::move(offload) : Offload([](std::function<void()> f) { f(); })) {}

void Api::cancel_bakes() {
  for (const auto& j : bakes_.list()) j->cancel();
}

HttpResponse Api::error(int status, const std::string& message, const std::string& field) {
  nlohmann::json j = {{"error", message}};
  if (!field.empty()) j["field"] = field;
  return json_response(j, status);
}

void Api::handle(const HttpRequest& request, Respond respond) {
  auto route_name = std::make_shared<std::string>("other");
  auto start = std::chrono::steady_clock::now();
  Respond once = [this, route_name, start, method = request.method,
                  respond = std::move(respond)](HttpResponse r) {
    metrics_.count_request(*route_name, r.status);
    spdlog::info("event=request method={} route={} status={} ms={:.1f}", method, *route_name,
                 r.status,
                 std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                     .count());
    respond(std::move(r));
  };
  // route() answers through `once`, or throws before it has: the error is the answer.
  try {
    route(request, *route_name, once);
  } catch (const RequestTooCostly& e) {
    once(error(413, e.what(), e.field()));
  } catch (const ServerUnavailable& e) {
    once(error(503, without_paths(e.what(), options_), e.field()));
  } catch (const ValidationError& e) {
    once(error(400, without_paths(e.what(), options_), e.field()));
  } catch (const gpu::GpuError& e) {
    once(error(503, without_paths(e.what(), options_)));
  } catch (const BakeJobs::Busy& e) {
    once(error(503, e.what()));
  } catch (const std::exception& e) {
    // A bad request must never take the daemon down; report and go on.
    spdlog::error("event=internal_error route={} error=\"{}\"", *route_name, e.what());
    once(error(500, "internal error: " + without_paths(e.what(), options_)));
  }
}

HttpResponse Api::handle(const HttpRequest& request) {
  std::promise<HttpResponse> answer;
  auto result = answer.get_future();
  handle(request, [&answer](HttpResponse r) { answer.set_value(std::move(r)); });
  return result.get();
}

bool Api::quick(const HttpRequest& request) {
  std::string path = request.target.substr(0, request.target.find('?'));
  if (request.method == "GET")
    return path == "/api/health" || path == "/api/pipelines" || path == "/metrics" ||
           path == "/api/assets" || path == "/api/bakes" || path.rfind("/api/bakes/", 0) == 0 ||
           web_file(path).has_value();
  return request.method == "DELETE" && path.rfind("/api/bakes/", 0) == 0;
}

void Api::route(const HttpRequest& request, std::string& route_name, const Respond& respond) {
  std::string path = request.target.substr(0, request.target.find('?'));
  if (!authorized(request)) {
    route_name = "unauthorized";
    return respond(error(401, "this server needs a token: send \"Authorization: Bearer TOKEN\""));
  }
  static const std::map<std::string, std::string> kMethods = {{"/api/health", "GET"},
                                                              {"/api/pipelines", "GET"},
                                                              {"/api/devices", "GET"},
                                                              {"/api/render", "POST"},
                                                              {"/metrics", "GET"}};
  if (path == "/api/assets") {
    route_name = path;
    return respond(assets(request));
  }
  if (path == "/api/bakes" || path.rfind("/api/bakes/", 0) == 0) {
    route_name = "/api/bakes";
    return respond(bakes(request, path));
  }
  auto it = kMethods.find(path);
  if (it != kMethods.end()) {
    route_name = path;
    if (request.method != it->second)
      return respond(
          error(405, request.method + " is not allowed on " + path + ": use " + it->second));
    if (path == "/api/health") return respond(health());
    if (path == "/api/pipelines") return respond(json_response(pipelines_json()));
    if (path == "/api/devices") return devices(respond);
    if (path == "/api/render") return render(request, respond);
    return respond(metrics_text());
  }
  // The browser client (web/), compiled into the binary.
  if (auto f = web_file(path); f && request.method == "GET") {
    route_name = "static";
    return respond({200, f->type, std::string(f->body), {}});
  }
  route_name = "not_found";
  respond(error(404, "no such resource: " + path));
}

HttpResponse Api::metrics_text() {
  std::string text =
      metrics_.text(queue_.depth()) +
      "# HELP scatter_sessions Live WebSocket sessions.\n# TYPE scatter_sessions gauge\n"
      "scatter_sessions " +
      std::to_string(sessions_.load()) + "\n";
  text += "# HELP scatter_bakes Bake jobs by state.\n# TYPE scatter_bakes gauge\n";
  auto counts = bakes_.counts();
  for (const char* state : {"queued", "running", "done", "failed", "cancelled"})
    text += std::string("scatter_bakes{state=\"") + state + "\"} " + std::to_string(counts[state]) +
            "\n";
  if (BakeCache* cache = queue_.cache()) {
    CacheStats c = cache->stats();
    text +=
        "# HELP scatter_bake_cache_lookups_total Bake cache lookups by outcome.\n"
        "# TYPE scatter_bake_cache_lookups_total counter\n";
    text += "scatter_bake_cache_lookups_total{result=\"memory_hit\"} " +
            std::to_string(c.memory_hits) + "\n";
    text += "scatter_bake_cache_lookups_total{result=\"disk_hit\"} " + std::to_string(c.disk_hits) +
            "\n";
    text += "scatter_bake_cache_lookups_total{result=\"miss\"} " + std::to_string(c.misses) + "\n";
    text +=
        "scatter_bake_cache_lookups_total{result=\"corrupt\"} " + std::to_string(c.corrupt) + "\n";
  }
  SceneLibrary::Stats l = scenes_.stats();
  text +=
      "# HELP scatter_scene_library_scenes Parsed scenes kept for reuse.\n# TYPE "
      "scatter_scene_library_scenes gauge\n";
  text += "scatter_scene_library_scenes " + std::to_string(l.scenes) + "\n";
  text +=
      "# HELP scatter_scene_loads_total Scenes parsed (library misses).\n# TYPE "
      "scatter_scene_loads_total counter\n";
  text += "scatter_scene_loads_total " + std::to_string(l.loads) + "\n";
  return {200, "text/plain; version=0.0.4", text, {}};
}

bool Api::acquire_session() {
  int n = sessions_.load();
  while (n < options_.max_sessions)
    if (sessions_.compare_exchange_weak(n, n + 1)) return true;
  return false;
}

void Api::release_session() {
  --sessions_;
}

std::map<std::string, std::string> parse_query(std::string_view target) {
  std::map<std::string, std::string> q;
  auto at = target.find('?');
  if (at == std::string_view::npos) return q;
  std::string_view query = target.substr(at + 1);
  while (!query.empty()) {
    std::string_view item = query.substr(0, query.find('&'));
    query.remove_prefix(std::min(query.size(), item.size() + 1));
    auto eq = item.find('=');
    if (eq == std::string_view::npos) continue;
    auto key = percent_decode(item.substr(0, eq)), value = percent_decode(item.substr(eq + 1));
    if (key && value) q.emplace(*key, *value);
  }
  return q;
}

bool Api::authorized(const HttpRequest& request) const {
  if (options_.token.empty() || same_secret(request.authorization, "Bearer " + options_.token))
    return true;
  auto q = parse_query(request.target);
  auto token = q.find("token");
  return token != q.end() && same_secret(token->second, options_.token);
}

HttpResponse Api::health() {
  double uptime =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
  return json_response({{"status", "ok"},
                        {"version", "0.1.0"},
                        {"uptime_s", uptime},
                        {"queue_depth", queue_.depth()},
                        {"render_busy", queue_.busy()},
                        {"bake_queue_depth", bake_queue_.depth()},
                        {"bake_busy", bake_queue_.busy()},
                        {"sessions", sessions_.load()}});
}

void Api::devices(const Respond& respond) {
  RenderQueue::Job job;
  job.dropped = [respond](const std::string& why) {
    respond(error(503, "devices not listed: " + why));
  };
  job.run = [respond](RenderQueue::Context& c) {
    nlohmann::json cl = nlohmann::json::array();
    for (const auto& d : gpu::list_cl_devices())
      cl.push_back({{"id", std::to_string(d.platform) + ":" + std::to_string(d.device)},
                    {"name", d.name},
                    {"version", d.version},
                    {"type", d.type},
                    {"global_memory", d.global_memory},
                    {"fp64", d.fp64}});
    nlohmann::json gl;
    try {
      gl = {{"renderer", c.gpu.gl().renderer()}, {"version", c.gpu.gl().version()}};
    } catch (const gpu::GpuError& e) {
      gl = {{"error", e.what()}};
    }
    respond(json_response({{"opencl", cl}, {"opengl", gl}}));
  };
  if (!queue_.post(std::move(job))) respond(error(503, busy_message(queue_)));
}

}  // namespace scatter::server
