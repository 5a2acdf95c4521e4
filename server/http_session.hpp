// One HTTP connection: reads requests (with header and body limits and a timeout), answers quick
// ones (health, metrics, status) on its own strand at once, hands the others to the worker pool
// (uploads to check, scenes to parse) from where renders are queued on the render thread, and
// writes each response from the connection's strand. No thread waits for a render.
//
// While a request is being served the connection watches its socket: a client that hangs up
// cancels its render (bytes that arrive meanwhile, a pipelined request, are kept for the parser).
#pragma once

#include <atomic>
#include <boost/asio.hpp>
#include <boost/beast.hpp>
#include <functional>
#include <memory>
#include <optional>

#include "server/api.hpp"

namespace scatter::server {

namespace beast = boost::beast;
namespace http = beast::http;
using tcp = boost::asio::ip::tcp;

class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  // `owed` counts the requests read whose answer is not written yet, over every session: the
  // server's stop waits for it to fall to 0 before it ends the I/O (Server::linger).
  HttpSession(tcp::socket&& socket, Api& api, boost::asio::thread_pool& workers, size_t body_limit,
              std::atomic<int>& owed);
  void run();

 private:
  void do_read();
  void on_read(beast::error_code ec, size_t bytes);
  void watch();
  void on_watch(beast::error_code ec, size_t bytes);
  void send(http::response<http::string_body>&& response);
  void on_write(bool keep_alive, beast::error_code ec, size_t bytes);
  void do_drain();

  beast::tcp_stream stream_;
  beast::flat_buffer buffer_;
  std::unique_ptr<http::request_parser<http::string_body>> parser_;
  Api& api_;
  boost::asio::thread_pool& workers_;
  size_t body_limit_;
  std::shared_ptr<http::response<http::string_body>> response_;
  std::vector<char> drain_;
  std::shared_ptr<CancelToken> cancel_;  // the request being served
  bool watching_ = false;
  std::function<void()> after_watch_;  // what on_write would have done, once the watch has ended
  // One count in `owed` while a request read is unanswered (released with the session too).
  struct Owing {
    std::atomic<int>* owed;
    explicit Owing(std::atomic<int>& n) : owed(&n) { ++n; }
    Owing(const Owing&) = delete;
    Owing& operator=(const Owing&) = delete;
    ~Owing() { --*owed; }
  };
  std::atomic<int>& owed_;
  std::optional<Owing> owing_;
};

}  // namespace scatter::server
