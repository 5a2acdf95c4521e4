#include "server/ws_session.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

#include "pipelines/registry.hpp"
#include "protocol/json_reader.hpp"
#include "protocol/session_messages.hpp"

namespace scatter::server {

namespace beast = boost::beast;
namespace websocket = beast::websocket;

WsSession::WsSession(boost::asio::ip::tcp::socket&& socket, Api& api,
                     boost::asio::thread_pool& workers)
    : ws_(std::move(socket)),
      api_(api),
      queue_(api.queue()),
      metrics_(api.metrics()),
      workers_(workers),
      options_(api.options()),
      refine_timer_(ws_.get_executor()),
      idle_timer_(ws_.get_executor()) {}

WsSession::~WsSession() {
  if (cancel_) cancel_->cancel("the client left");
  release_slot();
}

void WsSession::release_slot() {
  if (std::exchange(holds_slot_, false)) api_.release_session();
}

void WsSession::run(beast::http::request<beast::http::string_body> upgrade) {
  ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
  ws_.read_message_max(options_.max_message_bytes);
  last_message_ = std::chrono::steady_clock::now();
  ws_.async_accept(upgrade, [self = shared_from_this()](beast::error_code ec) {
    if (ec) return;
    self->watch_idle();
    self->do_read();
  });
}

void WsSession::end(const std::string& why) {
  if (closed_) return;
  closed_ = true;
  if (cancel_) cancel_->cancel(why);
  refine_timer_.cancel();
  idle_timer_.cancel();
  spdlog::info("event=session_end reason=\"{}\"", why);
  release_slot();          // at once: a client that does not answer the close must not keep it
  if (!writes_.empty()) {  // a write is pending, and a close is a write too: drop the connection
    beast::error_code ec;
    beast::get_lowest_layer(ws_).socket().close(ec);
    return;
  }
  ws_.async_close(websocket::close_reason(websocket::close_code::policy_error, why),
                  [self = shared_from_this()](beast::error_code) {});
  // A peer that never completes the close handshake loses the connection soon after.
  idle_timer_.expires_after(std::chrono::seconds(2));
  idle_timer_.async_wait([self = shared_from_this()](boost::system::error_code ec) {
    if (ec) return;
    beast::error_code ignored;
    beast::get_lowest_layer(self->ws_).socket().close(ignored);
  });
}

// A session that says nothing for --session-idle-s (no pose, ack or ping) gives its slot back.
void WsSession::watch_idle() {
  auto idle = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(options_.session_idle_s));
  idle_timer_.expires_at(last_message_ + idle);
  idle_timer_.async_wait([self = shared_from_this(), idle](boost::system::error_code ec) {
    if (ec || self->closed_) return;
    if (std::chrono::steady_clock::now() - self->last_message_ >= idle)
      return self->end("idle: no message for " + short_number(self->options_.session_idle_s) +
                       " s (--session-idle-s)");
    self->watch_idle();
  });
}

void WsSession::do_read() {
  ws_.async_read(buffer_, beast::bind_front_handler(&WsSession::on_read, shared_from_this()));
}

void WsSession::on_read(beast::error_code ec, size_t) {
  if (ec) {  // closed, reset or too large: the session ends, and so does its frame in flight
    closed_ = true;
    if (cancel_) cancel_->cancel("the client left");
    refine_timer_.cancel();
    idle_timer_.cancel();
    return;
  }
  last_message_ = std::chrono::steady_clock::now();
  std::string text = beast::buffers_to_string(buffer_.data());
  buffer_.consume(buffer_.size());
  dispatch(std::move(text));
  if (!closed_) do_read();
}

void WsSession::dispatch(std::string text) {
  if (hello_pending_) {  // in order, after the hello being read
    if (backlog_.size() >= kMaxBacklog)
      return send_error(
          "too many messages while the scene loads (" + std::to_string(kMaxBacklog) + ")", "type");
    backlog_.push_back(std::move(text));
    return;
  }
  try {
    handle(text);
  } catch (const ValidationError& e) {
    send_error(e.what(), e.field());
  } catch (const std::exception& e) {
    send_error(e.what(), "");
  }
}

// Reading a hello loads its scene (the first time, an import of seconds): on the worker pool,
// then applied here; messages that come meanwhile wait in the backlog.
void WsSession::read_hello(nlohmann::json msg) {
  hello_pending_ = true;
  boost::asio::post(workers_, [self = shared_from_this(), msg = std::move(msg)] {
    std::optional<Hello> hello;
    std::string error, field;
    long long request = 0;
    try {
      hello = read_hello_message(msg, self->options_, self->api_.scenes(), request);
    } catch (const ValidationError& e) {
      error = e.what();
      field = e.field();
    } catch (const std::exception& e) {
      error = e.what();
    }
    boost::asio::post(self->ws_.get_executor(),
                      [self, hello = std::move(hello), error, field, request]() mutable {
                        self->hello_pending_ = false;
                        if (self->closed_) return;
                        if (hello) {
                          self->request_ = request;
                          self->apply_hello(std::move(*hello));
                        } else {
                          nlohmann::json e = {{"type", "error"}, {"error", error}};
                          if (!field.empty()) e["field"] = field;
                          e["request"] = request;
                          self->send(e.dump(), false);
                        }
                        while (!self->backlog_.empty() && !self->hello_pending_) {
                          std::string next = std::move(self->backlog_.front());
                          self->backlog_.pop_front();
                          self->dispatch(std::move(next));
                        }
                      });
  });
}

void WsSession::apply_hello(Hello hello) {
  Api::RenderSpec& spec = hello.spec;
  nlohmann::json& said = hello.scene_message;
  // keep_view: the pose and lights the user steered to stay (a change of pipeline or quality);
  // only possible once a scene was shown.
  bool keep = hello.keep_view && scene_;
  scene_ = spec.scene;
  scene_load_ms_ = spec.scene_load_ms;
  if (!keep) {
    camera_ = scene_->camera;
    lights_ = scene_->lights;
  } else {
    nlohmann::json lights = nlohmann::json::array();
    for (const Light& l : lights_) lights.push_back(light_json(l));
    said["lights"] = lights;
    said["camera"] = camera_json(camera_);
  }
  said["kept_view"] = keep;
  if (said["request"] != 0) send(said.dump(), false);  // asked for: clients without one get none
  exposure_ = spec.exposure;
  pipeline_ = spec.pipeline;
  terms_ = spec.terms;
  format_ = spec.format == "json" ? "jpg" : spec.format;
  settings_ = spec.settings;
  max_error_ = spec.max_error;
  refine_floor_ = spec.refine_floor;
  composite_ = std::move(hello.composite);
  cancel_unsent("a new hello");  // it renders what the session no longer shows
  dirty_ = true;
  interactive_ = false;
  last_change_ = std::chrono::steady_clock::now();
  maybe_render();
}

// The frame in flight, unless it was sent (then only its ack frees the slot): its render stops
// at its next progress check, and its result is dropped.
void WsSession::cancel_unsent(const std::string& why) {
  if (!in_flight_ || awaiting_ack_) return;
  if (cancel_) cancel_->cancel(why);
  in_flight_ = 0;
}

void WsSession::send_error(const std::string& error, const std::string& field) {
  nlohmann::json j = {{"type", "error"}, {"error", error}};
  if (!field.empty()) j["field"] = field;
  send(j.dump(), false);
}

void WsSession::handle(const std::string& text) {
  nlohmann::json msg = parse_json(text, "message");
  JsonObject m(msg, "");
  std::string type = m.choice(
      "type", {"hello", "camera", "lights", "ack", "ping", "cancel", "snapshot"}, std::nullopt);
  if (type == "hello") {
    return read_hello(std::move(msg));
  } else if (type == "camera") {
    if (!scene_) throw ValidationError("type", "send hello first");
    Camera c = camera_;
    c.position = m.vec3("position", c.position, {-1e6, 1e6});
    c.target = m.vec3("target", c.target, {-1e6, 1e6});
    c.up = m.vec3("up", c.up, {-1e6, 1e6});
    c.fov_deg = m.number("fov_deg", c.fov_deg, {1, 170});
    if (length(c.target - c.position) < 1e-9 ||
        length(cross(normalize(c.target - c.position), c.up)) < 1e-6)
      throw ValidationError("position",
                            "the camera must look somewhere and up must not be parallel to it");
    long long rev =
        static_cast<long long>(m.number("revision", double(camera_revision_ + 1), {0, 9e15}));
    m.finish();
    camera_ = c;
    camera_revision_ = rev;
    dirty_ = true;
    interactive_ = true;
    last_change_ = std::chrono::steady_clock::now();
    if (frame_step_) cancel_unsent("the camera moved");  // a still frame: refining a stale view
  } else if (type == "lights") {
    if (!scene_) throw ValidationError("type", "send hello first");
    long long rev =
        static_cast<long long>(m.number("revision", double(light_revision_ + 1), {0, 9e15}));
    m.array("lights", 0, 16);
    m.finish();
    std::vector<Light> lights = parse_lights(msg["lights"], "lights");
    Scene lit = *scene_;  // the cost depends on the number of lights (the mesh is shared)
    lit.lights = lights;
    Api::check_cost(options_, pipeline_, lit, terms_, settings_, false, max_error_);
    lights_ = std::move(lights);
    light_revision_ = rev;
    dirty_ = true;
    interactive_ = true;
    last_change_ = std::chrono::steady_clock::now();
    if (frame_step_) cancel_unsent("the lights changed");
  } else if (type == "ack") {
    long long frame = m.integer("frame", std::nullopt, {0, 2e9});
    m.finish();
    // Only the frame in flight, once it was sent, can be acked: an ack for any other frame (one
    // never received, or acked twice) would let a client queue renders without reading them.
    if (!awaiting_ack_ || frame != in_flight_) return;
    awaiting_ack_ = false;
    in_flight_ = 0;
    schedule_refine();
  } else if (type == "snapshot") {
    // The current view at full size as linear EXR: the next still frame, then refining goes on
    // in the session's format.
    if (!scene_) throw ValidationError("type", "send hello first");
    m.finish();
    snapshot_ = true;
    cancel_unsent("a snapshot");
    dirty_ = true;
    interactive_ = false;
  } else if (type == "cancel") {
    // The user gave up on a long frame: it stops, the view stays still and is not refined.
    m.finish();
    bool had = in_flight_ && !awaiting_ack_;
    cancel_unsent("cancelled by the user");
    refine_.stop();
    dirty_ = false;
    refine_timer_.cancel();
    send(nlohmann::json{{"type", "cancelled"}, {"request", request_}, {"frame_cancelled", had}}
             .dump(),
         false);
    return;
  } else {
    m.finish();
    send(nlohmann::json{{"type", "pong"}}.dump(), false);
    return;
  }
  maybe_render();
}

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

void WsSession::send(std::string message, bool binary) {
  if (closed_) return;
  if (writes_.size() >= kMaxQueuedWrites)
    return end("the client does not read its messages (" + std::to_string(kMaxQueuedWrites) +
               " unsent)");
  writes_.emplace_back(std::make_shared<const std::string>(std::move(message)), binary);
  if (writes_.size() == 1) do_write();
}

void WsSession::do_write() {
  auto& [message, binary] = writes_.front();
  ws_.binary(binary);
  ws_.async_write(boost::asio::buffer(*message),
                  [self = shared_from_this()](beast::error_code ec, size_t) {
                    if (ec) {
                      self->closed_ = true;
                      if (self->cancel_) self->cancel_->cancel("the client left");
                      self->writes_.clear();
                      return;
                    }
                    self->writes_.pop_front();
                    if (!self->writes_.empty() && !self->closed_) self->do_write();
                  });
}

}  // namespace scatter::server
