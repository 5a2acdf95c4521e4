// POST /api/render: the request read into a RenderSpec (also the bakes' and the sessions'),
// checked against the limits, and run on the render queue.
#include <spdlog/spdlog.h>

#include <filesystem>
#include <memory>
#include <optional>

#include "core/errors.hpp"
#include "pipelines/budget/planner.hpp"
#include "pipelines/registry.hpp"
#include "protocol/json_reader.hpp"
#include "scene/scene.hpp"
#include "server/api.hpp"
#include "server/api_util.hpp"

namespace scatter::server {

Api::RenderSpec Api::read_render_spec(JsonObject& r, const nlohmann::json& request,
                                      const ApiOptions& options, SceneLibrary& library) {
  RenderSpec spec;
  spec.pipeline = r.string("pipeline", "auto");
  spec.terms = r.string("terms", "");
  spec.format = r.choice("format", {"png", "jpg", "exr", "json"}, "png");
  spec.exposure = r.number("exposure", 1.0, {1e-6, 1e6});
  if (auto q = r.optional_object("quality")) {
    if (q->has("max_error")) spec.max_error = q->number("max_error", std::nullopt, {0, 1});
    spec.refine_floor = q->number("refine_floor", spec.refine_floor, {1e-4, 1});
    q->finish();
  }
  if (auto s = r.optional_object("settings")) {
    for (const auto& [key, value] : request["settings"].items())
      spec.settings[key] = s->number(key, std::nullopt, kAnyFinite);
    s->finish();
  }
  if (r.has("scene") == r.has("scene_name"))
    throw ValidationError("scene", "give exactly one of \"scene\" or \"scene_name\"");
  SceneLimits limits;
  limits.max_image = options.max_image;
  if (r.has("scene_name")) {
    std::string name = r.string("scene_name", std::nullopt);
    if (name.empty() ||
        name.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789-_") != std::string::npos)
      throw ValidationError("scene_name",
                            "must be the name of a shipped scene (letters, digits, - and _)");
    auto file = options.scenes_dir / (name + ".json");
    if (!std::filesystem::exists(file))
      throw ValidationError("scene_name", "no scene named \"" + name + "\"");
    // A shipped scene that cannot load is the server's problem (503), not the request's.
    std::vector<std::string> missing = SceneLibrary::missing_files(file);
    if (!missing.empty())
      throw ServerUnavailable("scene_name", "the server cannot show scene \"" + name +
                                                "\": the file it names, \"" + missing.front() +
                                                "\", is missing on the server");
    try {
      spec.scene = library.load(file, limits, &spec.scene_load_ms);
    } catch (const ValidationError&) {
      throw;
    } catch (const std::exception& e) {
      throw ServerUnavailable("scene_name", "the server cannot load scene \"" + name +
                                                "\": " + without_paths(e.what(), options));
    }
  } else {
    check_file_fields(request["scene"], "scene");
    r.object("scene");  // marks it read; parse_scene validates it
    nlohmann::json scene = request["scene"];
    resolve_assets(scene, "scene", options.assets_dir);
    try {
      spec.scene = library.parse(scene, options.scenes_dir, limits, &spec.scene_load_ms);
    } catch (const ValidationError& e) {
      throw ValidationError(
          e.field(),
          without_paths(std::string(e.what()).substr(e.field().empty() ? 0 : e.field().size() + 2),
                        options));
    } catch (
        const std::exception& e) {  // files it names that cannot be read: the request's problem
      throw ValidationError("scene", without_paths(e.what(), options));
    }
  }
  check_pipeline(spec.pipeline, spec.terms, spec.settings);
  if (spec.max_error) check_budget(spec.pipeline, *spec.max_error, "quality.max_error");
  return spec;
}

void Api::check_pipeline(const std::string& pipeline, const std::string& terms,
                         const Settings& settings) {
  const PipelineInfo& info = pipeline_info(pipeline);  // names the known ones when unknown
  if (!terms.empty()) require_terms(info, parse_terms(terms));
  info.validate(settings);
}

void Api::render(const HttpRequest& http, const Respond& respond) {
  nlohmann::json request = parse_json(http.body, "body");
  JsonObject r(request, "");
  RenderSpec spec = read_render_spec(r, request, options_, scenes_);
  r.finish();
  check_cost(options_, spec.pipeline, *spec.scene, spec.terms, spec.settings, false,
             spec.max_error);
  FrameSpec frame;
  frame.scene = spec.scene;
  frame.pipeline = spec.pipeline;
  frame.terms = spec.terms;
  frame.settings = spec.settings;
  frame.max_error = spec.max_error;
  frame.scene_load_ms = spec.scene_load_ms;
  frame.max_seconds = options_.max_render_s;
  auto cancel = http.cancel ? http.cancel : std::make_shared<CancelToken>();
  bool queued = post_render(
      queue_, metrics_, std::move(frame), cancel,
      [this, respond, format = spec.format, exposure = spec.exposure](RenderOutcome o) {
        if (!o.result) return respond(error(o.status, without_paths(o.error, options_), o.field));
        // Encoded off the render thread.
        offload_([o = std::move(o), respond, format, exposure]() mutable {
          RenderResult& result = *o.result;
          nlohmann::json timings = nlohmann::json::object();
          for (const auto& t : result.timings) timings[t.stage] = t.ms;
          nlohmann::json plan = result.plan;
          if (format == "json") {
            nlohmann::json j = {{"pipeline", result.plan.pipeline},
                                {"plan", plan},
                                {"timings_ms", timings},
                                {"queue_wait_ms", o.wait_ms},
                                {"width", result.image.width},
                                {"height", result.image.height}};
            if (result.error_estimate) j["error_estimate"] = *result.error_estimate;
            return respond(json_response(j));
          }
          HttpResponse response{
              200,
              format == "exr" ? "image/x-exr" : (format == "png" ? "image/png" : "image/jpeg"),
              encode_image(result.image, format, ToneMap{exposure}),
              {}};
          response.headers = {{"X-Scatter-Pipeline", result.plan.pipeline},
                              {"X-Scatter-Plan", plan.dump()},
                              {"X-Scatter-Timings", timings.dump()},
                              {"X-Scatter-Queue-Wait-Ms", short_number(o.wait_ms)}};
          if (result.error_estimate)
            response.headers.push_back(
                {"X-Scatter-Error-Estimate", short_number(*result.error_estimate)});
          respond(std::move(response));
        });
      });
  if (!queued) respond(error(503, busy_message(queue_)));
}

}  // namespace scatter::server
