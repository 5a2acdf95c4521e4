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
#include "server_fixture.hpp"

namespace scatter::server {
namespace {

using namespace test_http;
using namespace test_server;

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

}  // namespace
}  // namespace scatter::server
