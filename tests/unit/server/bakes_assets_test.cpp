// Bake jobs and asset uploads over loopback HTTP against a real daemon.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <thread>

#include "../test_util.hpp"
#include "bake/cache.hpp"
#include "http_client.hpp"
#include "server/server.hpp"

namespace scatter::server {
namespace {

using namespace test_http;

// A bake job over REST: created (202), progress rises to 1 through the stages, asking again gives
// the same job (200); a second server on the same cache directory answers from disk; a running job
// can be cancelled, a finished one cannot (409); bad input is a 400 and unknown ids a 404.
TEST(ServerBakes, JobRunsToCompletionIsIdempotentAndCancels) {
  auto dir = test::scratch_dir("server_bakes");
  auto start = [&](std::thread& t) {
    ServerOptions o;
    o.port = 0;
    o.api.scenes_dir = test::source_path("scenes");
    o.cache = std::make_shared<BakeCache>(dir);
    auto s = std::make_unique<Server>(o);
    t = std::thread([p = s.get()] { p->run(false); });
    return s;
  };
  auto json = [](const auto& r) { return nlohmann::json::parse(r.body()); };
  const std::string body = R"({"scene_name": "sphere", "pipeline": "single",
                               "settings": {"samples": 2000, "directions": 32, "sh_order": 3}})";
  std::string id, key;
  {
    std::thread t;
    auto server = start(t);
    auto r = request(server->port(), http::verb::post, "/api/bakes", body);
    ASSERT_EQ(r.result_int(), 202) << r.body();
    id = json(r)["id"];
    EXPECT_EQ(r[http::field::location], "/api/bakes/" + id);
    std::set<std::string> stages;
    double last = 0;
    nlohmann::json status;
    for (int i = 0; i < 1200; ++i) {
      status = json(request(server->port(), http::verb::get, "/api/bakes/" + id));
      EXPECT_GE(status["progress"].get<double>(), last);  // never goes back
      last = status["progress"];
      stages.insert(status["stage"].get<std::string>());
      if (status["state"] == "done" || status["state"] == "failed") break;
      std::this_thread::sleep_for(std::chrono::milliseconds(25));
    }
    ASSERT_EQ(status["state"], "done") << status.dump();
    EXPECT_EQ(status["progress"], 1.0);
    EXPECT_FALSE(status["cache_hit"].get<bool>());
    EXPECT_TRUE(status["bake_timings_ms"].contains("sh"));
    EXPECT_GE(stages.size(), 3u);  // seen mid-way, not only queued and done
    key = status["key"];
    EXPECT_EQ(id, key);  // the job is named by the product it makes
    // The same asset and settings: the same job, already done.
    r = request(server->port(), http::verb::post, "/api/bakes", body);
    EXPECT_EQ(r.result_int(), 200);
    EXPECT_EQ(json(r)["id"], id);
    EXPECT_EQ(json(r)["state"], "done");
    // The same scene inline, with the camera moved: still the same bake, so the same job.
    auto moved = nlohmann::json::parse(body);
    moved.erase("scene_name");
    moved["scene"] = nlohmann::json::parse(std::ifstream(test::source_path("scenes/sphere.json")));
    moved["scene"]["camera"]["position"] = {1, 2, 4};
    r = request(server->port(), http::verb::post, "/api/bakes", moved.dump());
    EXPECT_EQ(r.result_int(), 200);
    EXPECT_EQ(json(r)["id"], id);
    // Other settings: another job.
    moved["settings"]["samples"] = 2100;
    r = request(server->port(), http::verb::post, "/api/bakes", moved.dump());
    EXPECT_EQ(r.result_int(), 202);
    EXPECT_NE(json(r)["id"], id);
    // Finished jobs cannot be cancelled; unknown ids and bad settings are clear errors.
    EXPECT_EQ(request(server->port(), http::verb::delete_, "/api/bakes/" + id).result_int(), 409);
    EXPECT_EQ(request(server->port(), http::verb::get, "/api/bakes/0000").result_int(), 404);
    r = request(server->port(), http::verb::post, "/api/bakes",
                R"({"scene_name": "sphere", "settings": {"samplez": 1}})");
    EXPECT_EQ(r.result_int(), 400);
    EXPECT_EQ(json(r)["field"], "settings.samplez");
    r = request(server->port(), http::verb::post, "/api/bakes",
                R"({"scene_name": "sphere", "pipeline": "thickness"})");
    EXPECT_EQ(r.result_int(), 400);
    EXPECT_EQ(json(r)["error"], "pipeline: pipeline thickness needs no bake");
    server->stop();
    t.join();
  }
  {
    std::thread t;
    auto server = start(t);  // a restarted daemon: no jobs in memory, the product on disk
    auto r = request(server->port(), http::verb::post, "/api/bakes", body);
    ASSERT_EQ(r.result_int(), 202);
    EXPECT_EQ(json(r)["id"], id);  // the same name for the same bake
    nlohmann::json status;
    for (int i = 0; i < 400; ++i) {
      status = json(request(server->port(), http::verb::get, "/api/bakes/" + id));
      if (status["state"] == "done") break;
      std::this_thread::sleep_for(std::chrono::milliseconds(25));
    }
    EXPECT_EQ(status["state"], "done");
    EXPECT_TRUE(status["cache_hit"].get<bool>());
    EXPECT_EQ(status["key"], key);
    // A big bake, cancelled while it runs.
    r = request(server->port(), http::verb::post, "/api/bakes",
                R"({"scene_name": "bunny", "settings": {"samples": 60000, "directions": 256}})");
    ASSERT_EQ(r.result_int(), 202);
    std::string big = json(r)["id"];
    for (int i = 0; i < 400 && json(request(server->port(), http::verb::get,
                                            "/api/bakes/" + big))["state"] != "running";
         ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    r = request(server->port(), http::verb::delete_, "/api/bakes/" + big);
    EXPECT_EQ(r.result_int(), 202);
    for (int i = 0; i < 2000; ++i) {
      status = json(request(server->port(), http::verb::get, "/api/bakes/" + big));
      if (status["state"] != "running") break;
      std::this_thread::sleep_for(std::chrono::milliseconds(25));
    }
    EXPECT_EQ(status["state"], "cancelled");
    EXPECT_LT(status["progress"].get<double>(), 1.0);
    auto metrics = request(server->port(), http::verb::get, "/metrics").body();
    EXPECT_NE(metrics.find("scatter_bakes{state=\"cancelled\"} 1"), std::string::npos);
    EXPECT_NE(metrics.find("scatter_bake_cache_lookups_total{result=\"disk_hit\"} 1"),
              std::string::npos)
        << metrics;
    server->stop();
    t.join();
  }
}

// Uploads: a watertight mesh and a density grid get content ids (201, then 200 for the same bytes),
// are listed, and render when a scene names them; bad uploads are 400s that leave nothing behind.
TEST(ServerAssets, UploadListAndRenderWithThem) {
  auto dir = test::scratch_dir("server_assets");
  ServerOptions o;
  o.port = 0;
  o.api.scenes_dir = test::source_path("scenes");
  o.api.assets_dir = dir / "assets";
  auto server = std::make_unique<Server>(o);
  std::thread t([p = server.get()] { p->run(false); });
  auto json = [](const auto& r) { return nlohmann::json::parse(r.body()); };
  const unsigned short port = server->port();
  // A unit cube, faces counter-clockwise seen from outside.
  std::string cube =
      "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n"
      "f 1 4 3\nf 1 3 2\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 4 8 7\nf 4 7 3\n"
      "f 1 5 8\nf 1 8 4\nf 2 3 7\nf 2 7 6\n";
  auto r = request(port, http::verb::post, "/api/assets?kind=mesh&format=obj", cube);
  ASSERT_EQ(r.result_int(), 201) << r.body();
  std::string mesh_id = json(r)["id"];
  EXPECT_EQ(mesh_id, sha256_hex(cube));
  EXPECT_EQ(json(r)["triangles"], 12);
  EXPECT_EQ(request(port, http::verb::post, "/api/assets?kind=mesh&format=obj", cube).result_int(),
            200);
  std::string values(8 * sizeof(float), '\0');
  for (int i = 0; i < 8; ++i) {
    float v = 0.5f + i;
    std::memcpy(&values[i * sizeof(float)], &v, sizeof v);
  }
  r = request(port, http::verb::post, "/api/assets?kind=grid&dims=2,2,2&bounds=-1,-1,-1,1,1,1",
              values);
  ASSERT_EQ(r.result_int(), 201) << r.body();
  std::string grid_id = json(r)["id"];
  auto list = json(request(port, http::verb::get, "/api/assets"))["assets"];
  EXPECT_EQ(list.size(), 2u);
  // Bad uploads: nothing is kept.
  auto files_before = std::distance(std::filesystem::directory_iterator(dir / "assets"), {});
  EXPECT_EQ(
      request(port, http::verb::post, "/api/assets?kind=mesh&format=obj", "v 0 0 0\nf 1 1 1\n")
          .result_int(),
      400);
  r = request(port, http::verb::post, "/api/assets?kind=mesh&format=obj",
              cube.substr(0, cube.rfind("f 2 7 6")));
  EXPECT_EQ(r.result_int(), 400);
  EXPECT_NE(json(r)["error"].get<std::string>().find("not watertight"), std::string::npos);
  EXPECT_EQ(request(port, http::verb::post, "/api/assets?kind=mesh&format=exe", cube).result_int(),
            400);
  EXPECT_EQ(request(port, http::verb::post,
                    "/api/assets?kind=grid&dims=2,2,3&bounds=-1,-1,-1,1,1,1", values)
                .result_int(),
            400);
  EXPECT_EQ(request(port, http::verb::post, "/api/assets?kind=grid&dims=2,2&bounds=-1,-1,-1,1,1,1",
                    values)
                .result_int(),
            400);
  // Bounds with an axis flipped or not finite are refused by name, before anything is written.
  for (const char* bounds : {"1,-1,-1,-1,1,1", "-1,-1,-1,1,1,nan", "-1,-1,-1,1,1,1e300"}) {
    r = request(port, http::verb::post,
                std::string("/api/assets?kind=grid&dims=2,2,2&bounds=") + bounds, values);
    EXPECT_EQ(r.result_int(), 400) << bounds;
    EXPECT_EQ(json(r)["field"], "bounds") << bounds;
  }
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir / "assets"), {}), files_before);
  // A scene made of the uploads renders.
  nlohmann::json scene = test::minimal_scene();
  scene["mesh"] = {{"asset", mesh_id}};
  scene["medium"]["density"] = {{"type", "grid"}, {"asset", grid_id}};
  r = request(
      port, http::verb::post, "/api/render",
      nlohmann::json(
          {{"scene", scene}, {"pipeline", "reference"}, {"terms", "single"}, {"format", "json"}})
          .dump());
  EXPECT_EQ(r.result_int(), 200) << r.body();
  scene["mesh"] = {{"asset", std::string(64, 'a')}};
  r = request(port, http::verb::post, "/api/render",
              nlohmann::json({{"scene", scene}, {"format", "json"}}).dump());
  EXPECT_EQ(r.result_int(), 400);
  EXPECT_EQ(json(r)["field"], "scene.mesh.asset");
  server->stop();
  t.join();
}

}  // namespace
}  // namespace scatter::server
