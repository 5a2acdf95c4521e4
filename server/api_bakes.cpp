// POST/GET /api/bakes and GET/DELETE /api/bakes/{id}: bake jobs validated here, run on the
// render thread, followed through bake/jobs.
#include <spdlog/spdlog.h>

#include <fstream>

#include "pipelines/registry.hpp"
#include "protocol/json_reader.hpp"
#include "server/api.hpp"
#include "server/api_util.hpp"

namespace scatter::server {

HttpResponse Api::create_bake(const std::string& body) {
  nlohmann::json request = parse_json(body, "body");
  if (request.is_object() && !request.contains("pipeline")) request["pipeline"] = "single";
  JsonObject r(request, "");
  RenderSpec spec = read_render_spec(r, request, options_, scenes_);
  r.finish();
  std::shared_ptr<const Scene> scene = spec.scene;
  const std::string pipeline = spec.pipeline;
  const Settings settings = spec.settings;
  // Checked from the registry (no instance, no GPU), so that a typo is a 400 at once and a POST
  // never waits behind a running bake.
  const PipelineInfo& info = pipeline_info(pipeline);
  if (!info.bakes()) throw ValidationError("pipeline", "pipeline " + pipeline + " needs no bake");
  info.validate(settings);
  const std::vector<std::pair<std::string, double>> stages = info.bake_stages;
  const Terms terms = info.default_terms;
  check_cost(options_, pipeline, *scene, "", settings, true);
  // The job is named by the key of the product it makes (BakeJobs takes a bake key as the id).
  const std::string identity = info.bake_key(*scene, settings);
  bool created = false;
  auto job = bakes_.submit(
      identity, pipeline, stages,
      [&](std::shared_ptr<BakeJob> j) {
        spdlog::info("event=bake_queued id={} pipeline={}", j->id(), pipeline);
        RenderQueue::Job work;
        // On the bake queue's own thread and GPU contexts: live sessions' frames do not wait for
        // it.
        work.run = [j, scene, pipeline, settings, terms](RenderQueue::Context& c) {
          j->run([&](const BakeProgress& progress) {
            return c.pipeline(pipeline).bake(*scene, {terms, settings, nullptr}, progress);
          });
          nlohmann::json s = j->status();
          spdlog::info("event=bake_finished id={} state={} cache_hit={} seconds={}", j->id(),
                       s["state"].get<std::string>(), s.value("cache_hit", false),
                       s.value("seconds", 0.0));
        };
        work.dropped = [j](const std::string& why) {
          j->cancel();  // a queued job is recorded as cancelled at once
          spdlog::info("event=bake_dropped id={} reason=\"{}\"", j->id(), why);
        };
        if (!bake_queue_.post(std::move(work))) {
          j->cancel();
          throw BakeJobs::Busy();
        }
      },
      &created);
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
    if (!job->cancel())
      return error(
          409, "bake job " + id + " has already " +
                   (job->state() == BakeJob::State::Done ? "finished" : to_string(job->state())));
    return json_response(job->status(), 202);
  }
  return error(405, request.method + " is not allowed on /api/bakes/{id}: use GET or DELETE");
}

}  // namespace scatter::server
