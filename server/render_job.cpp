#include "server/render_job.hpp"

#include <algorithm>
#include <chrono>

#include "core/errors.hpp"

namespace scatter::server {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

RenderResult render_frame(RenderQueue::Context& c, Metrics& metrics, const FrameSpec& spec,
                          const std::shared_ptr<CancelToken>& cancel) {
  // The frame's own scene: the shared one's fields with this frame's camera, lights and size.
  // The mesh and the density field are shared, not copied.
  Scene scene = *spec.scene;
  if (spec.camera) scene.camera = *spec.camera;
  if (spec.lights) scene.lights = *spec.lights;
  if (spec.width > 0) scene.width = spec.width;
  if (spec.height > 0) scene.height = spec.height;
  Pipeline& p = c.pipeline(spec.pipeline);
  RenderRequest req;
  req.settings = spec.settings;
  req.max_error = spec.max_error;
  req.time_limit_s = spec.max_seconds;  // the path tracer stops in time to return its samples
  auto ok = p.supported_terms();
  req.terms = !spec.terms.empty()                                       ? parse_terms(spec.terms)
              : std::find(ok.begin(), ok.end(), Terms::All) != ok.end() ? Terms::All
                                                                        : ok.front();
  if (cancel) {
    if (spec.max_seconds > 0) cancel->set_deadline(spec.max_seconds, "--max-render-s");
    cancel->check();
    req.progress = [cancel](double) { cancel->check(); };
  }
  auto start = Clock::now();
  RenderResult result = p.render(scene, req);
  double seconds = ms_since(start) / 1000;
  std::vector<std::pair<std::string, double>> stages;
  for (const auto& t : result.timings) stages.emplace_back(t.stage, t.ms / 1000);
  metrics.observe_render(p.name(), seconds, stages);
  if (spec.scene_load_ms > 0)
    result.timings.insert(result.timings.begin(), {"scene_load", spec.scene_load_ms});
  return result;
}

}  // namespace

bool post_render(RenderQueue& queue, Metrics& metrics, FrameSpec spec,
                 std::shared_ptr<CancelToken> cancel, std::function<void(RenderOutcome)> done,
                 bool bypass_limit) {
  auto finish = std::make_shared<std::function<void(RenderOutcome)>>(std::move(done));
  auto queued = Clock::now();
  RenderQueue::Job job;
  job.cancel = cancel;
  job.dropped = [finish, &metrics](const std::string& why) {
    metrics.count_cancelled();
    RenderOutcome o;
    o.status = 503;
    o.error = "render not run: " + why;
    (*finish)(std::move(o));
  };
  job.run = [spec = std::move(spec), cancel, finish, &metrics, queued](RenderQueue::Context& c) {
    RenderOutcome o;
    o.wait_ms = ms_since(queued);
    try {
      o.result = render_frame(c, metrics, spec, cancel);
    } catch (const ValidationError& e) {
      o.status = 400;
      o.error = e.what();
      o.field = e.field();
    } catch (const JobCancelled& e) {
      metrics.count_cancelled();
      o.status = 503;
      o.error = std::string("render cancelled: ") + e.what();
    } catch (const gpu::GpuError& e) {
      o.status = 503;
      o.error = e.what();
    } catch (const std::exception& e) {
      o.status = 500;
      o.error = std::string("internal error: ") + e.what();
    }
    (*finish)(std::move(o));
  };
  return queue.post(std::move(job), bypass_limit);
}

}  // namespace scatter::server
