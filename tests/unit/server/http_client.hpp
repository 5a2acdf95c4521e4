// A plain HTTP client on loopback for the daemon's tests (Beast, one request per connection).
#pragma once

#include <boost/beast.hpp>
#include <chrono>
#include <string>

namespace scatter::server::test_http {

namespace beast = boost::beast;
namespace http = beast::http;

inline constexpr int kAnswerTimeoutS = 300;

// A real HTTP client on loopback.
inline http::response<http::string_body> request(unsigned short port, http::verb verb,
                                                 const std::string& target,
                                                 const std::string& body = "") {
  boost::asio::io_context io;
  beast::tcp_stream stream(io);
  stream.connect(boost::asio::ip::tcp::endpoint(boost::asio::ip::make_address("127.0.0.1"), port));
  http::request<http::string_body> req{verb, target, 11};
  req.set(http::field::host, "127.0.0.1");
  req.body() = body;
  req.prepare_payload();
  http::write(stream, req);
  beast::flat_buffer buffer;
  http::response_parser<http::string_body> parser;
  parser.body_limit(64 << 20);
  // With a deadline: a lost answer fails the test (the read throws) instead of hanging it; no
  // answer in these tests takes minutes.
  beast::error_code read;
  stream.expires_after(std::chrono::seconds(kAnswerTimeoutS));
  http::async_read(stream, buffer, parser, [&](beast::error_code e, size_t) { read = e; });
  io.run();
  if (read) throw beast::system_error(read);
  beast::error_code ec;
  stream.socket().shutdown(boost::asio::ip::tcp::socket::shutdown_both, ec);
  return parser.release();
}

}  // namespace scatter::server::test_http
