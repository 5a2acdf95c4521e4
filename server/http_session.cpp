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

http::response<http::string_body> to_beast(const HttpResponse& r, unsigned version, bool keep_alive) {
  http::response<http::string_body> res{static_cast<http::status>(r.status), version};
  res.set(http::field::server, "scatterd");
  res.set(http::field::content_type, r.content_type);
  for (const auto& [k, v] : r.headers) res.set(k, v);
  res.keep_alive(keep_alive);
  res.body() = r.body;
  res.prepare_payload();
  return res;
}

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
  parser_->body_limit(body_limit_);
  stream_.expires_after(std::chrono::seconds(60));
  http::async_read(stream_, buffer_, *parser_,
                   beast::bind_front_handler(&HttpSession::on_read, shared_from_this()));
}

void HttpSession::on_read(beast::error_code ec, size_t) {
  if (ec == http::error::body_limit) {
    HttpResponse r = Api::error(413, "the request body is larger than the server's limit of " +
                                         std::to_string(body_limit_) + " bytes");
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
        HttpResponse r = Api::error(503, "all " + std::to_string(api_.options().max_sessions) +
                                             " live sessions are in use; try again later");
        return send(to_beast(r, req.version(), false));
      }
      api_.metrics().count_request("/api/ws", 101);
      std::make_shared<WsSession>(stream_.release_socket(), api_, workers_)->run(std::move(req));
      return;
    }
  }
  HttpRequest request{std::string(req.method_string()), std::string(req.target()), req.body(),
                      std::string(req[http::field::authorization])};
  unsigned version = req.version();
  bool keep_alive = req.keep_alive();
  // The Api may wait on the render thread: run it off the I/O threads, then write from the
  // connection's own executor.
  boost::asio::post(workers_, [self = shared_from_this(), request, version, keep_alive] {
    HttpResponse r = self->api_.handle(request);
    boost::asio::post(self->stream_.get_executor(), [self, r, version, keep_alive] {
      self->send(to_beast(r, version, keep_alive));
    });
  });
}

void HttpSession::send(http::response<http::string_body>&& response) {
  response_ = std::make_shared<http::response<http::string_body>>(std::move(response));
  bool keep_alive = response_->keep_alive();
  stream_.expires_after(std::chrono::seconds(60));
  http::async_write(stream_, *response_,
                    beast::bind_front_handler(&HttpSession::on_write, shared_from_this(), keep_alive));
}

void HttpSession::on_write(bool keep_alive, beast::error_code ec, size_t) {
  if (ec) return fail(ec, "write");
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
  stream_.async_read_some(boost::asio::buffer(drain_), [self = shared_from_this()](beast::error_code ec, size_t) {
    if (!ec) self->do_drain();
  });
}

}  // namespace scatter::server
