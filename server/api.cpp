#include "server/api.hpp"

#include <algorithm>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include <unistd.h>

#include <spdlog/spdlog.h>

#include "bake/cache.hpp"
#include "gpu/embedded_sources.hpp"
#include "gpu/error.hpp"
#include "protocol/json_reader.hpp"
#include "scene/density.hpp"
#include "scene/mesh.hpp"
#include "scene/scene.hpp"

namespace scatter::server {
namespace {

HttpResponse json_response(const nlohmann::json& j, int status = 200) {
  return {status, "application/json", j.dump(), {}};
}

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

bool is_asset_id(const std::string& s) { return is_bake_key(s); }

// Replaces every {"asset": ID} field of an inline scene by {"file": PATH} of the uploaded file,
// after check_file_fields: the paths are the server's own.
void resolve_assets(nlohmann::json& j, const std::string& path, const std::filesystem::path& dir) {
  if (j.is_object()) {
    if (j.contains("asset")) {
      std::string p = path + ".asset";
      if (!j["asset"].is_string() || !is_asset_id(j["asset"].get<std::string>()))
        throw ValidationError(p, "must be an asset id (64 hex digits, from POST /api/assets)");
      if (j.contains("file")) throw ValidationError(p, "give \"asset\" or \"file\", not both");
      std::string id = j["asset"];
      std::filesystem::path file;
      for (const char* ext : {".obj", ".ply", ".stl", ".glb", ".off", ".grid.json"})
        if (!dir.empty() && std::filesystem::exists(dir / (id + ext))) file = dir / (id + ext);
      if (file.empty()) throw ValidationError(p, "no uploaded asset " + id);
      j.erase("asset");
      j["file"] = file.string();
    }
    for (auto& [key, value] : j.items()) resolve_assets(value, path + "." + key, dir);
  } else if (j.is_array()) {
    for (size_t i = 0; i < j.size(); ++i) resolve_assets(j[i], path + "[" + std::to_string(i) + "]", dir);
  }
}

// Query parameters of a target ("/a?x=1&y=2").
std::map<std::string, std::string> query_of(const std::string& target) {
  std::map<std::string, std::string> q;
  auto at = target.find('?');
  if (at == std::string::npos) return q;
  std::string rest = target.substr(at + 1);
  size_t start = 0;
  while (start <= rest.size()) {
    size_t end = rest.find('&', start);
    if (end == std::string::npos) end = rest.size();
    std::string kv = rest.substr(start, end - start);
    auto eq = kv.find('=');
    if (eq != std::string::npos) q[kv.substr(0, eq)] = kv.substr(eq + 1);
    start = end + 1;
  }
  return q;
}

std::vector<double> numbers(const std::string& text, size_t count, const std::string& field) {
  std::vector<double> v;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    try {
      size_t used = 0;
      v.push_back(std::stod(item, &used));
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw ValidationError(field, "\"" + item + "\" is not a number");
    }
  }
  if (v.size() != count) throw ValidationError(field, "needs " + std::to_string(count) + " comma-separated numbers");
  return v;
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
    for (const char* state : {"queued", "running", "done", "failed", "cancelled"}) {
      auto counts = bakes_.counts();
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

HttpResponse Api::assets(const HttpRequest& request) {
  const auto& dir = options_.assets_dir;
  auto describe = [&](const std::filesystem::path& file) {
    std::string name = file.filename().string();
    std::string id = name.substr(0, 64);
    bool grid = name.size() > 64 && name.substr(64) == ".grid.json";
    nlohmann::json j = {{"id", id}, {"kind", grid ? "grid" : "mesh"}};
    std::error_code ec;
    j["bytes"] = std::filesystem::file_size(grid ? dir / (id + ".raw") : file, ec);
    if (!grid) j["format"] = file.extension().string().substr(1);
    return j;
  };
  if (request.method == "GET") {
    nlohmann::json list = nlohmann::json::array();
    std::error_code ec;
    if (!dir.empty())
      for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
        std::string name = e.path().filename().string();
        if (name.size() < 65 || !is_asset_id(name.substr(0, 64)) || name.find(".tmp") != std::string::npos) continue;
        if (name.substr(64) == ".raw") continue;  // a grid's data, listed with its header
        list.push_back(describe(e.path()));
      }
    return json_response({{"assets", list}});
  }
  if (request.method != "POST") return error(405, request.method + " is not allowed on /api/assets: use POST or GET");
  if (dir.empty()) return error(503, "this server keeps no assets (start it with a --cache-dir)");
  auto q = query_of(request.target);
  std::string kind = q.count("kind") ? q["kind"] : "mesh";
  if (kind != "mesh" && kind != "grid") throw ValidationError("kind", "must be mesh or grid");
  if (request.body.empty()) throw ValidationError("body", "is empty: send the file's bytes");
  std::filesystem::create_directories(dir);
  // Written under a temporary name, checked, then renamed: a bad upload leaves nothing behind.
  static std::atomic<unsigned> serial{0};
  std::string tmp = ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(serial++);
  // Messages name "the upload", not the server's files.
  auto plain = [&](std::string m, const std::filesystem::path& p) {
    for (const std::string& s : {p.string(), p.filename().string()})
      for (size_t at; !s.empty() && (at = m.find(s)) != std::string::npos;) m.replace(at, s.size(), "the upload");
    return m;
  };
  auto write = [&](const std::filesystem::path& p, const std::string& bytes) {
    std::ofstream out(p, std::ios::binary);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!out) throw std::runtime_error("cannot write " + p.string());
  };
  nlohmann::json info;
  if (kind == "mesh") {
    std::string format = q.count("format") ? q["format"] : "";
    static const std::set<std::string> kFormats = {"obj", "ply", "stl", "glb", "off"};
    if (!kFormats.count(format)) throw ValidationError("format", "must be one of obj, ply, stl, glb, off");
    const std::string id = sha256_hex(request.body);
    auto final_path = dir / (id + "." + format);
    if (std::filesystem::exists(final_path)) return json_response(describe(final_path), 200);
    auto tmp_path = dir / (id + tmp + "." + format);
    write(tmp_path, request.body);
    try {
      Mesh mesh = load_mesh(tmp_path);
      WatertightReport w = check_watertight(mesh);
      if (!w.watertight()) throw ValidationError("body", "the mesh is not watertight (" + w.summary() + ")");
      Vec3 size = mesh.bounds().size();
      if (!(std::abs(mesh.volume()) > 1e-9 * size.x * size.y * size.z) || std::max({size.x, size.y, size.z}) <= 0)
        throw ValidationError("body", "the mesh encloses no volume");
      info = {{"triangles", mesh.triangle_count()}};
    } catch (const ValidationError&) {
      std::filesystem::remove(tmp_path);
      throw;
    } catch (const std::exception& e) {
      std::filesystem::remove(tmp_path);
      throw ValidationError("body", "is not a readable " + format + " mesh: " + plain(e.what(), tmp_path));
    }
    std::filesystem::rename(tmp_path, final_path);
    nlohmann::json j = describe(final_path);
    j.update(info);
    return json_response(j, 201);
  }
  if (!q.count("dims")) throw ValidationError("dims", "is required for a grid: nx,ny,nz");
  if (!q.count("bounds")) throw ValidationError("bounds", "is required for a grid: x0,y0,z0,x1,y1,z1");
  std::vector<double> d = numbers(q["dims"], 3, "dims"), b = numbers(q["bounds"], 6, "bounds");
  // A grid is its values and where they sit: both name it.
  const std::string id = sha256_hex(nlohmann::json({d, b}).dump() + "\n" + request.body);
  for (double v : d)
    if (v != std::floor(v) || v < 1 || v > 512) throw ValidationError("dims", "must be integers in [1, 512]");
  nlohmann::json header = {{"dims", {int(d[0]), int(d[1]), int(d[2])}}, {"format", "float32"}, {"data", id + ".raw"},
                           {"bounds", {{"min", {b[0], b[1], b[2]}}, {"max", {b[3], b[4], b[5]}}}}};
  auto final_header = dir / (id + ".grid.json");
  if (std::filesystem::exists(final_header)) return json_response(describe(final_header), 200);
  // Checked by the scene loader itself, from a temporary header next to the data.
  write(dir / (id + ".raw"), request.body);
  auto tmp_header = dir / (id + tmp + ".grid.json");
  write(tmp_header, header.dump());
  try {
    nlohmann::json density = {{"type", "grid"}, {"file", tmp_header.string()}};
    JsonObject o(density, "grid");
    parse_density(o, dir);
  } catch (const std::exception& e) {
    std::filesystem::remove(tmp_header);
    std::filesystem::remove(dir / (id + ".raw"));
    throw ValidationError("body", "is not a valid grid: " + plain(plain(e.what(), tmp_header), dir / (id + ".raw")));
  }
  std::filesystem::rename(tmp_header, final_header);
  return json_response(describe(final_header), 201);
}

// What a bake depends on in a scene: the solid, the medium and the grid resolution (not the camera,
// lights or image size), as canonical JSON.
nlohmann::json bake_identity(const nlohmann::json& scene) {
  nlohmann::json id = nlohmann::json::object();
  for (const char* k : {"mesh", "medium", "voxels"})
    if (scene.is_object() && scene.contains(k)) id[k] = scene[k];
  return id;
}

HttpResponse Api::create_bake(const std::string& body) {
  nlohmann::json request = nlohmann::json::parse(body, nullptr, false);
  if (request.is_discarded()) throw ValidationError("body", "is not valid JSON");
  if (request.is_object() && !request.contains("pipeline")) request["pipeline"] = "single";
  JsonObject r(request, "");
  RenderSpec spec = read_render_spec(r, request, options_);
  r.finish();
  // The scene's JSON, for the job's identity.
  nlohmann::json scene_json;
  if (request.contains("scene")) {
    scene_json = request["scene"];
  } else {
    std::ifstream in(options_.scenes_dir / (request["scene_name"].get<std::string>() + ".json"));
    scene_json = nlohmann::json::parse(in, nullptr, false);
  }
  auto scene = std::make_shared<const Scene>(std::move(spec.scene));
  const std::string pipeline = spec.pipeline;
  const Settings settings = spec.settings;
  // Checked here on the network thread with a pipeline of its own (plan() needs no GPU), so that a
  // typo is a 400 and a POST never waits behind a running bake on the render thread.
  std::vector<std::pair<std::string, double>> stages;
  {
    gpu::Gpu unused;  // contexts are made on first use, and plan() makes none
    auto p = make_pipeline(pipeline, unused);
    p->plan(*scene, {p->supported_terms().front(), settings, nullptr});
    stages = p->bake_stages();
  }
  if (stages.empty()) throw ValidationError("pipeline", "pipeline " + pipeline + " needs no bake");
  nlohmann::json identity = {{"pipeline", pipeline}, {"settings", settings}, {"scene", bake_identity(scene_json)}};
  bool created = false;
  auto job = bakes_.submit(identity.dump(), pipeline, stages, [&](std::shared_ptr<BakeJob> j) {
    spdlog::info("event=bake_queued id={} pipeline={}", j->id(), pipeline);
    queue_.submit([j, scene, pipeline, settings](RenderQueue::Context& c) {
      j->run([&](const BakeProgress& progress) {
        Pipeline& p = c.pipeline(pipeline);
        return p.bake(*scene, {p.supported_terms().front(), settings, nullptr}, progress);
      });
      nlohmann::json s = j->status();
      spdlog::info("event=bake_finished id={} state={} cache_hit={} seconds={}", j->id(), s["state"].get<std::string>(),
                   s.value("cache_hit", false), s.value("seconds", 0.0));
      return 0;
    });
  }, &created);
  HttpResponse response = json_response(job->status(), created ? 202 : 200);
  response.headers.push_back({"Location", "/api/bakes/" + job->id()});
  return response;
}

HttpResponse Api::bakes(const HttpRequest& request, const std::string& path) {
  if (path == "/api/bakes") {
    if (request.method == "POST") return create_bake(request.body);
    if (request.method == "GET") {
      nlohmann::json list = nlohmann::json::array();
      for (const auto& j : bakes_.list()) list.push_back(j->status());
      return json_response({{"bakes", list}});
    }
    return error(405, request.method + " is not allowed on /api/bakes: use POST or GET");
  }
  std::string id = path.substr(std::string("/api/bakes/").size());
  auto job = bakes_.find(id);
  if (!job) return error(404, "no bake job " + id);
  if (request.method == "GET") return json_response(job->status());
  if (request.method == "DELETE") {
    if (!job->cancel()) return error(409, "bake job " + id + " has already " + (job->state() == BakeJob::State::Done ? "finished" : to_string(job->state())));
    return json_response(job->status(), 202);
  }
  return error(405, request.method + " is not allowed on /api/bakes/{id}: use GET or DELETE");
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
