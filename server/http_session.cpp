#include "server/http_session.hpp"

#include <spdlog/spdlog.h>

#include <cctype>

#include "server/api_util.hpp"
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

// The page's token travels in this cookie once /?token=T was opened, so that the page's own
// assets, REST calls and WebSocket carry it without the page adding it to every URL.
constexpr const char* kTokenCookie = "scatter_token";

// Every byte but unreserved ones as %XX, so that any token survives the cookie.
std::string percent_encode(const std::string& s) {
  static const char* kHex = "0123456789ABCDEF";
  std::string out;
  for (unsigned char c : s) {
    if (std::isalnum(c) || c == '-' || c == '_' || c == '.' || c == '~') {
      out += static_cast<char>(c);
    } else {
      out += '%';
      out += kHex[c >> 4];
      out += kHex[c & 15];
    }
  }
  return out;
}

// "Bearer T" from the Authorization header, else from the token cookie (percent-decoded).
std::string authorization(const http::request<http::string_body>& req) {
  std::string header(req[http::field::authorization]);
  if (!header.empty()) return header;
  std::string_view cookies = req[http::field::cookie];
  std::string name = std::string(kTokenCookie) + "=";
  for (size_t at = 0; at < cookies.size();) {
    size_t end = std::min(cookies.find(';', at), cookies.size());
    std::string_view item = cookies.substr(at, end - at);
    while (!item.empty() && item.front() == ' ') item.remove_prefix(1);
    if (item.substr(0, name.size()) == name) {
      auto q = parse_query("?t=" + std::string(item.substr(name.size())));
      if (auto t = q.find("t"); t != q.end()) return "Bearer " + t->second;
    }
    at = end + 1;
  }
  return "";
}

bool is_page(const std::string& path) {
  return path == "/" || path == "/index.html";
}

// A person who opened the page with a wrong or missing token reads why, not JSON.
constexpr const char* kUnauthorizedPage =
    "<!doctype html><html lang=\"en\"><head><meta charset=\"utf-8\">"
    "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
    "<title>scatter: token needed</title></head>"
    "<body style=\"font: 16px sans-serif; background: #111; color: #ddd; padding: 2rem\">"
    "<h1>This scatterd needs a token</h1>"
    "<p>The server was started with <code>--token</code>, and this address carries no token or "
    "a wrong one. Open <code>/?token=YOUR_TOKEN</code> (percent-encode <code>+ / = &amp;</code> "
    "as <code>%2B %2F %3D %26</code>); the page then keeps it in a cookie.</p></body></html>";

// Beast's default (8 KiB) as an explicit limit: the 431 message names it.
constexpr uint32_t kHeaderLimit = 8 * 1024;

}  // namespace

HttpSession::HttpSession(tcp::socket&& socket, Api& api, boost::asio::thread_pool& workers,
                         size_t body_limit, std::atomic<int>& owed)
    : stream_(std::move(socket)),
      api_(api),
      workers_(workers),
      body_limit_(body_limit),
      owed_(owed) {}

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
    HttpRequest probe{"GET", target, "", authorization(req)};
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
  owing_.emplace(owed_);
  HttpRequest request{std::string(req.method_string()), std::string(req.target()),
                      std::move(req.body()), authorization(req), cancel_};
  unsigned version = req.version();
  bool keep_alive = req.keep_alive();
  std::string path = request.target.substr(0, request.target.find('?'));
  std::string query_token;
  if (is_page(path) && req.method() == http::verb::get) {
    auto q = parse_query(request.target);
    if (auto t = q.find("token"); t != q.end()) query_token = t->second;
  }
  bool page = is_page(path);
  auto respond = [self = shared_from_this(), version, keep_alive, page,
                  query_token](HttpResponse r) {
    if (page && r.status == 401) r = {401, "text/html; charset=utf-8", kUnauthorizedPage, {}};
    if (page && r.status == 200 && !query_token.empty())
      r.headers.emplace_back("Set-Cookie", std::string(kTokenCookie) + "=" +
                                               percent_encode(query_token) +
                                               "; Path=/; HttpOnly; SameSite=Strict");
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
  if (!owing_) owing_.emplace(owed_);  // an answer to a request the parser refused
  response_ = std::make_shared<http::response<http::string_body>>(std::move(response));
  bool keep_alive = response_->keep_alive();
  stream_.expires_after(std::chrono::seconds(60));
  http::async_write(
      stream_, *response_,
      beast::bind_front_handler(&HttpSession::on_write, shared_from_this(), keep_alive));
}

void HttpSession::on_write(bool keep_alive, beast::error_code ec, size_t) {
  owing_.reset();  // written, or never will be
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
