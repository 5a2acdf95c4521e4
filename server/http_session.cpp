#include "server/http_session.hpp"

#include <spdlog/spdlog.h>

#include "server/ws_session.hpp"

namespace scatter::server {
namespace {

// Errors that only mean the peer went away.
void fail(beast::error_code ec, const char* what) {
  if (ec == boost::asio::error::operation_aborted || ec == beast::error::timeout ||
      ec == http::error::end_of_stream || ec == boost::asio::error::connection_reset)
    return;
  spdlog::debug("event=http_error stage={} error=\"{}\"", what, ec.message());
}

http::response<http::string_body> to_beast(const HttpResponse& r, unsigned version,
                                           bool keep_alive) {
  http::response<http::string_body> res{static_cast<http::status>(r.status), version};
  res.set(http::field::server, "scatterd");
  res.set(http::field::content_type, r.content_type);
  for (const auto& [k, v] : r.headers) res.set(k, v);
  res.keep_alive(keep_alive);
  res.body() = r.body;
  res.prepare_payload();
  return res;
}

// Beast's default (8 KiB) as an explicit limit: the 431 message names it.
constexpr uint32_t kHeaderLimit = 8 * 1024;

}  // namespace

HttpSession::HttpSession(tcp::socket&& socket, Api& api, boost::asio::thread_pool& workers,
                         size_t body_limit)
    : stream_(std::move(socket)), api_(api), workers_(workers), body_limit_(body_limit) {}

void HttpSession::run() {
  boost::asio::dispatch(stream_.get_executor(),
                        beast::bind_front_handler(&HttpSession::do_read, shared_from_this()));
}

void HttpSession::do_read() {
  parser_ = std::make_unique<http::request_parser<http::string_body>>();
  parser_->header_limit(kHeaderLimit);
  parser_->body_limit(body_limit_);
  stream_.expires_after(std::chrono::seconds(60));
  http::async_read(stream_, buffer_, *parser_,
                   beast::bind_front_handler(&HttpSession::on_read, shared_from_this()));
}

void HttpSession::on_read(beast::error_code ec, size_t) {
  if (ec == http::error::body_limit) {
    HttpResponse r = Api::error(413, "the request body is larger than the server's limit of " +
                                         std::to_string(body_limit_) + " bytes (--max-upload-mb)");
    return send(to_beast(r, 11, false));
  }
  if (ec == http::error::header_limit) {
    HttpResponse r =
        Api::error(431, "the request's headers are larger than the server's limit of " +
                            std::to_string(kHeaderLimit) + " bytes");
    return send(to_beast(r, 11, false));
  }
  if (ec && ec.category() == http::make_error_code(http::error::bad_target).category() &&
      ec != http::error::end_of_stream && ec != http::error::partial_message) {
    HttpResponse r = Api::error(400, "the request is not valid HTTP/1.1: " + ec.message());
    return send(to_beast(r, 11, false));
  }
  if (ec) return fail(ec, "read");
  auto req = parser_->release();
  if (beast::websocket::is_upgrade(req)) {
    std::string target(req.target());
    HttpRequest probe{"GET", target, "", std::string(req[http::field::authorization])};
    if (target.substr(0, target.find('?')) == "/api/ws" && api_.authorized(probe)) {
      if (!api_.acquire_session()) {
        api_.metrics().count_request("/api/ws", 503);
        HttpResponse r =
            Api::error(503, "all " + std::to_string(api_.options().max_sessions) +
                                " live sessions are in use (--max-sessions); try again later");
        return send(to_beast(r, req.version(), false));
      }
      api_.metrics().count_request("/api/ws", 101);
      std::make_shared<WsSession>(stream_.release_socket(), api_, workers_)->run(std::move(req));
      return;
    }
  }
  cancel_ = std::make_shared<CancelToken>();
  HttpRequest request{std::string(req.method_string()), std::string(req.target()),
                      std::move(req.body()), std::string(req[http::field::authorization]), cancel_};
  unsigned version = req.version();
  bool keep_alive = req.keep_alive();
  auto respond = [self = shared_from_this(), version, keep_alive](HttpResponse r) {
    boost::asio::post(self->stream_.get_executor(), [self, r = std::move(r), version, keep_alive] {
      self->send(to_beast(r, version, keep_alive));
    });
  };
  if (Api::quick(request)) return api_.handle(request, respond);  // answered from memory, here
  // Parsing scenes and checking uploads take CPU: off the I/O threads. Renders are then queued
  // and answered from the render thread's completion; nothing waits.
  boost::asio::post(workers_, [self = shared_from_this(), request = std::move(request), respond] {
    self->api_.handle(request, respond);
  });
  watch();
}

void HttpSession::watch() {
  watching_ = true;
  stream_.expires_never();  // a long render is not the client's timeout
  stream_.async_read_some(buffer_.prepare(4096),
                          beast::bind_front_handler(&HttpSession::on_watch, shared_from_this()));
}

void HttpSession::on_watch(beast::error_code ec, size_t bytes) {
  watching_ = false;
  buffer_.commit(bytes);  // a pipelined request: kept for the next read
  if (ec && ec != boost::asio::error::operation_aborted && cancel_)
    cancel_->cancel("the client closed the connection");
  if (after_watch_) std::exchange(after_watch_, nullptr)();
}

void HttpSession::send(http::response<http::string_body>&& response) {
  response_ = std::make_shared<http::response<http::string_body>>(std::move(response));
  bool keep_alive = response_->keep_alive();
  stream_.expires_after(std::chrono::seconds(60));
  http::async_write(
      stream_, *response_,
      beast::bind_front_handler(&HttpSession::on_write, shared_from_this(), keep_alive));
}

void HttpSession::on_write(bool keep_alive, beast::error_code ec, size_t) {
  if (ec) return fail(ec, "write");
  cancel_.reset();
  if (watching_) {  // one read at a time: the watch ends first, then on_watch comes back here
    after_watch_ = [self = shared_from_this(), keep_alive] { self->on_write(keep_alive, {}, 0); };
    stream_.socket().cancel(ec);
    return;
  }
  if (!keep_alive) {
    // Lingering close: stop sending, then read and drop what the client still sends (say the
    // rest of an oversized body), so that it sees our answer instead of a reset connection.
    stream_.socket().shutdown(tcp::socket::shutdown_send, ec);
    stream_.expires_after(std::chrono::seconds(5));
    return do_drain();
  }
  do_read();
}

void HttpSession::do_drain() {
  drain_.resize(64 * 1024);
  stream_.async_read_some(boost::asio::buffer(drain_),
                          [self = shared_from_this()](beast::error_code ec, size_t) {
                            if (!ec) self->do_drain();
                          });
}

}  // namespace scatter::server
