// The daemon on a free loopback port for the server's tests (server_test.cpp,
// ws_session_test.cpp), and a scripted WebSocket client of its live sessions.
#pragma once

#include <gtest/gtest.h>

#include <boost/beast.hpp>
#include <cmath>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "../test_util.hpp"
#include "server/server.hpp"

namespace scatter::server::test_server {

class ServerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ServerOptions o;
    o.port = 0;  // any free port
    o.max_upload_mb = 1;
    o.api.scenes_dir = test::source_path("scenes");
    server_ = std::make_unique<Server>(o);
    thread_ = std::thread([this] { server_->run(false); });
  }
  void TearDown() override {
    server_->stop();
    thread_.join();
    server_.reset();
  }
  std::unique_ptr<Server> server_;
  std::thread thread_;
};

namespace websocket = boost::beast::websocket;

// A scripted WebSocket client.
class WsClient {
 public:
  explicit WsClient(unsigned short port) : ws_(io_) {
    auto ep = boost::asio::ip::tcp::endpoint(boost::asio::ip::make_address("127.0.0.1"), port);
    boost::beast::get_lowest_layer(ws_).connect(ep);
    ws_.handshake("127.0.0.1", "/api/ws");
  }
  void send(const nlohmann::json& j) { ws_.write(boost::asio::buffer(j.dump())); }
  // The next message: JSON text, or binary (returned with binary = true).
  std::string next(bool& binary) {
    boost::beast::flat_buffer b;
    ws_.read(b);
    binary = ws_.got_binary();
    return boost::beast::buffers_to_string(b.data());
  }
  nlohmann::json next_json() {
    bool binary = true;
    std::string s = next(binary);
    EXPECT_FALSE(binary);
    return nlohmann::json::parse(s);
  }
  // Reads a frame header and its image; returns the header.
  nlohmann::json next_frame(std::string& image) {
    nlohmann::json h = next_json();
    if (h["type"] != "frame") return h;
    bool binary = false;
    image = next(binary);
    EXPECT_TRUE(binary);
    return h;
  }
  void close() { ws_.close(websocket::close_code::normal); }

 private:
  boost::asio::io_context io_;
  websocket::stream<boost::beast::tcp_stream> ws_;
};

inline nlohmann::json hello() {
  nlohmann::json scene = test::minimal_scene();
  return {{"type", "hello"}, {"scene", scene}, {"pipeline", "surface"}, {"format", "png"}};
}

inline nlohmann::json pose(int revision) {
  double a = revision * 0.01;
  return {{"type", "camera"},
          {"position", {4 * std::sin(a), 0.5, 4 * std::cos(a)}},
          {"target", {0, 0, 0}},
          {"revision", revision}};
}

}  // namespace scatter::server::test_server
