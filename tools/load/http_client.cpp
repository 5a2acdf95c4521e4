#include "tools/load/http_client.hpp"

#include <chrono>

namespace scatter::load {

namespace beast = boost::beast;
namespace http = beast::http;

HttpClient::HttpClient(const LoadOptions& options) : options_(options), stream_(io_) {}

HttpReply HttpClient::request(http::verb method, const std::string& target,
                              const std::string& body) {
  http::request<http::string_body> req{method, target, 11};
  req.set(http::field::host, options_.host + ":" + options_.port);
  req.set(http::field::user_agent, "scatter-load");
  if (!options_.token.empty()) req.set(http::field::authorization, "Bearer " + options_.token);
  if (!body.empty()) {
    req.set(http::field::content_type, "application/json");
    req.body() = body;
  }
  req.keep_alive(true);
  req.prepare_payload();
  if (open_) {
    try {
      return exchange(req);
    } catch (const boost::system::system_error& e) {
      if (e.code() == beast::error::timeout) throw;
      // The server closed the kept-alive connection: once more on a new one.
    }
  }
  return exchange(req);
}

HttpReply HttpClient::exchange(const http::request<http::string_body>& req) {
  auto timeout = span(options_.timeout_s);
  if (!open_) {
    beast::error_code ignored;
    stream_.socket().close(ignored);
    buffer_.clear();
    boost::asio::ip::tcp::resolver resolver(io_);
    stream_.expires_after(timeout);
    stream_.connect(resolver.resolve(options_.host, options_.port));
    open_ = true;
  }
  auto start = std::chrono::steady_clock::now();
  // Asynchronous calls run to completion here, so that the stream's timer bounds them
  // (synchronous ones ignore it): a request that takes longer than timeout_s fails.
  http::response_parser<http::string_body> parser;
  parser.body_limit(1ull << 30);
  beast::error_code ec;
  stream_.expires_after(timeout);
  http::async_write(stream_, req, [&](beast::error_code e, size_t) {
    if ((ec = e)) return;
    http::async_read(stream_, buffer_, parser, [&](beast::error_code e2, size_t) { ec = e2; });
  });
  io_.restart();
  io_.run();
  if (ec) {
    open_ = false;
    throw boost::system::system_error(ec);
  }
  HttpReply reply;
  reply.ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  reply.status = parser.get().result_int();
  reply.body = parser.get().body();
  if (!parser.get().keep_alive()) open_ = false;
  return reply;
}

}  // namespace scatter::load
