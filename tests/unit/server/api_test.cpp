#include "server/api.hpp"

#include <gtest/gtest.h>

#include "../test_util.hpp"
#include "gpu/embedded_sources.hpp"

namespace scatter::server {
namespace {

class ApiTest : public ::testing::Test {
 protected:
  ApiTest() : queue_(gpu::GpuOptions{}), api_(options(""), queue_, metrics_) {}
  static ApiOptions options(const std::string& token) {
    ApiOptions o;
    o.token = token;
    o.scenes_dir = test::source_path("scenes");
    o.max_image = 512;
    return o;
  }
  HttpResponse call(const std::string& method, const std::string& target,
                    const std::string& body = "") {
    return api_.handle({method, target, body, ""});
  }
  static nlohmann::json json(const HttpResponse& r) { return nlohmann::json::parse(r.body); }

  RenderQueue queue_;
  Metrics metrics_;
  Api api_;
};

TEST_F(ApiTest, HealthAndPipelines) {
  HttpResponse r = call("GET", "/api/health");
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(json(r)["status"], "ok");
  EXPECT_EQ(json(call("GET", "/api/pipelines"))["pipelines"].size(), pipeline_names().size());
}

// GET /api/pipelines is the registry: every pipeline's terms, settings table and presets.
TEST_F(ApiTest, PipelinesCarryTheirSettingsTables) {
  nlohmann::json list = json(call("GET", "/api/pipelines"))["pipelines"];
  ASSERT_EQ(list.size(), pipeline_names().size());
  for (size_t i = 0; i < list.size(); ++i) EXPECT_EQ(list[i]["name"], pipeline_names()[i]);
  auto find = [&](const std::string& name) {
    for (const auto& p : list)
      if (p["name"] == name) return p;
    return nlohmann::json();
  };
  nlohmann::json single = find("single");
  EXPECT_EQ(single["terms"], nlohmann::json::array({"single"}));
  EXPECT_TRUE(single["bakes"].get<bool>());
  EXPECT_EQ(single["bake_stages"].size(), 6u);
  bool samples = false;
  for (const auto& s : single["settings"])
    if (s["key"] == "samples") {
      samples = true;
      EXPECT_EQ(s["default"], 25000);
      EXPECT_EQ(s["kind"], "integer");
      EXPECT_EQ(s["shapes"], "bake");
      EXPECT_FALSE(s["doc"].get<std::string>().empty());
    }
  EXPECT_TRUE(samples);
  nlohmann::json lbl = find("lbl");
  EXPECT_EQ(lbl["default_terms"], "all");
  for (const auto& s : lbl["settings"]) {
    if (s["key"] == "directions") {
      EXPECT_EQ(s["allowed"], nlohmann::json::array({6, 18}));
    }
  }
  EXPECT_EQ(find("auto")["delegates"],
            nlohmann::json::array({"thickness", "single", "lbl", "psf", "reference"}));
  EXPECT_FALSE(find("psf")["bakes"].get<bool>());
}

// A setting is checked at the edge against the table, whatever pipeline auto would pick.
TEST_F(ApiTest, SettingsAreCheckedAtTheEdge) {
  HttpResponse r =
      call("POST", "/api/render",
           R"({"scene_name": "sphere", "pipeline": "single", "settings": {"sampels": 10}})");
  EXPECT_EQ(r.status, 400);
  EXPECT_EQ(json(r)["field"], "settings.sampels");
  r = call("POST", "/api/render",
           R"({"scene_name": "sphere", "pipeline": "auto", "settings": {"spp": 2}})");
  EXPECT_EQ(
      r.status,
      400);  // below reference's range, though auto picks thickness for the sphere's single term
  EXPECT_EQ(json(r)["field"], "settings.spp");
  // A value far out of range is told the pipeline's own limits, exactly.
  r = call("POST", "/api/render",
           R"({"scene_name": "sphere", "pipeline": "reference", "settings": {"spp": 1e12}})");
  EXPECT_EQ(r.status, 400);
  EXPECT_EQ(json(r)["error"],
            "settings.spp: must be in [3, 1048576] for pipeline reference, got 1e+12");
  r = call("POST", "/api/bakes", R"({"scene_name": "sphere", "pipeline": "psf"})");
  EXPECT_EQ(r.status, 400);
  EXPECT_NE(json(r)["error"].get<std::string>().find("needs no bake"), std::string::npos);
}

// quality.max_error: auto plans by it; a budget only a render past --max-render-s could meet is
// refused naming it; pipelines that render at their own settings refuse it.
TEST_F(ApiTest, ABudgetIsPlannedForOrRefusedByName) {
  HttpResponse r = call("POST", "/api/render",
                        R"({"scene_name": "sphere", "pipeline": "surface",
                            "quality": {"max_error": 0.05}})");
  EXPECT_EQ(r.status, 400);
  EXPECT_EQ(json(r)["field"], "quality.max_error");
  r = call("POST", "/api/render",
           R"({"scene_name": "sphere", "pipeline": "auto", "quality": {"max_error": 0}})");
  EXPECT_EQ(r.status, 400);
  EXPECT_EQ(json(r)["field"], "quality.max_error");
  r = call("POST", "/api/render",
           R"({"scene_name": "bunny", "pipeline": "auto", "terms": "all",
               "quality": {"max_error": 0.0001}})");
  EXPECT_EQ(r.status, 413) << r.body;
  EXPECT_EQ(json(r)["field"], "quality.max_error") << r.body;
  r = call("POST", "/api/render",
           R"({"scene_name": "sphere", "pipeline": "auto", "terms": "single", "format": "json",
               "quality": {"max_error": 0.2}})");
  ASSERT_EQ(r.status, 200) << r.body;
  nlohmann::json plan = json(r)["plan"];
  EXPECT_LE(plan["expected_error"].get<double>(), 0.2);
  EXPECT_GT(plan["expected_seconds"].get<double>(), 0);
  EXPECT_FALSE(plan["alternatives"].empty());
  EXPECT_EQ(plan["stages"][0]["stage"], "choose");
  EXPECT_NE(plan["stages"][0]["reason"].get<std::string>().find("budget 20 %"), std::string::npos);
}

TEST_F(ApiTest, UnknownRoutesMethodsAndBodiesAreClearErrors) {
  HttpResponse r = call("GET", "/api/nothing");
  EXPECT_EQ(r.status, 404);
  EXPECT_EQ(json(r)["error"], "no such resource: /api/nothing");
  EXPECT_EQ(call("POST", "/api/health").status, 405);
  r = call("POST", "/api/render", "{not json");
  EXPECT_EQ(r.status, 400);
  EXPECT_EQ(json(r)["field"], "body");
  r = call("POST", "/api/render", R"({"scene_name": "sphere", "pipeline": "magic"})");
  EXPECT_EQ(r.status, 400);
  EXPECT_EQ(json(r)["field"], "pipeline");
  r = call("POST", "/api/render", R"({"scene_name": "../etc/passwd"})");
  EXPECT_EQ(r.status, 400);
  EXPECT_EQ(json(r)["field"], "scene_name");
  r = call("POST", "/api/render",
           R"({"scene": {"mesh": {"file": "/etc/passwd"}, "medium": {}, "lights": []}})");
  EXPECT_EQ(r.status, 400);
  EXPECT_EQ(json(r)["field"], "scene.mesh.file");
  r = call("POST", "/api/render", R"({"scene_name": "sphere", "colour": 1})");
  EXPECT_EQ(r.status, 400);
  EXPECT_EQ(json(r)["field"], "colour");
  nlohmann::json big = {{"scene", test::minimal_scene()}};
  big["scene"]["image"] = {{"width", 4096}, {"height", 64}};
  r = call("POST", "/api/render", big.dump());
  EXPECT_EQ(r.status, 400);
  EXPECT_EQ(json(r)["field"], "scene.image.width");
}

// A shipped scene whose mesh file is missing is the server's problem: 503 naming the scene and
// the file, for a render and a bake alike; the scene works again once the file is there.
TEST_F(ApiTest, AShippedSceneWithAMissingMeshIs503NamingSceneAndFile) {
  auto dir = test::scratch_dir("api_missing_mesh");
  nlohmann::json scene = test::minimal_scene();
  scene["mesh"] = {{"file", "gone.obj"}};
  test::write_file(dir / "lost.json", scene.dump());
  ApiOptions o = options("");
  o.scenes_dir = dir;
  Api api(o, queue_, metrics_);
  for (const char* route : {"/api/render", "/api/bakes"}) {
    HttpResponse r = api.handle(
        {"POST", route, R"({"scene_name": "lost", "pipeline": "single", "format": "json"})", ""});
    EXPECT_EQ(r.status, 503) << route << " " << r.body;
    EXPECT_EQ(json(r)["field"], "scene_name");
    std::string error = json(r)["error"];
    EXPECT_NE(error.find("\"lost\""), std::string::npos) << error;
    EXPECT_NE(error.find("\"gone.obj\""), std::string::npos) << error;
    EXPECT_EQ(error.find(dir.string()), std::string::npos) << error;  // no server paths
  }
  test::write_file(dir / "gone.obj",
                   "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
  EXPECT_TRUE(SceneLibrary::missing_files(dir / "lost.json").empty());
  HttpResponse r =
      api.handle({"POST", "/api/render",
                  R"({"scene_name": "lost", "pipeline": "surface", "format": "json"})", ""});
  EXPECT_EQ(r.status, 200) << r.body;
}

// An assets folder the server cannot make is its own problem: 503, naming no server path.
TEST_F(ApiTest, UploadsTheServerCannotStoreAre503) {
  auto dir = test::scratch_dir("api_unwritable_assets");
  test::write_file(dir / "blocked", "a file where the folder should go");
  ApiOptions o = options("");
  o.assets_dir = dir / "blocked" / "assets";
  Api api(o, queue_, metrics_);
  HttpResponse r = api.handle({"POST", "/api/assets?kind=mesh&format=obj", "v 0 0 0\n", ""});
  EXPECT_EQ(r.status, 503) << r.body;
  EXPECT_EQ(json(r)["field"], "body");
  EXPECT_NE(json(r)["error"].get<std::string>().find("cannot store"), std::string::npos) << r.body;
  EXPECT_EQ(r.body.find(dir.string()), std::string::npos) << r.body;
}

TEST_F(ApiTest, ServesTheWebClient) {
  HttpResponse r = call("GET", "/");
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(r.content_type, "text/html; charset=utf-8");
  EXPECT_NE(r.body.find("<canvas id=\"view\""), std::string::npos);
  EXPECT_NE(call("GET", "/app.js").body.find("/api/ws"), std::string::npos);
  // Every web/ file by its name, typed by its extension; nothing else, whatever the path says.
  for (const auto& [name, text] : gpu::embedded_sources()) {
    if (name.rfind("web/", 0) != 0) continue;
    r = call("GET", name.substr(3));  // "web/app.js" -> "/app.js"
    EXPECT_EQ(r.status, 200) << name;
    EXPECT_EQ(r.body, std::string(text)) << name;
  }
  EXPECT_EQ(call("GET", "/style.css").content_type, "text/css; charset=utf-8");
  for (const char* bad : {"/web/app.js", "/../CMakeLists.txt", "/%2e%2e/CMakeLists.txt",
                          "/kernels/common/rng.cl", "/.app.js", "//app.js", "/app.js/",
                          "/nothing.js", "/index", "/a/../app.js", "/app.js%00"}) {
    EXPECT_EQ(call("GET", bad).status, 404) << bad;
  }
  EXPECT_EQ(call("POST", "/app.js").status, 404);
}

TEST_F(ApiTest, TokenIsRequiredWhenSet) {
  Api guarded(options("s3cret"), queue_, metrics_);
  EXPECT_EQ(guarded.handle({"GET", "/api/health", "", ""}).status, 401);
  EXPECT_EQ(guarded.handle({"GET", "/api/health", "", "Bearer wrong"}).status, 401);
  EXPECT_EQ(guarded.handle({"GET", "/api/health", "", "Bearer s3cret"}).status, 200);
}

TEST_F(ApiTest, RendersImagesWithPlanAndTimings) {
  nlohmann::json req = {
      {"scene", test::minimal_scene()}, {"pipeline", "surface"}, {"format", "png"}};
  HttpResponse r = call("POST", "/api/render", req.dump());
  ASSERT_EQ(r.status, 200) << r.body;
  EXPECT_EQ(r.content_type, "image/png");
  EXPECT_EQ(r.body.substr(1, 3), "PNG");
  bool has_plan = false;
  for (const auto& [k, v] : r.headers)
    if (k == "X-Scatter-Plan") has_plan = nlohmann::json::parse(v)["pipeline"] == "surface";
  EXPECT_TRUE(has_plan);

  req = {{"scene_name", "sphere"}, {"pipeline", "auto"}, {"terms", "single"}, {"format", "json"}};
  r = call("POST", "/api/render", req.dump());
  ASSERT_EQ(r.status, 200) << r.body;
  EXPECT_EQ(json(r)["pipeline"].get<std::string>().rfind("auto -> ", 0), 0u) << r.body;
  EXPECT_LE(json(r)["plan"]["expected_error"].get<double>(), 0.1);  // the default budget
  EXPECT_FALSE(json(r)["timings_ms"].empty());

  std::string metrics = call("GET", "/metrics").body;
  EXPECT_NE(metrics.find("scatter_frame_seconds_count{pipeline=\"auto\"} 1"), std::string::npos)
      << metrics;
  EXPECT_NE(metrics.find("scatter_http_requests_total{route=\"/api/render\",status=\"200\"} 2"),
            std::string::npos);
}

}  // namespace
}  // namespace scatter::server
