#include "server/ws_session.hpp"

#include <spdlog/spdlog.h>

#include "protocol/json_reader.hpp"

namespace scatter::server {

namespace beast = boost::beast;
namespace websocket = beast::websocket;

WsSession::WsSession(boost::asio::ip::tcp::socket&& socket, Api& api, boost::asio::thread_pool& workers)
    : ws_(std::move(socket)),
      api_(api),
      queue_(api.queue()),
      metrics_(api.metrics()),
      workers_(workers),
      options_(api.options()),
      refine_timer_(ws_.get_executor()) {}

WsSession::~WsSession() { api_.release_session(); }

void WsSession::run(beast::http::request<beast::http::string_body> upgrade) {
  ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
  ws_.read_message_max(options_.max_message_bytes);
  ws_.async_accept(upgrade, [self = shared_from_this()](beast::error_code ec) {
    if (ec) return;
    self->do_read();
  });
}

void WsSession::do_read() {
  ws_.async_read(buffer_, beast::bind_front_handler(&WsSession::on_read, shared_from_this()));
}

void WsSession::on_read(beast::error_code ec, size_t) {
  if (ec) {  // closed, reset or too large: the session ends; a frame in flight is simply dropped
    closed_ = true;
    return;
  }
  std::string text = beast::buffers_to_string(buffer_.data());
  buffer_.consume(buffer_.size());
  try {
    handle(text);
  } catch (const ValidationError& e) {
    send_error(e.what(), e.field());
  } catch (const std::exception& e) {
    send_error(e.what(), "");
  }
  do_read();
}

void WsSession::send_error(const std::string& error, const std::string& field) {
  nlohmann::json j = {{"type", "error"}, {"error", error}};
  if (!field.empty()) j["field"] = field;
  send(j.dump(), false);
}

void WsSession::handle(const std::string& text) {
  nlohmann::json msg = nlohmann::json::parse(text, nullptr, false);
  if (msg.is_discarded()) throw ValidationError("message", "is not valid JSON");
  JsonObject m(msg, "");
  std::string type = m.choice("type", {"hello", "camera", "lights", "ack"}, std::nullopt);
  if (type == "hello") {
    Api::RenderSpec spec = Api::read_render_spec(m, msg, options_);
    m.finish();
    scene_ = std::make_shared<const Scene>(std::move(spec.scene));
    camera_ = scene_->camera;
    lights_ = scene_->lights;
    pipeline_ = spec.pipeline;
    terms_ = spec.terms;
    format_ = spec.format == "json" ? "jpg" : spec.format;
    settings_ = spec.settings;
    dirty_ = true;
    interactive_ = false;
  } else if (type == "camera") {
    if (!scene_) throw ValidationError("type", "send hello first");
    Camera c = camera_;
    c.position = m.vec3("position", c.position, {-1e6, 1e6});
    c.target = m.vec3("target", c.target, {-1e6, 1e6});
    c.up = m.vec3("up", c.up, {-1e6, 1e6});
    c.fov_deg = m.number("fov_deg", c.fov_deg, {1, 170});
    if (length(c.target - c.position) < 1e-9 ||
        length(cross(normalize(c.target - c.position), c.up)) < 1e-6)
      throw ValidationError("position", "the camera must look somewhere and up must not be parallel to it");
    long long rev = static_cast<long long>(m.number("revision", double(camera_revision_ + 1), {0, 9e15}));
    m.finish();
    camera_ = c;
    camera_revision_ = rev;
    dirty_ = true;
    interactive_ = true;
    last_change_ = std::chrono::steady_clock::now();
  } else if (type == "lights") {
    if (!scene_) throw ValidationError("type", "send hello first");
    long long rev = static_cast<long long>(m.number("revision", double(light_revision_ + 1), {0, 9e15}));
    m.array("lights", 0, 16);
    m.finish();
    lights_ = parse_lights(msg["lights"], "lights");
    light_revision_ = rev;
    dirty_ = true;
    interactive_ = true;
    last_change_ = std::chrono::steady_clock::now();
  } else {
    m.integer("frame", std::nullopt, {0, 2e9});
    m.finish();
    in_flight_ = false;
    schedule_refine();
  }
  maybe_render();
}

void WsSession::schedule_refine() {
  if (!last_frame_reduced_ || dirty_) return;
  auto wait = std::chrono::milliseconds(options_.idle_refine_ms) -
              (std::chrono::steady_clock::now() - last_change_);
  refine_timer_.expires_after(std::max(std::chrono::steady_clock::duration::zero(),
                                       std::chrono::duration_cast<std::chrono::steady_clock::duration>(wait)));
  refine_timer_.async_wait([self = shared_from_this()](boost::system::error_code ec) {
    if (ec || self->closed_ || self->dirty_ || !self->last_frame_reduced_) return;
    if (std::chrono::steady_clock::now() - self->last_change_ <
        std::chrono::milliseconds(self->options_.idle_refine_ms))
      return self->schedule_refine();  // moved again meanwhile
    self->interactive_ = false;
    self->dirty_ = true;
    self->maybe_render();
  });
}

void WsSession::maybe_render() {
  if (!dirty_ || in_flight_ || closed_ || !scene_) return;
  dirty_ = false;
  in_flight_ = true;
  // Everything the frame needs, copied now: later messages cannot change it (latest wins at the
  // start of each frame, never in the middle).
  auto scene = std::make_shared<Scene>(*scene_);
  scene->camera = camera_;
  scene->lights = lights_;
  bool reduced = interactive_;
  if (reduced) {  // cheaper while the user interacts
    scene->width = std::max(1, scene->width / 2);
    scene->height = std::max(1, scene->height / 2);
  }
  last_frame_reduced_ = reduced;
  long long frame = next_frame_++, cam_rev = camera_revision_, light_rev = light_revision_;
  std::string pipeline = pipeline_, terms = terms_, format = format_;
  Settings settings = settings_;
  boost::asio::post(workers_, [self = shared_from_this(), scene, frame, cam_rev, light_rev, pipeline,
                               terms, format, settings, reduced] {
    nlohmann::json header;
    std::string bytes;
    try {
      RenderResult r = Api::render_on_queue(self->queue_, self->metrics_, *scene, pipeline, terms, settings);
      nlohmann::json timings = nlohmann::json::object();
      for (const auto& t : r.timings) timings[t.stage] = t.ms;
      header = {{"type", "frame"}, {"frame", frame}, {"camera_revision", cam_rev},
                {"light_revision", light_rev}, {"pipeline", r.plan.pipeline}, {"plan", r.plan},
                {"timings_ms", timings}, {"width", r.image.width}, {"height", r.image.height},
                {"format", format}, {"reduced", reduced}};
      bytes = encode_image(r.image, format);  // encoded here, off the render thread
    } catch (const std::exception& e) {
      header = {{"type", "error"}, {"error", e.what()}, {"frame", frame}};
    }
    boost::asio::post(self->ws_.get_executor(), [self, header, bytes = std::move(bytes)]() mutable {
      if (self->closed_) return;  // the client left mid-frame: nothing to send, nothing to undo
      bool ok = header["type"] == "frame";
      self->send(header.dump(), false);
      if (ok) {
        self->send(std::move(bytes), true);
      } else {
        self->in_flight_ = false;  // no frame to ack
      }
    });
  });
}

void WsSession::send(std::string message, bool binary) {
  writes_.emplace_back(std::make_shared<const std::string>(std::move(message)), binary);
  if (writes_.size() == 1) do_write();
}

void WsSession::do_write() {
  auto& [message, binary] = writes_.front();
  ws_.binary(binary);
  ws_.async_write(boost::asio::buffer(*message), [self = shared_from_this()](beast::error_code ec, size_t) {
    if (ec) {
      self->closed_ = true;
      self->writes_.clear();
      return;
    }
    self->writes_.pop_front();
    if (!self->writes_.empty()) self->do_write();
  });
}

}  // namespace scatter::server
