// The daemon's live sessions over WebSocket, continued from server_test.cpp: snapshots, a hello's
// medium, the session limit, vanishing clients and a still view's refinement.
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
