// One HTTP connection: reads requests (with a body limit and a timeout), hands them to the Api on
// a worker thread so that a render does not block other connections' I/O, and writes responses.
#pragma once

#include <boost/asio.hpp>
#include <boost/beast.hpp>
#include <memory>

#include "server/api.hpp"

namespace scatter::server {

namespace beast = boost::beast;
namespace http = beast::http;
using tcp = boost::asio::ip::tcp;

class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(tcp::socket&& socket, Api& api, boost::asio::thread_pool& workers, size_t body_limit);
  void run();

 private:
  void do_read();
  void on_read(beast::error_code ec, size_t bytes);
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
};

}  // namespace scatter::server
