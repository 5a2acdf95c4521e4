#include "server/server.hpp"

#include <gtest/gtest.h>

#include <boost/beast.hpp>
#include <thread>

#include "../test_util.hpp"

namespace scatter::server {
namespace {

namespace beast = boost::beast;
namespace http = beast::http;

// A real HTTP client on loopback.
http::response<http::string_body> request(unsigned short port, http::verb verb, const std::string& target,
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

TEST_F(ServerTest, ServesHealthAndRendersOverHttp) {
  auto r = request(server_->port(), http::verb::get, "/api/health");
  EXPECT_EQ(r.result_int(), 200);
  EXPECT_EQ(nlohmann::json::parse(r.body())["status"], "ok");
  nlohmann::json req = {{"scene", test::minimal_scene()}, {"pipeline", "surface"}, {"format", "exr"}};
  r = request(server_->port(), http::verb::post, "/api/render", req.dump());
  ASSERT_EQ(r.result_int(), 200) << r.body();
  EXPECT_EQ(r[http::field::content_type], "image/x-exr");
  auto file = test::write_file(test::scratch_dir("server_exr") / "frame.exr", r.body());
  Image image = read_image(file);  // a real EXR of the requested size
  EXPECT_EQ(image.width, 64);
  EXPECT_EQ(image.height, 64);
  EXPECT_NE(r["X-Scatter-Timings"].find("raster"), std::string::npos);
}

TEST_F(ServerTest, OversizedBodiesGet413AndTheServerGoesOn) {
  std::string huge(2 << 20, 'x');
  auto r = request(server_->port(), http::verb::post, "/api/render", huge);
  EXPECT_EQ(r.result_int(), 413);
  EXPECT_NE(r.body().find("larger than the server's limit"), std::string::npos);
  EXPECT_EQ(request(server_->port(), http::verb::get, "/api/health").result_int(), 200);
}

TEST_F(ServerTest, ConcurrentClientsAllGetAnswers) {
  std::vector<std::thread> clients;
  std::atomic<int> ok{0};
  for (int i = 0; i < 8; ++i)
    clients.emplace_back([&, i] {
      auto r = i % 2 ? request(server_->port(), http::verb::get, "/api/health")
                     : request(server_->port(), http::verb::post, "/api/render",
                               nlohmann::json{{"scene", test::minimal_scene()}, {"pipeline", "surface"},
                                              {"format", "json"}}.dump());
      ok += r.result_int() == 200;
    });
  for (auto& c : clients) c.join();
  EXPECT_EQ(ok, 8);
}

}  // namespace
}  // namespace scatter::server
