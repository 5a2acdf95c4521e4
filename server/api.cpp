#include "server/api.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <map>

#include "bake/cache.hpp"
#include "gpu/embedded_sources.hpp"
#include "gpu/error.hpp"
#include "protocol/json_reader.hpp"
#include "scene/scene.hpp"
#include "server/api_util.hpp"

namespace scatter::server {
namespace {

// Inline scenes may only name files inside the scenes folder: no absolute paths, no "..".
void check_file_fields(const nlohmann::json& j, const std::string& path) {
  if (j.is_object()) {
    for (const auto& [key, value] : j.items()) {
      std::string p = path + "." + key;
      if (key == "file" && value.is_string()) {
        std::filesystem::path f = value.get<std::string>();
        bool escapes = f.is_absolute();
        for (const auto& part : f) escapes = escapes || part == "..";
        if (escapes)
          throw ValidationError(p, "must be a path inside the server's scene folder (no absolute "
                                   "paths, no \"..\")");
      }
      check_file_fields(value, p);
    }
  } else if (j.is_array()) {
    for (size_t i = 0; i < j.size(); ++i) check_file_fields(j[i], path + "[" + std::to_string(i) + "]");
  }
}

}  // namespace

Api::Api(ApiOptions options, RenderQueue& queue, Metrics& metrics)
    : options_(std::move(options)), queue_(queue), metrics_(metrics) {}

HttpResponse Api::error(int status, const std::string& message, const std::string& field) {
  nlohmann::json j = {{"error", message}};
  if (!field.empty()) j["field"] = field;
  return json_response(j, status);
}

HttpResponse Api::handle(const HttpRequest& request) {
  std::string route_name = "other";
  HttpResponse r;
  auto start = std::chrono::steady_clock::now();
  try {
    r = route(request, route_name);
  } catch (const ValidationError& e) {
    r = error(400, e.what(), e.field());
  } catch (const gpu::GpuError& e) {
    r = error(503, e.what());
  } catch (const BakeJobs::Busy& e) {
    r = error(503, e.what());
  } catch (const std::exception& e) {
    // A bad request must never take the daemon down; report and go on.
    r = error(500, std::string("internal error: ") + e.what());
  }
  metrics_.count_request(route_name, r.status);
  spdlog::info("event=request method={} route={} status={} ms={:.1f}", request.method, route_name, r.status,
               std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  return r;
}

HttpResponse Api::route(const HttpRequest& request, std::string& route_name) {
  std::string path = request.target.substr(0, request.target.find('?'));
  if (!authorized(request)) {
    route_name = "unauthorized";
    return error(401, "this server needs a token: send \"Authorization: Bearer TOKEN\"");
  }
  static const std::map<std::string, std::string> kMethods = {
      {"/api/health", "GET"}, {"/api/pipelines", "GET"}, {"/api/devices", "GET"},
      {"/api/render", "POST"}, {"/metrics", "GET"}};
  if (path == "/api/assets") {
    route_name = path;
    return assets(request);
  }
  if (path == "/api/bakes" || path.rfind("/api/bakes/", 0) == 0) {
    route_name = "/api/bakes";
    return bakes(request, path);
  }
  auto it = kMethods.find(path);
  if (it != kMethods.end()) {
    route_name = path;
    if (request.method != it->second)
      return error(405, request.method + " is not allowed on " + path + ": use " + it->second);
    if (path == "/api/health") return health();
    if (path == "/api/pipelines") return json_response({{"pipelines", pipeline_names()}});
    if (path == "/api/devices") return devices();
    if (path == "/api/render") return render(request.body);
    std::string text = metrics_.text(queue_.depth()) +
                       "# HELP scatter_sessions Live WebSocket sessions.\n# TYPE scatter_sessions gauge\n"
                       "scatter_sessions " + std::to_string(sessions_.load()) + "\n";
    text += "# HELP scatter_bakes Bake jobs by state.\n# TYPE scatter_bakes gauge\n";
    auto counts = bakes_.counts();
    for (const char* state : {"queued", "running", "done", "failed", "cancelled"}) {
      text += std::string("scatter_bakes{state=\"") + state + "\"} " + std::to_string(counts[state]) + "\n";
    }
    if (BakeCache* cache = queue_.cache()) {
      CacheStats c = cache->stats();
      text += "# HELP scatter_bake_cache_lookups_total Bake cache lookups by outcome.\n"
              "# TYPE scatter_bake_cache_lookups_total counter\n";
      text += "scatter_bake_cache_lookups_total{result=\"memory_hit\"} " + std::to_string(c.memory_hits) + "\n";
      text += "scatter_bake_cache_lookups_total{result=\"disk_hit\"} " + std::to_string(c.disk_hits) + "\n";
      text += "scatter_bake_cache_lookups_total{result=\"miss\"} " + std::to_string(c.misses) + "\n";
      text += "scatter_bake_cache_lookups_total{result=\"corrupt\"} " + std::to_string(c.corrupt) + "\n";
    }
    return {200, "text/plain; version=0.0.4", text, {}};
  }
  // The browser client (web/), compiled into the binary.
  static const std::map<std::string, std::pair<std::string, std::string>> kStatic = {
      {"/", {"web/index.html", "text/html; charset=utf-8"}},
      {"/index.html", {"web/index.html", "text/html; charset=utf-8"}},
      {"/app.js", {"web/app.js", "text/javascript; charset=utf-8"}},
      {"/style.css", {"web/style.css", "text/css; charset=utf-8"}}};
  if (auto s = kStatic.find(path); s != kStatic.end() && request.method == "GET") {
    route_name = "static";
    return {200, s->second.second, std::string(gpu::embedded_source(s->second.first)), {}};
  }
  route_name = "not_found";
  return error(404, "no such resource: " + path);
}

bool Api::acquire_session() {
  int n = sessions_.load();
  while (n < options_.max_sessions)
    if (sessions_.compare_exchange_weak(n, n + 1)) return true;
  return false;
}

void Api::release_session() { --sessions_; }

bool Api::authorized(const HttpRequest& request) const {
  if (options_.token.empty() || request.authorization == "Bearer " + options_.token) return true;
  auto q = request.target.find('?');
  if (q == std::string::npos) return false;
  std::string query = "&" + request.target.substr(q + 1) + "&";
  return query.find("&token=" + options_.token + "&") != std::string::npos;
}

HttpResponse Api::health() {
  double uptime = std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
  return json_response({{"status", "ok"},
                        {"version", "0.1.0"},
                        {"uptime_s", uptime},
                        {"queue_depth", queue_.depth()},
                        {"sessions", sessions_.load()}});
}

HttpResponse Api::devices() {
  auto info = queue_.submit([](RenderQueue::Context& c) {
    nlohmann::json cl = nlohmann::json::array();
    for (const auto& d : gpu::list_cl_devices())
      cl.push_back({{"id", std::to_string(d.platform) + ":" + std::to_string(d.device)},
                    {"name", d.name}, {"version", d.version}, {"type", d.type},
                    {"global_memory", d.global_memory}, {"fp64", d.fp64}});
    nlohmann::json gl;
    try {
      gl = {{"renderer", c.gpu.gl().renderer()}, {"version", c.gpu.gl().version()}};
    } catch (const gpu::GpuError& e) {
      gl = {{"error", e.what()}};
    }
    return nlohmann::json{{"opencl", cl}, {"opengl", gl}};
  });
  return json_response(info.get());
}

Api::RenderSpec Api::read_render_spec(JsonObject& r, const nlohmann::json& request,
                                      const ApiOptions& options) {
  RenderSpec spec;
  spec.pipeline = r.string("pipeline", "auto");
  spec.terms = r.string("terms", "");
  spec.format = r.choice("format", {"png", "jpg", "exr", "json"}, "png");
  spec.exposure = r.number("exposure", 1.0, {1e-6, 1e6});
  if (auto s = r.optional_object("settings")) {
    for (const auto& [key, value] : request["settings"].items())
      spec.settings[key] = s->number(key, std::nullopt, {-1e9, 1e9});
    s->finish();
  }
  if (r.has("scene") == r.has("scene_name"))
    throw ValidationError("scene", "give exactly one of \"scene\" or \"scene_name\"");
  SceneLimits limits;
  limits.max_image = options.max_image;
  if (r.has("scene_name")) {
    std::string name = r.string("scene_name", std::nullopt);
    if (name.empty() || name.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789-_") != std::string::npos)
      throw ValidationError("scene_name", "must be the name of a shipped scene (letters, digits, - and _)");
    auto file = options.scenes_dir / (name + ".json");
    if (!std::filesystem::exists(file)) throw ValidationError("scene_name", "no scene named \"" + name + "\"");
    spec.scene = load_scene(file, limits);
  } else {
    check_file_fields(request["scene"], "scene");
    r.object("scene");  // marks it read; parse_scene validates it
    nlohmann::json scene = request["scene"];
    resolve_assets(scene, "scene", options.assets_dir);
    spec.scene = parse_scene(scene, options.scenes_dir, limits);
  }
  return spec;
}

RenderResult Api::render_on_queue(RenderQueue& queue, Metrics& metrics, const Scene& scene,
                                  const std::string& pipeline, const std::string& terms,
                                  const Settings& settings) {
  auto job = queue.submit([&](RenderQueue::Context& c) {
    Pipeline& p = c.pipeline(pipeline);
    RenderRequest req;
    req.settings = settings;
    auto ok = p.supported_terms();
    req.terms = !terms.empty() ? parse_terms(terms)
                : std::find(ok.begin(), ok.end(), Terms::All) != ok.end() ? Terms::All : ok.front();
    auto start = std::chrono::steady_clock::now();
    RenderResult result = p.render(scene, req);
    double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::vector<std::pair<std::string, double>> stages;
    for (const auto& t : result.timings) stages.emplace_back(t.stage, t.ms / 1000);
    metrics.observe_render(p.name(), seconds, stages);
    return result;
  });
  return job.get();
}

HttpResponse Api::render(const std::string& body) {
  nlohmann::json request = nlohmann::json::parse(body, nullptr, false);
  if (request.is_discarded()) throw ValidationError("body", "is not valid JSON");
  JsonObject r(request, "");
  RenderSpec spec = read_render_spec(r, request, options_);
  r.finish();
  RenderResult result = render_on_queue(queue_, metrics_, spec.scene, spec.pipeline, spec.terms, spec.settings);
  const std::string& format = spec.format;
  const double exposure = spec.exposure;

  nlohmann::json timings = nlohmann::json::object();
  for (const auto& t : result.timings) timings[t.stage] = t.ms;
  nlohmann::json plan = result.plan;
  if (format == "json")
    return json_response({{"pipeline", result.plan.pipeline}, {"plan", plan}, {"timings_ms", timings},
                          {"width", result.image.width}, {"height", result.image.height}});
  // Encoding runs here, on the network thread, not on the render thread.
  HttpResponse response{200, format == "exr" ? "image/x-exr" : (format == "png" ? "image/png" : "image/jpeg"),
                        encode_image(result.image, format, ToneMap{exposure}), {}};
  response.headers = {{"X-Scatter-Pipeline", result.plan.pipeline},
                      {"X-Scatter-Plan", plan.dump()},
                      {"X-Scatter-Timings", timings.dump()}};
  return response;
}

}  // namespace scatter::server
