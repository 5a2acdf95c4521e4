// A live session over WebSocket (/api/ws). The client sends JSON messages; the server answers with
// a JSON frame header followed by the encoded frame as a binary message.
//
//   {"type": "hello", "scene_name": "bunny" | "scene": {...}, "pipeline": "surface",
//    "terms": "...", "format": "jpg" | "png", "settings": {...},
//    "quality": {"max_error": E, "refine_floor": F}, "exposure": X,
//    "request": n, "keep_view": true,     keep_view: the session's camera and lights stay
//    "medium": {...},                     with scene_name: that scene in another medium
//    "composite": {"pipeline": "psf", "settings": {...}, "scale": 0.5}}
//                                         a still view of the single term adds the multiple
//                                         term from that pipeline (server/refine.hpp)
//
// After a hello with a "request" (> 0) is applied the server says {"type": "scene", "request",
// "scene_name", "source" (the scene's JSON, for a client to edit), "camera", "lights", "bounds":
// {"min", "max"}, "scenes" (names in --scenes-dir)}; frame headers and errors carry the hello's
// "request", so a client drops frames of a scene it no longer shows.
//   {"type": "camera", "position": [..], "target": [..], "up": [..], "fov_deg": 40, "revision": n}
//   {"type": "lights", "lights": [...], "revision": n}
//   {"type": "cancel"}                    stops the frame in flight (not yet sent) and the
//   refinement
//   {"type": "ack", "frame": id}
//   {"type": "ping"}                      keeps a still session alive; answered {"type": "pong"}
//
// Latest wins: camera and light messages only replace the session's state; a frame renders the
// newest state when it starts, so stale poses are never rendered. At most one frame is in flight:
// from the moment it is queued until the client acks it, and an ack counts only for that frame.
// While poses keep coming frames are rendered reduced, at a scale chosen per pipeline from its
// measured reduced-frame times against ReducedFrames::kFrameBudgetMs (server/reduced_frames.hpp);
// after ~200 ms without a change (and after a hello) the still view is refined (server/refine.hpp):
// the full-size frame (header "reduced": false), the pipeline's higher qualities, then accumulated
// reference passes, each refined frame's header with "error_estimate" and "refine": {"stage",
// "state", ...}, sent only when its estimate dropped by a tenth, until it is under refine_floor or
// the passes run out. A refinement step whose result is not sent frees the slot at once (nothing to
// ack) and is told as {"type": "refine", "refine", "error_estimate", "shown_error_estimate"}. A
// camera, lights or hello message cancels a still frame not yet sent (its render stops at its next
// progress check; the new pose's job queues behind it). Each session otherwise has at most one
// job on the render thread's FIFO queue, so sessions take turns. The render thread posts the
// result here; it is encoded on the worker pool and sent from this session's strand.
//
// Bounded: a client that does not read its messages (more than kMaxQueuedWrites unsent) is
// disconnected; one that sends nothing for --session-idle-s gives its slot back. A bad message
// gets {"type": "error", "error", "field"}; the connection stays. A client that leaves cancels
// its frame in flight.
#pragma once

#include <boost/asio.hpp>
#include <boost/beast.hpp>
#include <boost/beast/websocket.hpp>
#include <deque>
#include <map>
#include <memory>
#include <optional>

#include "scene/scene.hpp"
#include "server/api.hpp"
#include "server/reduced_frames.hpp"
#include "server/refine.hpp"
#include "server/session_hello.hpp"

namespace scatter::server {

class WsSession : public std::enable_shared_from_this<WsSession> {
 public:
  static constexpr size_t kMaxQueuedWrites = 32;
  static constexpr size_t kMaxBacklog = 64;  // messages held while a hello's scene loads

  // Holds one of the Api's session slots (taken by the caller) and gives it back when it ends.
  WsSession(boost::asio::ip::tcp::socket&& socket, Api& api, boost::asio::thread_pool& workers);
  ~WsSession();
  void run(boost::beast::http::request<boost::beast::http::string_body> upgrade);

 private:
  void do_read();
  void on_read(boost::beast::error_code ec, size_t bytes);
  void dispatch(std::string text);
  void handle(const std::string& text);
  void read_hello(nlohmann::json msg);
  void apply_hello(Hello hello);
  void maybe_render();
  void start_frame(std::optional<RefineStep> step);
  void on_rendered(long long frame, bool reduced, RenderOutcome outcome);
  void send_frame(long long frame, bool reduced, RenderOutcome outcome, nlohmann::json extra);
  void cancel_unsent(const std::string& why);
  void send(std::string message, bool binary);
  void do_write();
  void send_error(const std::string& error, const std::string& field);
  void schedule_refine();
  void watch_idle();
  void end(const std::string& why);
  void release_slot();

  boost::beast::websocket::stream<boost::beast::tcp_stream> ws_;
  boost::beast::flat_buffer buffer_;
  Api& api_;
  RenderQueue& queue_;
  Metrics& metrics_;
  boost::asio::thread_pool& workers_;
  const ApiOptions& options_;

  // Session state; touched only on the session's strand.
  std::shared_ptr<const Scene>
      scene_;                 // as loaded, shared; the camera and lights below override it
  double scene_load_ms_ = 0;  // reported with the first frame after a hello that loaded it
  Camera camera_;
  std::vector<Light> lights_;
  std::string pipeline_ = "surface", terms_, format_ = "jpg";
  bool snapshot_ = false;             // the next still frame goes out as EXR ("snapshot")
  std::string frame_format_ = "jpg";  // the frame in flight's
  Settings settings_;
  std::optional<double> max_error_;     // the hello's quality.max_error, for the session's frames
  std::optional<Composite> composite_;  // the hello's: the multiple term still frames add
  double refine_floor_ = 0.01;          // the hello's quality.refine_floor
  long long camera_revision_ = 0, light_revision_ = 0;
  bool dirty_ = false, closed_ = false;
  // The frame in flight: queued, rendering, or sent and not yet acked (0: none).
  long long in_flight_ = 0;
  long long frame_camera_revision_ = 0, frame_light_revision_ = 0;  // the state it renders
  bool awaiting_ack_ = false;
  std::shared_ptr<CancelToken> cancel_;   // the frame in flight's
  std::optional<RefineStep> frame_step_;  // the frame in flight's refinement step (none: reduced)
  // While the user moves the camera or lights, frames render at half size; once the view has
  // been still for idle_refine_ms, it is refined (server/refine.hpp): the full-size frame first.
  bool interactive_ = false, last_frame_reduced_ = false;
  Refinement refine_;
  std::chrono::steady_clock::time_point last_change_, last_message_;
  boost::asio::steady_timer refine_timer_, idle_timer_;
  long long next_frame_ = 1;
  long long request_ = 0;  // the applied hello's "request", echoed in frame headers
  double exposure_ = 1.0;
  ReducedFrames reduced_;  // the reduced frames' size and settings, per pipeline
  bool hello_pending_ = false;
  bool holds_slot_ = true;  // the Api's session slot, given back once (at end() or destruction)
  std::deque<std::string> backlog_;
  std::deque<std::pair<std::shared_ptr<const std::string>, bool>> writes_;
};

}  // namespace scatter::server
