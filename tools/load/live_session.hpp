// One scripted live session over /api/ws, as the web client behaves: hello, then camera poses at
// a steady rate (and lights, if asked) with increasing revisions, an ack for every frame received.
// Measures pose-to-frame latency: from sending the pose with revision r to receiving the first
// frame whose camera_revision >= r; a pose answered by a frame of a later revision was coalesced
// (latest wins on the server). Runs on one io_context thread, with no locks.
#pragma once

#include <boost/asio.hpp>
#include <boost/beast.hpp>
#include <boost/beast/websocket.hpp>
#include <chrono>
#include <deque>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>

#include "tools/load/error_tally.hpp"
#include "tools/load/latency_stats.hpp"
#include "tools/load/load_options.hpp"
#include "tools/load/pose_script.hpp"

namespace scatter::load {

struct SessionResult {
  int index = 0;
  bool admitted = false;  // the upgrade was accepted
  std::string end;        // why it ended: duration, frames, refused, connect, disconnected, stall
  long long frames = 0, frames_reduced = 0, bytes = 0;
  long long frames_failed = 0;  // frames the server answered with an error instead of an image
  long long poses_sent = 0, poses_answered = 0, poses_coalesced = 0, poses_unanswered = 0;
  long long lights_sent = 0;
  double open_s = 0;           // from the accepted upgrade to the end
  double first_frame_ms = -1;  // from hello to the first frame
  LatencyStats pose_to_frame;  // every answered pose
  LatencyStats render;         // the server's own timings_ms, summed, per frame
  LatencyStats minus_render;  // pose to frame minus that frame's render, for exactly answered poses
  LatencyStats header_to_image;  // from a frame's JSON header to its image (the transport's share)
  ErrorTally errors;

  double fps() const { return open_s > 0 ? double(frames) / open_s : 0; }
  nlohmann::json to_json() const;
};

class LiveSession : public std::enable_shared_from_this<LiveSession> {
 public:
  using Clock = std::chrono::steady_clock;
  LiveSession(boost::asio::io_context& io, const LoadOptions& options, int index);
  void start(const boost::asio::ip::tcp::resolver::results_type& endpoints);
  const SessionResult& result() const { return result_; }

 private:
  void on_connect(boost::beast::error_code ec);
  void on_handshake(boost::beast::error_code ec);
  void do_read();
  void on_read(boost::beast::error_code ec, size_t bytes);
  void on_text(const std::string& text);
  void on_frame(size_t bytes);
  void next_pose();
  void on_pose_timer(boost::beast::error_code ec);
  void send(nlohmann::json message);
  void do_write();
  void arm_stall();
  void finish(const std::string& why);
  void closed();

  boost::beast::websocket::stream<boost::beast::tcp_stream> ws_;
  boost::beast::websocket::response_type upgrade_;
  boost::beast::flat_buffer buffer_;
  const LoadOptions& options_;
  PoseScript script_;
  boost::asio::steady_timer pose_timer_, deadline_, stall_;

  Clock::time_point opened_, hello_sent_, poses_from_, header_at_;
  long long tick_ = 0, revision_ = 0;
  std::deque<std::pair<long long, Clock::time_point>> pending_;  // poses not yet answered
  std::optional<nlohmann::json> header_;  // a frame header awaiting its image
  std::deque<std::string> writes_;
  bool finishing_ = false;
  SessionResult result_;
};

}  // namespace scatter::load
