// A blocking HTTP/1.1 client on one keep-alive connection (reopened when the server closes it),
// for the REST clients and the RSS sampler; each owns one and uses it from one thread.
#pragma once

#include <boost/asio.hpp>
#include <boost/beast.hpp>
#include <string>

#include "tools/load/load_options.hpp"

namespace scatter::load {

struct HttpReply {
  int status = 0;
  std::string body;
  double ms = 0;  // from sending the request to the whole response read
};

class HttpClient {
 public:
  explicit HttpClient(const LoadOptions& options);
  // Throws boost::system::system_error when the daemon cannot be reached or the exchange fails
  // (one retry on a fresh connection when a kept-alive one turns out closed).
  HttpReply request(boost::beast::http::verb method, const std::string& target,
                    const std::string& body = "");

 private:
  HttpReply exchange(const boost::beast::http::request<boost::beast::http::string_body>& req);

  const LoadOptions& options_;
  boost::asio::io_context io_;
  boost::beast::tcp_stream stream_;
  boost::beast::flat_buffer buffer_;
  bool open_ = false;
};

}  // namespace scatter::load
