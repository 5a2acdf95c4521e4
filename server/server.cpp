#include "server/server.hpp"

#include <spdlog/spdlog.h>

#include "server/http_session.hpp"

namespace scatter::server {

Server::Server(ServerOptions options)
    : options_([&] {
        if (!options.cache) options.cache = std::make_shared<BakeCache>();
        return std::move(options);
      }()),
      workers_(static_cast<size_t>(std::max(1, options_.workers))),
      queue_(options_.gpu, options_.cache.get(), options_.max_queue, "render"),
      bake_queue_(options_.gpu, options_.cache.get(), BakeJobs::kMaxActive, "bake"),
      api_(
          [&] {
            ApiOptions a = options_.api;
            a.max_message_bytes = options_.max_upload_mb << 20;
            return a;
          }(),
          queue_, metrics_, &bake_queue_,
          [this](std::function<void()> f) { boost::asio::post(workers_, std::move(f)); }),
      acceptor_(boost::asio::make_strand(io_)),
      stop_timer_(io_) {
  boost::system::error_code ec;
  auto address = boost::asio::ip::make_address(options_.bind, ec);
  if (ec) throw std::runtime_error("--bind: \"" + options_.bind + "\" is not an IP address");
  tcp::endpoint endpoint(address, options_.port);
  acceptor_.open(endpoint.protocol(), ec);
  if (!ec) acceptor_.set_option(boost::asio::socket_base::reuse_address(true), ec);
  if (!ec) acceptor_.bind(endpoint, ec);
  if (!ec) acceptor_.listen(boost::asio::socket_base::max_listen_connections, ec);
  if (ec)
    throw std::runtime_error("cannot listen on " + options_.bind + ":" +
                             std::to_string(options_.port) + ": " + ec.message());
  port_ = acceptor_.local_endpoint().port();
  do_accept();
}

Server::~Server() {
  stop();
  // The queues' threads first (their callbacks reach the Api, the workers and io_), then the
  // workers' encodes; io_ and its sessions go last, with the members.
  queue_.stop("the server is stopping");
  bake_queue_.stop("the server is stopping");
  wait_stopped(std::chrono::hours(24));
  workers_.join();
}

bool Server::wait_stopped(std::chrono::milliseconds timeout) {
  auto until = std::chrono::steady_clock::now() + timeout;
  bool render = queue_.wait_stopped(timeout);
  auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
      until - std::chrono::steady_clock::now());
  return bake_queue_.wait_stopped(std::max(left, std::chrono::milliseconds(0))) && render;
}

void Server::do_accept() {
  acceptor_.async_accept(
      boost::asio::make_strand(io_), [this](boost::system::error_code ec, tcp::socket socket) {
        if (ec) {
          if (ec != boost::asio::error::operation_aborted && acceptor_.is_open())
            spdlog::warn("event=accept_error error=\"{}\"", ec.message());
        } else {
          // A frame is a header then an image: without this, Nagle's algorithm holds the image
          // until the client acknowledges the header (its delayed ack: ~40 ms a frame).
          socket.set_option(tcp::no_delay(true), ec);
          std::make_shared<HttpSession>(std::move(socket), api_, workers_,
                                        options_.max_upload_mb << 20, answers_owed_)
              ->run();
        }
        // Closed by stop() (on this strand): no next accept, which would fail on the closed socket.
        if (acceptor_.is_open()) do_accept();
      });
}

void Server::run(bool handle_signals) {
  std::unique_ptr<boost::asio::signal_set> signals;
  if (handle_signals) {
    signals = std::make_unique<boost::asio::signal_set>(io_, SIGINT, SIGTERM);
    signals->async_wait([this](boost::system::error_code, int sig) {
      spdlog::info("event=signal signal={} action=stop", sig);
      stop();
    });
  }
  std::vector<std::thread> threads;
  for (int i = 1; i < options_.io_threads; ++i) threads.emplace_back([this] { io_.run(); });
  io_.run();
  for (auto& t : threads) t.join();
}

void Server::stop() {
  if (stopping_.exchange(true)) return;  // once: a second linger would cancel the first's timer
  // Cancelled now, not behind the I/O: queued work is dropped and the running job stops at its
  // next check.
  api_.cancel_bakes();
  queue_.stop("the server is stopping");
  bake_queue_.stop("the server is stopping");
  // On the acceptor's strand: its accept handler (which may be starting the next accept) runs on
  // another I/O thread otherwise, and a close racing it freed the descriptor under that accept.
  boost::asio::post(acceptor_.get_executor(), [this] {
    boost::system::error_code ec;
    acceptor_.close(ec);
    linger(std::chrono::steady_clock::now() + kStopGrace, std::nullopt);
  });
}

void Server::linger(std::chrono::steady_clock::time_point deadline,
                    std::optional<std::chrono::steady_clock::time_point> answers_by) {
  // The I/O ends once the queues' threads are done (the running job has stopped at its check and
  // answered "503: the server is stopping") or the grace is over, then once every request read
  // has its answer written (the answers go through the workers and the sessions' strands) or a
  // grace after, and a moment after that, for the last bytes to leave. Ending it a fixed 250 ms
  // after the queues stopped lost a 503 on a loaded machine, its client waiting on an open socket
  // (ServiceTest.QuickRoutesAndValidationErrorsAnswerAtOnceWhileARenderRuns hung so).
  const auto now = std::chrono::steady_clock::now();
  const bool stopped = queue_.wait_stopped(std::chrono::milliseconds(0)) &&
                       bake_queue_.wait_stopped(std::chrono::milliseconds(0));
  if (!answers_by && (stopped || now >= deadline)) answers_by = now + kStopGrace;
  if (answers_by && (answers_owed_ == 0 || now >= *answers_by)) {
    stop_timer_.expires_after(kStopLinger);
    stop_timer_.async_wait([this](boost::system::error_code) { io_.stop(); });
    return;
  }
  stop_timer_.expires_after(std::chrono::milliseconds(10));
  stop_timer_.async_wait(
      [this, deadline, answers_by](boost::system::error_code) { linger(deadline, answers_by); });
}

}  // namespace scatter::server
