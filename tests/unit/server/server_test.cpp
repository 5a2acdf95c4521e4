#include "server/server.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <boost/beast.hpp>
#include <chrono>
#include <iostream>
#include <thread>

#include "../pipelines/jpeg_quality.hpp"
#include "../test_util.hpp"
#include "http_client.hpp"

namespace scatter::server {
namespace {

using namespace test_http;

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
  nlohmann::json req = {
      {"scene", test::minimal_scene()}, {"pipeline", "surface"}, {"format", "exr"}};
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
                               nlohmann::json{{"scene", test::minimal_scene()},
                                              {"pipeline", "surface"},
                                              {"format", "json"}}
                                   .dump());
      ok += r.result_int() == 200;
    });
  for (auto& c : clients) c.join();
  EXPECT_EQ(ok, 8);
}

}  // namespace
}  // namespace scatter::server

namespace scatter::server {
namespace {

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

nlohmann::json hello() {
  nlohmann::json scene = test::minimal_scene();
  return {{"type", "hello"}, {"scene", scene}, {"pipeline", "surface"}, {"format", "png"}};
}

nlohmann::json pose(int revision) {
  double a = revision * 0.01;
  return {{"type", "camera"},
          {"position", {4 * std::sin(a), 0.5, 4 * std::cos(a)}},
          {"target", {0, 0, 0}},
          {"revision", revision}};
}

TEST_F(ServerTest, WebSocketStreamsFramesAndTheLatestPoseWins) {
  WsClient c(server_->port());
  c.send(hello());
  std::string image;
  nlohmann::json h = c.next_frame(image);
  ASSERT_EQ(h["type"], "frame") << h.dump();
  EXPECT_EQ(h["width"], 64);
  EXPECT_EQ(image.substr(1, 3), "PNG");
  // A burst of 100 poses while the first frame is still unacknowledged: only the newest counts.
  for (int r = 1; r <= 100; ++r) c.send(pose(r));
  c.send({{"type", "ack"}, {"frame", h["frame"]}});
  int frames = 0;
  long long last = 0;
  while (last < 100 && frames < 100) {
    h = c.next_frame(image);
    ASSERT_EQ(h["type"], "frame") << h.dump();
    last = h["camera_revision"];
    ++frames;
    c.send({{"type", "ack"}, {"frame", h["frame"]}});
  }
  EXPECT_EQ(last, 100);
  EXPECT_LE(frames, 3);           // far fewer frames than poses
  EXPECT_EQ(h["reduced"], true);  // cheaper frames while the camera moves
  EXPECT_EQ(h["width"], 32);
  // The view stays still: one full-size frame refines it.
  h = c.next_frame(image);
  ASSERT_EQ(h["type"], "frame") << h.dump();
  EXPECT_EQ(h["reduced"], false);
  EXPECT_EQ(h["width"], 64);
  EXPECT_EQ(h["camera_revision"], 100);
  c.close();
}

TEST_F(ServerTest, WebSocketBadMessagesGetErrorsAndTheConnectionStays) {
  WsClient c(server_->port());
  c.send(nlohmann::json{{"type", "camera"}, {"position", {0, 0, 1}}});
  nlohmann::json e = c.next_json();
  EXPECT_EQ(e["type"], "error");
  EXPECT_EQ(e["error"], "type: send hello first");
  c.send(nlohmann::json{{"type", "dance"}});
  EXPECT_EQ(c.next_json()["field"], "type");
  nlohmann::json bad = hello();
  bad["scene"]["voxels"] = 4096;
  c.send(bad);
  EXPECT_EQ(c.next_json()["field"], "scene.voxels");
  c.send(hello());  // still usable
  std::string image;
  EXPECT_EQ(c.next_frame(image)["type"], "frame");
  c.close();
}

// A hello with a request id: the scene message describes what the session shows, frames carry
// the id, keep_view keeps the pose a later hello would otherwise reset, and cancel is answered.
TEST_F(ServerTest, WebSocketHelloRequestKeepViewAndCancel) {
  WsClient c(server_->port());
  nlohmann::json h = hello();
  h["request"] = 7;
  c.send(h);
  nlohmann::json scene = c.next_json();
  ASSERT_EQ(scene["type"], "scene") << scene.dump();
  EXPECT_EQ(scene["request"], 7);
  EXPECT_EQ(scene["kept_view"], false);
  EXPECT_EQ(scene["source"], h["scene"]);
  EXPECT_EQ(scene["lights"].size(), 1u);
  EXPECT_EQ(scene["lights"][0]["type"], "directional");
  EXPECT_NEAR(scene["bounds"]["max"][0].get<double>(), 1.0, 0.01);
  EXPECT_NEAR(scene["camera"]["position"][2].get<double>(), 4.0, 1e-9);
  EXPECT_TRUE(std::find(scene["scenes"].begin(), scene["scenes"].end(), "cube-torus") !=
              scene["scenes"].end())
      << scene["scenes"].dump();
  std::string image;
  nlohmann::json f = c.next_frame(image);
  ASSERT_EQ(f["type"], "frame") << f.dump();
  EXPECT_EQ(f["request"], 7);
  c.send({{"type", "ack"}, {"frame", f["frame"]}});
  c.send(pose(50));
  // The same view by another request, keeping the pose: the scene message says the pose sent.
  h["request"] = 8;
  h["keep_view"] = true;
  c.send(h);
  // The next message that is not a frame; frames meanwhile (their request noted) are acked.
  std::vector<long long> requests;
  auto next_other = [&] {
    for (;;) {
      nlohmann::json m = c.next_frame(image);
      if (m["type"] != "frame") return m;
      requests.push_back(m["request"]);
      c.send({{"type", "ack"}, {"frame", m["frame"]}});
    }
  };
  nlohmann::json m = next_other();
  ASSERT_EQ(m["type"], "scene") << m.dump();
  EXPECT_EQ(m["request"], 8);
  EXPECT_EQ(m["kept_view"], true);
  EXPECT_NEAR(m["camera"]["position"][0].get<double>(), pose(50)["position"][0].get<double>(),
              1e-9);
  requests.clear();
  c.send({{"type", "cancel"}});
  m = next_other();
  EXPECT_EQ(m["type"], "cancelled") << m.dump();
  EXPECT_EQ(m["request"], 8);
  for (long long r : requests) EXPECT_EQ(r, 8);
  c.close();
}

// JPEG frames while the camera moves are encoded at the lower quality, the still frame after them
// at the higher; each header says which, and the bytes agree.
TEST_F(ServerTest, WebSocketJpegQualityIsLowerWhileMoving) {
  WsClient c(server_->port());
  nlohmann::json h = hello();
  h["format"] = "jpg";
  c.send(h);
  std::string image;
  nlohmann::json f = c.next_frame(image);
  ASSERT_EQ(f["type"], "frame") << f.dump();
  EXPECT_EQ(f["reduced"], false);
  EXPECT_EQ(f["jpeg_quality"], kJpegQuality);
  EXPECT_EQ(test::jpeg_quality(image), kJpegQuality);
  c.send(pose(1));
  c.send({{"type", "ack"}, {"frame", f["frame"]}});
  f = c.next_frame(image);
  ASSERT_EQ(f["type"], "frame") << f.dump();
  EXPECT_EQ(f["reduced"], true);
  EXPECT_EQ(f["jpeg_quality"], kMovingJpegQuality);
  EXPECT_EQ(test::jpeg_quality(image), kMovingJpegQuality);
  c.send({{"type", "ack"}, {"frame", f["frame"]}});
  f = c.next_frame(image);  // still again: the full frame
  ASSERT_EQ(f["type"], "frame") << f.dump();
  EXPECT_EQ(f["reduced"], false);
  EXPECT_EQ(test::jpeg_quality(image), kJpegQuality);
  c.close();
}

// A hello's composite names a pipeline that renders the multiple term, for frames of the single
// (or surface) term; anything else is an error naming the field, and the session goes on.
TEST_F(ServerTest, WebSocketCompositeIsCheckedByField) {
  WsClient c(server_->port());
  auto error_for = [&](nlohmann::json composite, const std::string& terms) {
    nlohmann::json h = hello();
    h["pipeline"] = "thickness";
    h["terms"] = terms;
    h["composite"] = composite;
    c.send(h);
    return c.next_json();
  };
  nlohmann::json e = error_for({{"pipeline", "surface"}}, "single");
  EXPECT_EQ(e["type"], "error") << e.dump();
  EXPECT_EQ(e["field"], "composite.pipeline");
  EXPECT_NE(e["error"].get<std::string>().find("multiple"), std::string::npos) << e.dump();
  EXPECT_EQ(error_for({{"pipeline", "nope"}}, "single")["field"], "composite.pipeline");
  EXPECT_EQ(error_for({{"pipeline", "psf"}, {"scale", 2}}, "single")["field"], "composite.scale");
  EXPECT_EQ(error_for({{"pipeline", "psf"}, {"settings", {{"step", -1}}}}, "single")["field"],
            "composite.settings.step");
  EXPECT_EQ(error_for({{"pipeline", "psf"}, {"colour", 1}}, "single")["field"], "composite.colour");
  nlohmann::json h = hello();  // surface renders only the surface term: "all" is refused anyway
  h["composite"] = {{"pipeline", "psf"}};
  c.send(h);
  std::string image;
  nlohmann::json f = c.next_frame(image);
  EXPECT_EQ(f["type"], "frame") << f.dump();  // surface frames may take one
  c.close();
}

// A snapshot: the current view's next full-size frame comes as linear EXR.
TEST_F(ServerTest, WebSocketSnapshotIsAnExrFrame) {
  WsClient c(server_->port());
  c.send(hello());
  std::string image;
  nlohmann::json f = c.next_frame(image);
  ASSERT_EQ(f["type"], "frame") << f.dump();
  EXPECT_EQ(f["format"], "png");
  c.send({{"type", "snapshot"}});
  c.send({{"type", "ack"}, {"frame", f["frame"]}});
  for (int i = 0; i < 5; ++i) {  // refinement frames may come first; the snapshot follows
    f = c.next_frame(image);
    ASSERT_EQ(f["type"], "frame") << f.dump();
    c.send({{"type", "ack"}, {"frame", f["frame"]}});
    if (f["format"] == "exr") break;
  }
  EXPECT_EQ(f["format"], "exr");
  EXPECT_EQ(f["width"], 64);
  EXPECT_EQ(image.substr(0, 4), std::string("\x76\x2f\x31\x01", 4));
  c.close();
}

// A hello's "medium" renders a shipped scene in another medium; a bad one names its field.
TEST_F(ServerTest, WebSocketHelloMediumOverridesAShippedScene) {
  WsClient c(server_->port());
  nlohmann::json h = {{"type", "hello"},
                      {"scene_name", "sphere"},
                      {"pipeline", "surface"},
                      {"request", 1},
                      {"medium", {{"sigma_s", {5, 1, 1}}, {"g", 5}}}};
  c.send(h);
  nlohmann::json e = c.next_json();
  EXPECT_EQ(e["type"], "error");
  EXPECT_EQ(e["field"], "medium.g") << e.dump();
  EXPECT_EQ(e["request"], 1);
  h["medium"]["g"] = 0.5;
  h["request"] = 2;
  c.send(h);
  nlohmann::json scene = c.next_json();
  ASSERT_EQ(scene["type"], "scene") << scene.dump();
  EXPECT_EQ(scene["source"]["medium"]["sigma_s"][0], 5);
  EXPECT_EQ(scene["source"]["mesh"]["shape"], "sphere");
  std::string image;
  EXPECT_EQ(c.next_frame(image)["request"], 2);
  c.close();
}

TEST_F(ServerTest, SessionsBeyondTheLimitAreRefusedUntilOneEnds) {
  TearDown();  // restart with a limit of two sessions
  ServerOptions o;
  o.port = 0;
  o.api.scenes_dir = test::source_path("scenes");
  o.api.max_sessions = 2;
  server_ = std::make_unique<Server>(o);
  thread_ = std::thread([this] { server_->run(false); });
  auto a = std::make_unique<WsClient>(server_->port());
  WsClient b(server_->port());
  EXPECT_THROW(WsClient(server_->port()), boost::system::system_error);  // 503 on the upgrade
  a->close();
  a.reset();
  bool admitted = false;
  for (int i = 0; i < 50 && !admitted; ++i) {  // the slot comes back once the session is gone
    try {
      WsClient c(server_->port());
      admitted = true;
      c.close();
    } catch (const boost::system::system_error&) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }
  EXPECT_TRUE(admitted);
  b.close();
}

TEST_F(ServerTest, AClientVanishingMidFrameCostsNothing) {
  {
    WsClient c(server_->port());
    c.send(hello());
  }  // gone before its frame is sent
  WsClient d(server_->port());
  d.send(hello());
  std::string image;
  EXPECT_EQ(d.next_frame(image)["type"], "frame");
  d.close();
  EXPECT_EQ(request(server_->port(), http::verb::get, "/api/health").result_int(), 200);
}

// A still view refines itself: the full frame, thickness's "high", then reference passes of the
// single term whose accumulated error_estimate falls, each sent frame a tenth under the one before,
// until the floor (or the pass limit); a pose then cancels the refinement and renders reduced.
TEST_F(ServerTest, AStillViewConvergesWithItsErrorEstimate) {
  TearDown();
  ServerOptions o;
  o.port = 0;
  o.api.scenes_dir = test::source_path("scenes");
  o.api.refine_pass_s = 0.1;
  o.api.refine_max_passes = 60;
  server_ = std::make_unique<Server>(o);
  thread_ = std::thread([this] { server_->run(false); });
  WsClient c(server_->port());
  nlohmann::json h = hello();
  h["pipeline"] = "thickness";
  h["quality"] = {{"refine_floor", 0.07}};
  c.send(h);
  std::vector<nlohmann::json> headers;
  std::string image;
  int notes = 0;  // steps not sent: each told by a "refine" message
  auto start = std::chrono::steady_clock::now();
  for (;;) {
    nlohmann::json f = c.next_frame(image);
    if (f["type"] == "refine") {
      ASSERT_EQ(f["refine"]["stage"], "reference") << f.dump();
      double shown = f.value("shown_error_estimate", 0.1);  // none: an assumed 10 %
      EXPECT_GT(f["error_estimate"].get<double>(), 0.9 * shown) << f.dump();
      ++notes;
      if (f["refine"]["state"] == "converging") continue;
      headers.push_back(f);  // ended without a frame
      break;
    }
    ASSERT_EQ(f["type"], "frame") << f.dump();
    ASSERT_TRUE(f.contains("refine")) << f.dump();
    EXPECT_EQ(f["reduced"], false);
    EXPECT_EQ(f["width"], 64);
    headers.push_back(f);
    c.send({{"type", "ack"}, {"frame", f["frame"]}});
    if (f["refine"]["state"] != "converging") break;
    ASSERT_LT(headers.size(), 65u);
  }
  double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_GE(headers.size(), 4u);
  EXPECT_EQ(headers[0]["refine"]["stage"], "full");
  EXPECT_EQ(headers[1]["refine"]["stage"], "quality");
  EXPECT_EQ(headers[1]["refine"]["quality"], "high");
  std::vector<double> errors;
  std::string line;
  for (size_t i = 2; i < headers.size(); ++i) {
    const nlohmann::json& r = headers[i]["refine"];
    if (headers[i]["type"] == "frame") {
      EXPECT_EQ(r["stage"], "reference");
      EXPECT_EQ(headers[i]["pipeline"], "reference");
      line += " pass " + r["pass"].dump() + " " + r["spp"].dump() + " spp " +
              headers[i]["error_estimate"].dump() + ";";
    }
    if (headers[i]["type"] == "frame") errors.push_back(headers[i]["error_estimate"]);
  }
  std::cout << "refinement: " << seconds << " s, " << notes << " passes not sent;" << line << "\n";
  EXPECT_GT(notes, 0);
  ASSERT_GE(errors.size(), 2u);
  EXPECT_LE(errors[0],
            0.09);  // over thickness's frames (no estimate): an assumed 10 %, less a tenth
  for (size_t i = 1; i + 1 < errors.size(); ++i) EXPECT_LE(errors[i], 0.9 * errors[i - 1]);
  EXPECT_LT(errors.back(), errors[errors.size() - 2]);
  const nlohmann::json& last = headers.back()["refine"];
  if (last["state"] == "converged")
    EXPECT_LE(errors.back(), 0.07);
  else
    EXPECT_EQ(headers.back()["refine"]["pass"], 60);  // the passes ran out
  // The next frame, past the notes of steps not sent.
  auto next_frame = [&] {
    nlohmann::json f = c.next_frame(image);
    while (f["type"] == "refine") f = c.next_frame(image);
    return f;
  };
  // A pose while nothing is in flight: the next frame is the reduced pose; once still, the
  // refinement starts over with the full frame.
  c.send(pose(1));
  nlohmann::json f = next_frame();
  ASSERT_EQ(f["type"], "frame") << f.dump();
  EXPECT_EQ(f["reduced"], true);
  EXPECT_EQ(f["camera_revision"], 1);
  c.send({{"type", "ack"}, {"frame", f["frame"]}});
  f = next_frame();
  EXPECT_EQ(f["refine"]["stage"], "full");
  EXPECT_EQ(f["camera_revision"], 1);
  // A pose while a reference pass renders (high is sent first; the first passes are not sent):
  // the pass is cancelled, and the pose's reduced frame comes next.
  c.send({{"type", "ack"}, {"frame", f["frame"]}});
  f = next_frame();
  ASSERT_EQ(f["refine"]["stage"], "quality") << f.dump();
  c.send({{"type", "ack"}, {"frame", f["frame"]}});
  std::this_thread::sleep_for(std::chrono::milliseconds(30));
  c.send(pose(2));
  f = next_frame();
  ASSERT_EQ(f["type"], "frame") << f.dump();
  EXPECT_EQ(f["camera_revision"], 2);
  EXPECT_FALSE(f.contains("refine"));
  EXPECT_EQ(f["reduced"], true);
  std::string metrics = request(server_->port(), http::verb::get, "/metrics").body();
  EXPECT_EQ(metrics.find("\nscatter_renders_cancelled_total 0\n"), std::string::npos);
  c.close();
}

}  // namespace
}  // namespace scatter::server
