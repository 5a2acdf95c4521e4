#include "server/session_hello.hpp"

#include "pipelines/registry.hpp"
#include "protocol/json_reader.hpp"
#include "protocol/session_messages.hpp"

namespace scatter::server {
namespace {

// What a ValidationError says, without its field.
std::string problem_of(const ValidationError& e) {
  return std::string(e.what()).substr(e.field().empty() ? 0 : e.field().size() + 2);
}

// A hello's "composite": the pipeline that renders the multiple term a still frame of the
// session's single (or surface) term adds, its settings, and the fraction of each side it renders.
std::optional<Composite> read_composite(JsonObject& m, const nlohmann::json& msg,
                                        const std::string& pipeline, std::string terms) {
  std::optional<JsonObject> c = m.optional_object("composite");
  if (!c) return std::nullopt;
  Composite out;
  out.pipeline = c->string("pipeline", std::nullopt);
  const PipelineInfo* info = nullptr;
  try {
    info = &pipeline_info(out.pipeline);
  } catch (const ValidationError& e) {
    throw ValidationError("composite.pipeline", problem_of(e));
  }
  if (!info->renders(Terms::Multiple))
    throw ValidationError("composite.pipeline",
                          "pipeline " + out.pipeline + " does not render the multiple term");
  if (terms.empty()) terms = to_string(pipeline_info(pipeline).default_terms);
  if (terms != "single" && terms != "surface")
    throw ValidationError("composite",
                          "adds the multiple term to frames of the single or the "
                          "surface term: give \"terms\": \"single\" or \"surface\"");
  out.scale = c->number("scale", out.scale, {0.125, 1});
  if (auto s = c->optional_object("settings")) {
    for (const auto& [key, value] : msg["composite"]["settings"].items())
      out.settings[key] = s->number(key, std::nullopt, kAnyFinite);
    s->finish();
  }
  try {
    info->validate(out.settings);
  } catch (const ValidationError& e) {
    throw ValidationError("composite." + e.field(), problem_of(e));
  }
  c->finish();
  return out;
}

}  // namespace

Hello read_hello_message(const nlohmann::json& msg, const ApiOptions& options, SceneLibrary& scenes,
                         long long& request) {
  Hello hello;
  JsonObject m(msg, "");
  m.string("type", std::nullopt);
  hello.keep_view = m.boolean("keep_view", false);
  request = m.integer("request", 0, {0, 2e9});
  std::optional<JsonObject> medium = m.optional_object("medium");
  hello.spec = Api::read_render_spec(m, msg, options, scenes);
  Api::RenderSpec& spec = hello.spec;
  hello.composite = read_composite(m, msg, spec.pipeline, spec.terms);
  m.finish();
  nlohmann::json& said = hello.scene_message;
  said = scene_message(msg, *spec.scene, options.scenes_dir, request);
  if (medium) {
    // A shipped scene in another medium: its file's JSON (which may name meshes anywhere the
    // server's own scenes do) with the client's medium, validated as any scene.
    if (!said["source"].is_object())
      throw ValidationError("medium", "needs a scene_name whose file is in --scenes-dir");
    said["source"]["medium"] = msg["medium"];
    SceneLimits limits;
    limits.max_image = options.max_image;
    try {
      spec.scene =
          std::make_shared<const Scene>(parse_scene(said["source"], options.scenes_dir, limits));
    } catch (const ValidationError& e) {  // "scene.medium.g" is the hello's "medium.g"
      std::string f = e.field();
      if (f.rfind("scene.", 0) == 0) f = f.substr(6);
      throw ValidationError(f, problem_of(e));
    }
  }
  Api::check_cost(options, spec.pipeline, *spec.scene, spec.terms, spec.settings, false,
                  spec.max_error);
  return hello;
}

}  // namespace scatter::server
