// The daemon: listens on one port, serves the Api over HTTP and WebSocket. Two GPU-owning threads
// (RenderQueue): one renders frames and one-shot renders, one bakes, each with its own OpenCL and
// EGL contexts, so a bake never holds a live session's frame. Asio threads do the I/O; a small
// worker pool parses requests and encodes images. No thread waits on another's result.
#pragma once

#include <atomic>
#include <boost/asio.hpp>
#include <memory>
#include <optional>
#include <thread>
#include <vector>

#include "bake/cache.hpp"
#include "server/api.hpp"

namespace scatter::server {

struct ServerOptions {
  std::string bind = "127.0.0.1";
  unsigned short port = 8080;  // 0: any free port (see Server::port())
  size_t max_upload_mb = 64;
  int io_threads = 2;
  int workers = 4;
  size_t max_queue =
      64;  // renders waiting for the render thread (REST; each live session adds one)
  ApiOptions api;
  gpu::GpuOptions gpu;
  std::shared_ptr<BakeCache> cache;  // bake products; null: a memory-only cache
};

class Server {
 public:
  // Binds and starts listening; throws std::runtime_error if the address cannot be bound.
  explicit Server(ServerOptions options);
  ~Server();  // stops, waits for the running render and bake (however long), joins every thread
  unsigned short port() const { return port_; }
  // Serves until stop() (or SIGINT/SIGTERM when `handle_signals`).
  void run(bool handle_signals);
  // Stops accepting, drops queued renders and bakes, cancels the running ones, and ends run()
  // once they have stopped (or after kStopGrace, whichever comes first) and every request read
  // has its answer written (or kStopGrace after that: at most 2 x kStopGrace, and a moment).
  void stop();
  static constexpr std::chrono::milliseconds kStopGrace{1000};
  // After run() returned: waits up to `timeout` for the render and bake threads to finish their
  // cancelled jobs; false if one is still busy (a pipeline step that cannot be interrupted).
  bool wait_stopped(std::chrono::milliseconds timeout);

 private:
  void do_accept();

  ServerOptions options_;
  boost::asio::thread_pool workers_;
  RenderQueue queue_, bake_queue_;
  Metrics metrics_;
  Api api_;
  // Requests read and not answered yet, over the HTTP sessions (HttpSession): before io_, so
  // that the sessions it destroys still find it.
  std::atomic<int> answers_owed_{0};
  // After the Api: destroyed before it, with the sessions its unrun handlers hold (they give
  // their slots back to the Api). ~Server has stopped every thread that posts here by then.
  boost::asio::io_context io_;
  boost::asio::ip::tcp::acceptor acceptor_;  // on a strand of io_: its handlers and stop()'s close
  boost::asio::steady_timer stop_timer_;
  std::atomic<bool> stopping_{false};  // stop() has run
  static constexpr std::chrono::milliseconds kStopLinger{250};
  void linger(std::chrono::steady_clock::time_point deadline,
              std::optional<std::chrono::steady_clock::time_point> answers_by);
  unsigned short port_ = 0;
};

}  // namespace scatter::server
