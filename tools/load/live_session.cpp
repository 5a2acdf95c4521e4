#include "tools/load/live_session.hpp"

#include <cmath>

namespace scatter::load {

namespace beast = boost::beast;
namespace websocket = beast::websocket;
using Ms = std::chrono::duration<double, std::milli>;

nlohmann::json SessionResult::to_json() const {
  return {{"index", index},
          {"admitted", admitted},
          {"end", end},
          {"fps", std::round(fps() * 100) / 100},
          {"frames", frames},
          {"frames_reduced", frames_reduced},
          {"frames_failed", frames_failed},
          {"bytes_received", bytes},
          {"poses_sent", poses_sent},
          {"poses_answered", poses_answered},
          {"poses_coalesced", poses_coalesced},
          {"poses_unanswered", poses_unanswered},
          {"lights_sent", lights_sent},
          {"open_s", std::round(open_s * 1000) / 1000},
          {"first_frame_ms",
           first_frame_ms < 0 ? nlohmann::json() : nlohmann::json(std::round(first_frame_ms))},
          {"pose_to_frame_ms", pose_to_frame.summary()},
          {"render_ms", render.summary()},
          {"pose_to_frame_minus_render_ms", minus_render.summary()},
          {"header_to_image_ms", header_to_image.summary()},
          {"errors", errors.to_json()}};
}

LiveSession::LiveSession(boost::asio::io_context& io, const LoadOptions& options, int index)
    : ws_(io),
      options_(options),
      script_(options, index),
      pose_timer_(io),
      deadline_(io),
      stall_(io) {
  result_.index = index;
}

void LiveSession::start(const boost::asio::ip::tcp::resolver::results_type& endpoints) {
  auto& tcp = beast::get_lowest_layer(ws_);
  tcp.expires_after(span(options_.timeout_s));
  tcp.async_connect(endpoints, [self = shared_from_this()](beast::error_code ec, const auto&) {
    self->on_connect(ec);
  });
}

void LiveSession::on_connect(beast::error_code ec) {
  if (ec) {
    result_.errors.add("connect", ec.message());
    return finish("connect");
  }
  // As browsers do: small messages (poses, acks) go out at once, not held back by Nagle.
  beast::get_lowest_layer(ws_).socket().set_option(boost::asio::ip::tcp::no_delay(true), ec);
  // The TCP stream's timer (timeout_s) bounds the upgrade. Not the WebSocket stream's own timeout
  // option: after a refused upgrade its timer would keep the io_context busy until it expired.
  std::string token = options_.token;
  ws_.set_option(websocket::stream_base::decorator([token](websocket::request_type& req) {
    req.set(beast::http::field::user_agent, "scatter-load");
    if (!token.empty()) req.set(beast::http::field::authorization, "Bearer " + token);
  }));
  ws_.read_message_max(256 << 20);
  ws_.async_handshake(upgrade_, options_.host + ":" + options_.port, "/api/ws",
                      beast::bind_front_handler(&LiveSession::on_handshake, shared_from_this()));
}

void LiveSession::on_handshake(beast::error_code ec) {
  if (ec == websocket::error::upgrade_declined) {  // e.g. 503: every session slot is in use
    result_.errors.add("refused", std::to_string(upgrade_.result_int()));
    return finish("refused");
  }
  if (ec) {
    result_.errors.add("connect", ec.message());
    return finish("connect");
  }
  result_.admitted = true;
  beast::get_lowest_layer(ws_).expires_never();
  auto timeouts = websocket::stream_base::timeout::suggested(beast::role_type::client);
  timeouts.handshake_timeout =
      std::chrono::seconds(5);  // now: how long a closing handshake may take
  ws_.set_option(timeouts);
  opened_ = hello_sent_ = Clock::now();
  nlohmann::json hello = {{"type", "hello"},
                          {"scene_name", options_.scene},
                          {"pipeline", options_.pipeline},
                          {"format", options_.format}};
  if (!options_.terms.empty()) hello["terms"] = options_.terms;
  if (!options_.settings.empty()) hello["settings"] = options_.settings;
  send(hello);
  if (options_.duration_s > 0) {
    deadline_.expires_after(span(options_.duration_s));
    deadline_.async_wait([self = shared_from_this()](beast::error_code e) {
      if (!e) self->finish("duration");
    });
  }
  arm_stall();
  poses_from_ = Clock::now();
  next_pose();
  do_read();
}

// A session that hears nothing from the server for timeout_s gives up.
void LiveSession::arm_stall() {
  stall_.expires_after(span(options_.timeout_s));
  stall_.async_wait([self = shared_from_this()](beast::error_code ec) {
    if (ec || self->finishing_) return;
    self->result_.errors.add(
        "stall", "no message for " + std::to_string(int(self->options_.timeout_s)) + " s");
    self->finish("stall");
  });
}

void LiveSession::do_read() {
  ws_.async_read(buffer_, beast::bind_front_handler(&LiveSession::on_read, shared_from_this()));
}

void LiveSession::on_read(beast::error_code ec, size_t bytes) {
  if (ec) {
    if (!finishing_) {  // the server went away before we were done
      result_.errors.add("disconnect", ec.message());
      finish("disconnected");
    }
    return closed();
  }
  if (!finishing_) arm_stall();
  if (ws_.got_text()) {
    on_text(beast::buffers_to_string(buffer_.data()));
  } else {
    on_frame(bytes);
  }
  buffer_.consume(buffer_.size());
  do_read();  // also while closing: the close frame ends this loop
}

void LiveSession::on_text(const std::string& text) {
  nlohmann::json msg = nlohmann::json::parse(text, nullptr, false);
  if (msg.is_discarded() || !msg.is_object() || !msg.contains("type")) {
    result_.errors.add("protocol", "a text message that is not a JSON object with a type");
    return;
  }
  if (msg["type"] == "frame") {
    if (header_) result_.errors.add("protocol", "a frame header while another awaited its image");
    header_ = std::move(msg);
    header_at_ = Clock::now();
  } else if (msg["type"] == "refine") {
    // A still view's refinement step that was not sent (docs/API.md): no image follows.
  } else if (msg["type"] == "error") {
    std::string what = msg.value("error", std::string("(no message)"));
    result_.errors.add("server", msg.contains("frame") ? "frame failed: " + what : what);
    // A failed frame is an answer too: --frames counts it, so a session whose every frame
    // fails (a pipeline the scene cannot use) still ends.
    if (msg.contains("frame")) {
      ++result_.frames_failed;
      if (!finishing_ && options_.frames > 0 &&
          result_.frames + result_.frames_failed >= options_.frames)
        finish("frames");
    }
  } else {
    result_.errors.add("protocol", "unknown message type " + msg["type"].dump());
  }
}

void LiveSession::on_frame(size_t bytes) {
  if (!header_) {
    result_.errors.add("protocol", "an image with no frame header before it");
    return;
  }
  nlohmann::json header = std::move(*header_);
  header_.reset();
  auto now = Clock::now();
  if (result_.frames++ == 0) result_.first_frame_ms = Ms(now - hello_sent_).count();
  result_.header_to_image.add(Ms(now - header_at_).count());
  result_.bytes += static_cast<long long>(bytes);
  if (header.value("reduced", false)) ++result_.frames_reduced;
  double render_ms = 0;
  if (header.contains("timings_ms") && header["timings_ms"].is_object())
    for (const auto& [stage, ms] : header["timings_ms"].items())
      if (ms.is_number()) render_ms += ms.get<double>();
  result_.render.add(render_ms);
  auto revision = header.value("camera_revision", 0LL);
  while (!pending_.empty() && pending_.front().first <= revision) {
    auto [r, sent] = pending_.front();
    pending_.pop_front();
    double ms = Ms(now - sent).count();
    result_.pose_to_frame.add(ms);
    ++result_.poses_answered;
    if (r < revision) {
      ++result_.poses_coalesced;
    } else {
      result_.minus_render.add(ms - render_ms);
    }
  }
  if (finishing_) return;
  send({{"type", "ack"}, {"frame", header.value("frame", 0LL)}});
  if (options_.frames > 0 && result_.frames >= options_.frames) finish("frames");
}

// Ticks fall on a fixed schedule (poses_from_ + tick / rate), so a late tick does not delay the
// rest.
void LiveSession::next_pose() {
  pose_timer_.expires_at(poses_from_ + span(double(tick_) / options_.rate_hz));
  pose_timer_.async_wait(
      beast::bind_front_handler(&LiveSession::on_pose_timer, shared_from_this()));
}

void LiveSession::on_pose_timer(beast::error_code ec) {
  if (ec || finishing_) return;
  if (auto pose = script_.at(tick_)) {
    long long revision = ++revision_;
    send({{"type", "camera"},
          {"position", pose->position},
          {"target", {0, 0, 0}},
          {"up", {0, 1, 0}},
          {"revision", revision}});
    pending_.emplace_back(revision, Clock::now());
    ++result_.poses_sent;
    if (options_.light_every > 0 && result_.poses_sent % options_.light_every == 0) {
      long long n = ++result_.lights_sent;
      nlohmann::json light = {{"type", "point"},
                              {"position", PoseScript::light(n)},
                              {"color", {1, 1, 1}},
                              {"intensity", 20}};
      send({{"type", "lights"}, {"lights", {light}}, {"revision", n}});
    }
  }
  ++tick_;
  next_pose();
}

void LiveSession::send(nlohmann::json message) {
  writes_.push_back(message.dump());
  if (writes_.size() == 1) do_write();
}

void LiveSession::do_write() {
  ws_.text(true);
  ws_.async_write(boost::asio::buffer(writes_.front()),
                  [self = shared_from_this()](beast::error_code ec, size_t) {
                    if (ec) {
                      self->writes_.clear();
                      if (!self->finishing_) {
                        self->result_.errors.add("disconnect", "write: " + ec.message());
                        self->finish("disconnected");
                      }
                      return;
                    }
                    self->writes_.pop_front();
                    if (!self->writes_.empty()) self->do_write();
                  });
}

void LiveSession::finish(const std::string& why) {
  if (finishing_) return;
  finishing_ = true;
  result_.end = why;
  if (result_.admitted)
    result_.open_s = std::chrono::duration<double>(Clock::now() - opened_).count();
  result_.poses_unanswered = static_cast<long long>(pending_.size());
  pose_timer_.cancel();
  deadline_.cancel();
  if (!result_.admitted || why == "disconnected") return closed();
  // A polite close; the read loop sees the server's close frame. Bounded by the stall timer.
  stall_.expires_after(std::chrono::seconds(5));
  stall_.async_wait([self = shared_from_this()](beast::error_code ec) {
    if (!ec) beast::get_lowest_layer(self->ws_).close();
  });
  ws_.async_close(websocket::close_code::normal, [self = shared_from_this()](beast::error_code) {});
}

void LiveSession::closed() {
  stall_.cancel();
  pose_timer_.cancel();
  deadline_.cancel();
  beast::error_code ignored;
  beast::get_lowest_layer(ws_).socket().close(ignored);
}

}  // namespace scatter::load
