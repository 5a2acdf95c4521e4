// A live session's frames (server/ws_session.hpp): what renders next (a reduced frame while the
// user moves, the refinement's steps once still), the render job, and the frame sent back.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

#include "protocol/session_messages.hpp"
#include "server/ws_session.hpp"

namespace scatter::server {

void WsSession::schedule_refine() {
  if (!last_frame_reduced_ || dirty_) return;
  auto wait = std::chrono::milliseconds(options_.idle_refine_ms) -
              (std::chrono::steady_clock::now() - last_change_);
  refine_timer_.expires_after(
      std::max(std::chrono::steady_clock::duration::zero(),
               std::chrono::duration_cast<std::chrono::steady_clock::duration>(wait)));
  refine_timer_.async_wait([self = shared_from_this()](boost::system::error_code ec) {
    if (ec || self->closed_ || self->dirty_ || !self->last_frame_reduced_ || self->in_flight_)
      return;
    if (std::chrono::steady_clock::now() - self->last_change_ <
        std::chrono::milliseconds(self->options_.idle_refine_ms))
      return self->schedule_refine();  // moved again meanwhile
    self->interactive_ = false;
    self->dirty_ = true;
    self->maybe_render();
  });
}

// The next frame, if the slot is free: the newest pose (reduced while the user moves), else the
// still view's next refinement step.
void WsSession::maybe_render() {
  if (in_flight_ || closed_ || !scene_) return;
  if (dirty_) {
    dirty_ = false;
    if (interactive_) return start_frame(std::nullopt);
    Scene view = *scene_;  // the mesh and density are shared; the refinement weighs costs on it
    view.camera = camera_;
    view.lights = lights_;
    RefineOptions o{.floor = refine_floor_,
                    .max_passes = options_.refine_max_passes,
                    .pass_seconds = options_.refine_pass_s,
                    .max_render_s = options_.max_render_s,
                    .max_request_mb = options_.max_request_mb,
                    .step_max_s = 10 * options_.refine_pass_s,
                    .composite = composite_};
    try {
      refine_ = Refinement(view, pipeline_, terms_, settings_, o);
    } catch (const std::exception& e) {  // validated by the hello: not expected
      spdlog::warn("event=refine_failed error=\"{}\"", e.what());
      refine_ = Refinement();
    }
    return start_frame(
        refine_.next().value_or(RefineStep{RefineStep::Stage::Full, pipeline_, terms_, settings_}));
  }
  if (interactive_) return;
  if (auto step = refine_.next()) start_frame(std::move(step));
}

void WsSession::start_frame(std::optional<RefineStep> step) {
  // Everything the frame needs, taken now: later messages cannot change it (latest wins at the
  // start of each frame, never in the middle). The scene itself is shared, not copied.
  FrameSpec f;
  f.scene = scene_;
  f.camera = camera_;
  f.lights = lights_;
  bool reduced = !step;
  // Cheaper while the user interacts; a composite's multiple term is rendered smaller too.
  if (double scale = reduced ? reduced_.choice(pipeline_).scale : step->scale; scale != 1) {
    f.width = std::max(1, static_cast<int>(std::lround(scene_->width * scale)));
    f.height = std::max(1, static_cast<int>(std::lround(scene_->height * scale)));
  }
  if (!step || step->stage == RefineStep::Stage::Full) {  // the session's own frames
    f.pipeline = pipeline_;
    f.terms = terms_;
    f.settings = reduced ? reduced_.settings(pipeline_, settings_) : settings_;
    f.max_error = max_error_;
  } else {
    f.pipeline = step->pipeline;
    f.terms = step->terms;
    f.settings = step->settings;
  }
  f.scene_load_ms = std::exchange(scene_load_ms_, 0);
  frame_format_ = !reduced && std::exchange(snapshot_, false) ? "exr" : format_;
  f.max_seconds = options_.max_render_s;
  last_frame_reduced_ = reduced;
  frame_step_ = std::move(step);
  long long frame = next_frame_++;
  in_flight_ = frame;
  frame_camera_revision_ = camera_revision_;
  frame_light_revision_ = light_revision_;
  awaiting_ack_ = false;
  cancel_ = std::make_shared<CancelToken>();
  auto self = shared_from_this();
  // Runs on the render thread: hand the result to this session's strand at once.
  bool queued = post_render(
      queue_, metrics_, std::move(f), cancel_,
      [self, frame, reduced](RenderOutcome o) {
        boost::asio::post(self->ws_.get_executor(),
                          [self, frame, reduced, o = std::move(o)]() mutable {
                            self->on_rendered(frame, reduced, std::move(o));
                          });
      },
      /*bypass_limit=*/true);
  if (!queued)
    on_rendered(frame, reduced, RenderOutcome{std::nullopt, 503, "the server is stopping", "", 0});
}

void WsSession::on_rendered(long long frame, bool reduced, RenderOutcome o) {
  if (closed_ || frame != in_flight_) return;  // the client left or moved meanwhile: not sent
  if (reduced && o.result && !frame_step_) {   // the render's own time, not the scene's load
    double ms = 0;
    for (const auto& t : o.result->timings)
      if (t.stage != "scene_load") ms += t.ms;
    reduced_.measured(pipeline_, ms);
  }
  if (!o.result) {
    in_flight_ = 0;  // no frame to ack
    if (frame_step_) refine_.stop();
    nlohmann::json e = {
        {"type", "error"}, {"error", o.error}, {"frame", frame}, {"request", request_}};
    if (!o.field.empty()) e["field"] = o.field;
    send(e.dump(), false);
    return;
  }
  nlohmann::json extra = nlohmann::json::object();
  if (frame_step_) {
    // A reference pass becomes the accumulation of the passes so far (on this strand: a few ms).
    Refinement::Outcome out = refine_.take(*frame_step_, *o.result);
    extra["refine"] = refine_.describe(*frame_step_, out.state);
    if (!out.send) {  // not better by a tenth: the next step starts at once, nothing to ack
      in_flight_ = 0;
      // Said, without the image, so that a client can show how far the steps not shown got.
      nlohmann::json note = {{"type", "refine"}, {"refine", extra["refine"]}};
      if (out.estimate) note["error_estimate"] = *out.estimate;
      if (auto e = refine_.last_sent()) note["shown_error_estimate"] = *e;
      send(note.dump(), false);
      return maybe_render();
    }
  }
  send_frame(frame, reduced, std::move(o), std::move(extra));
}

// Encoded on the worker pool, then sent from this strand. `extra`: header fields beyond the
// render's own.
void WsSession::send_frame(long long frame, bool reduced, RenderOutcome o, nlohmann::json extra) {
  boost::asio::post(workers_, [self = shared_from_this(), frame, reduced, o = std::move(o),
                               format = frame_format_, extra = std::move(extra),
                               cam_rev = frame_camera_revision_, light_rev = frame_light_revision_,
                               request = request_, exposure = exposure_]() mutable {
    RenderResult& r = *o.result;
    nlohmann::json timings = nlohmann::json::object();
    for (const auto& t : r.timings) timings[t.stage] = t.ms;
    nlohmann::json header;
    std::string bytes;
    try {
      header = {{"type", "frame"},
                {"frame", frame},
                {"camera_revision", cam_rev},
                {"light_revision", light_rev},
                {"pipeline", r.plan.pipeline},
                {"plan", r.plan},
                {"timings_ms", timings},
                {"queue_wait_ms", o.wait_ms},
                {"width", r.image.width},
                {"height", r.image.height},
                {"format", format},
                {"reduced", reduced},
                {"request", request}};
      if (r.error_estimate) header["error_estimate"] = *r.error_estimate;
      // Frames while the user drags are seen for a moment: fewer bytes (as trame does).
      const int quality = reduced ? kMovingJpegQuality : kJpegQuality;
      if (format == "jpg") header["jpeg_quality"] = quality;
      header.update(extra);
      bytes = encode_image(r.image, format, ToneMap{exposure}, quality);
    } catch (const std::exception& e) {
      header = {{"type", "error"}, {"error", e.what()}, {"frame", frame}};
    }
    boost::asio::post(self->ws_.get_executor(), [self, frame, header = std::move(header),
                                                 bytes = std::move(bytes)]() mutable {
      if (self->closed_ || frame != self->in_flight_) return;
      if (header["type"] != "frame") {
        self->in_flight_ = 0;
        self->send(header.dump(), false);
        return self->maybe_render();
      }
      self->send(header.dump(), false);
      self->send(std::move(bytes), true);
      self->awaiting_ack_ = true;
    });
  });
}

}  // namespace scatter::server
