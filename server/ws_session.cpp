#include "server/ws_session.hpp"

#include <spdlog/spdlog.h>

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
