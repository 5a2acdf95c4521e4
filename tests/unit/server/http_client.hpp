// A plain HTTP client on loopback for the daemon's tests (Beast, one request per connection).
#pragma once

#include <boost/beast.hpp>
#include <string>

namespace scatter::server::test_http {

namespace beast = boost::beast;
namespace http = beast::http;

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
  http::read(stream, buffer, parser);
  beast::error_code ec;
  stream.socket().shutdown(boost::asio::ip::tcp::socket::shutdown_both, ec);
  return parser.release();
}

}  // namespace scatter::server::test_http
