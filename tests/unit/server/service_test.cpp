// The daemon under the load its users bring: a long render in flight, clients that leave, bad
// and costly requests, silent sessions, shutdown. Everything on loopback.
#include <gtest/gtest.h>

#include <algorithm>
#include <boost/beast.hpp>
#include <boost/beast/websocket.hpp>
#include <chrono>
#include <future>
#include <regex>
#include <thread>

#include "../test_util.hpp"
#include "http_client.hpp"
#include "server/server.hpp"

namespace scatter::server {
namespace {

using namespace test_http;
using Clock = std::chrono::steady_clock;
namespace websocket = boost::beast::websocket;

double ms_since(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

// A render that runs for many seconds on this CPU but stops at its next pass when cancelled.
nlohmann::json long_render() {
  return {{"scene", test::minimal_scene()},
          {"pipeline", "reference"},
          {"terms", "all"},
          {"format", "json"},
          {"settings", {{"spp", 100000}}}};
}

class ServiceTest : public ::testing::Test {
 protected:
  void start(ServerOptions o) {
    o.port = 0;
    o.api.scenes_dir = test::source_path("scenes");
    server_ = std::make_unique<Server>(o);
    thread_ = std::thread([this] { server_->run(false); });
  }
  void SetUp() override {
    ServerOptions o;
    o.api.max_render_s = 1e5;  // the long render is estimated at minutes
    start(o);
  }
  void TearDown() override {
    if (!server_) return;
    server_->stop();
    thread_.join();
    server_.reset();
  }
  unsigned short port() const { return server_->port(); }
  http::response<http::string_body> post(const std::string& target, const nlohmann::json& body) {
    return request(port(), http::verb::post, target, body.dump());
  }
  // Waits until the render thread has a job running (GET /api/health's "busy").
  void wait_busy() {
    for (int i = 0; i < 500; ++i) {
      if (nlohmann::json::parse(
              request(port(), http::verb::get, "/api/health").body())["render_busy"] == true)
        return;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    FAIL() << "the render thread never started the long render";
  }
  double metric(const std::string& name) {
    std::string text = request(port(), http::verb::get, "/metrics").body();
    auto at = text.find("\n" + name + " ");
    return at == std::string::npos ? -1 : std::stod(text.substr(at + name.size() + 2));
  }

  std::unique_ptr<Server> server_;
  std::thread thread_;
};

// A client whose long render is in flight; it leaves on destruction without reading the answer.
struct Leaver {
  boost::asio::io_context io;
  beast::tcp_stream stream{io};
  explicit Leaver(unsigned short port, const std::string& body) {
    stream.connect({boost::asio::ip::make_address("127.0.0.1"), port});
    http::request<http::string_body> req{http::verb::post, "/api/render", 11};
    req.set(http::field::host, "127.0.0.1");
    req.body() = body;
    req.prepare_payload();
    http::write(stream, req);
  }
};

TEST_F(ServiceTest, QuickRoutesAndValidationErrorsAnswerAtOnceWhileARenderRuns) {
  auto render = std::async(std::launch::async, [&] { return post("/api/render", long_render()); });
  wait_busy();
  std::vector<double> ms;
  for (int i = 0; i < 100; ++i) {
    const char* target = i % 4 == 0   ? "/api/health"
                         : i % 4 == 1 ? "/metrics"
                         : i % 4 == 2 ? "/api/bakes"
                                      : "/api/assets";
    auto t = Clock::now();
    EXPECT_EQ(request(port(), http::verb::get, target).result_int(), 200) << target;
    ms.push_back(ms_since(t));
  }
  std::sort(ms.begin(), ms.end());
  // The issue's bound, with the render thread busy: 99 of 100 answered within 10 ms.
  EXPECT_LE(ms[98], 10.0) << "p50 " << ms[50] << " ms, max " << ms.back() << " ms";
  // A validation error does not wait behind the render either.
  auto t = Clock::now();
  auto bad = post("/api/render", {{"scene_name", "sphere"}, {"pipeline", "magic"}});
  EXPECT_EQ(bad.result_int(), 400);
  EXPECT_LT(ms_since(t), 1000);
  server_->stop();  // cancels the render in flight
  EXPECT_EQ(render.get().result_int(), 503);
  thread_.join();
  server_.reset();
}

TEST_F(ServiceTest, AClientThatLeavesCancelsItsRender) {
  {
    Leaver gone(port(), long_render().dump());
    wait_busy();
  }  // hangs up mid-render
  auto t = Clock::now();
  // The render thread is free again soon: a small render after it is answered in seconds, not
  // after the minutes the abandoned one would take.
  auto r = post("/api/render",
                {{"scene", test::minimal_scene()}, {"pipeline", "surface"}, {"format", "json"}});
  EXPECT_EQ(r.result_int(), 200) << r.body();
  EXPECT_LT(ms_since(t), 20000);
  EXPECT_EQ(metric("scatter_renders_cancelled_total"), 1);
}

TEST_F(ServiceTest, RendersEstimatedPastTheTimeLimitAreRefused) {
  TearDown();
  ServerOptions o;
  o.api.max_render_s = 1;
  start(o);
  auto r = post("/api/render", long_render());
  EXPECT_EQ(r.result_int(), 413) << r.body();  // refused before it runs
  EXPECT_EQ(nlohmann::json::parse(r.body())["field"], "settings.spp");
  EXPECT_NE(r.body().find("--max-render-s"), std::string::npos) << r.body();
}

// Renders the minimal scene through a render job of `pipeline` and `settings`, all terms, cut at
// max_seconds, after a frame of `warm` settings on the same queue (its kernels built); also says
// how long it took.
RenderOutcome render_job(const std::string& pipeline, Settings settings, double max_seconds,
                         int size, double* ms, std::optional<Settings> warm = std::nullopt) {
  RenderQueue queue(gpu::GpuOptions{});
  Metrics metrics;
  FrameSpec f;
  f.scene = std::make_shared<const Scene>(
      parse_scene(test::minimal_scene(), test::source_path("scenes")));
  f.pipeline = pipeline;
  f.terms = "all";
  f.width = f.height = size;
  auto run = [&](const FrameSpec& spec) {
    std::promise<RenderOutcome> done;
    if (!post_render(queue, metrics, spec, std::make_shared<CancelToken>(),
                     [&](RenderOutcome o) { done.set_value(std::move(o)); })) {
      ADD_FAILURE() << "the queue refused the render";
      return RenderOutcome{};
    }
    return done.get_future().get();
  };
  if (warm) {
    FrameSpec w = f;
    w.settings = *warm;
    run(w);
  }
  f.settings = std::move(settings);
  f.max_seconds = max_seconds;  // enforced while it runs
  auto t = Clock::now();
  RenderOutcome o = run(f);
  *ms = ms_since(t);
  return o;
}

// A render past --max-render-s is stopped, whatever it was estimated at: psf's march checks
// between bands of rows.
TEST(RenderJob, ARenderPastItsTimeLimitIsStopped) {
  double ms = 0;
  RenderOutcome o = render_job("psf", {{"step", 0.05}}, 0.2, 1536, &ms);
  EXPECT_EQ(o.status, 503);
  EXPECT_NE(o.error.find("--max-render-s"), std::string::npos) << o.error;
  EXPECT_LT(ms, 15000);
}

// The path tracer is not cut off by the limit: it stops its passes in time and answers with the
// samples drawn, and its plan says why.
TEST(RenderJob, APathTracerPastItsTimeLimitAnswersWithItsSamples) {
  double ms = 0;
  RenderOutcome o = render_job("reference", {{"spp", 100000}}, 2, 0, &ms, Settings{{"spp", 3}});
  ASSERT_TRUE(o.result) << o.status << " " << o.error;
  const std::string trace = plan_stage(o.result->plan, "trace").reason;
  EXPECT_NE(trace.find("of 100000 samples per pixel, what the render's time limit (2 s)"),
            std::string::npos)
      << trace;
  EXPECT_LT(ms, 15000);
}

TEST_F(ServiceTest, CostlyRequestsAreRefusedNamingTheFieldAndTheLimit) {
  nlohmann::json scene = test::minimal_scene();
  scene["voxels"] = 512;
  nlohmann::json light = scene["lights"][0];
  for (int i = 0; i < 15; ++i) scene["lights"].push_back(light);
  auto r = post("/api/render",
                {{"scene", scene}, {"pipeline", "reference"}, {"settings", {{"spp", 3}}}});
  ASSERT_EQ(r.result_int(), 413) << r.body();
  auto j = nlohmann::json::parse(r.body());
  EXPECT_EQ(j["field"], "scene.voxels");
  EXPECT_NE(j["error"].get<std::string>().find("--max-request-mb"), std::string::npos) << j.dump();
  // The amount and the limit in the summary's units ("would need about 14 GB (...), over this
  // server's limit of 2.1 GB per request (--max-request-mb 2048)"), not "1.23e+04 MB".
  EXPECT_TRUE(std::regex_search(
      j["error"].get<std::string>(),
      std::regex(R"(would need about [0-9.]+ GB \(reference: .*\), over this server's limit )"
                 R"(of [0-9.]+ GB per request \(--max-request-mb [0-9]+\)$)")))
      << j.dump();
  r = post("/api/render",
           {{"scene", scene}, {"pipeline", "thickness"}, {"settings", {{"shadow_size", 8192}}}});
  ASSERT_EQ(r.result_int(), 413) << r.body();
  EXPECT_EQ(nlohmann::json::parse(r.body())["field"], "settings.shadow_size");
  // The daemon is unharmed.
  EXPECT_EQ(request(port(), http::verb::get, "/api/health").result_int(), 200);
}

TEST_F(ServiceTest, DeepNestingAndBadHttpAreClearErrors) {
  std::string deep = std::string(100000, '[') + std::string(100000, ']');
  auto r = request(port(), http::verb::post, "/api/render", R"({"scene": )" + deep + "}");
  EXPECT_EQ(r.result_int(), 400);
  EXPECT_NE(r.body().find("deeper than 64"), std::string::npos) << r.body();
  // Headers past the limit: 431, not a dropped connection.
  boost::asio::io_context io;
  beast::tcp_stream s(io);
  s.connect({boost::asio::ip::make_address("127.0.0.1"), port()});
  http::request<http::string_body> big{http::verb::get, "/api/health", 11};
  big.set("X-Padding", std::string(20000, 'x'));
  http::write(s, big);
  beast::flat_buffer b;
  http::response<http::string_body> res;
  http::read(s, b, res);
  EXPECT_EQ(res.result_int(), 431);
  EXPECT_EQ(request(port(), http::verb::get, "/api/health").result_int(), 200);
}

TEST_F(ServiceTest, ShippedScenesLoadOnceAndTheLoadIsTimed) {
  nlohmann::json req = {{"scene_name", "bunny"}, {"pipeline", "surface"}, {"format", "json"}};
  auto first = nlohmann::json::parse(post("/api/render", req).body());
  auto second = nlohmann::json::parse(post("/api/render", req).body());
  EXPECT_TRUE(first["timings_ms"].contains("scene_load")) << first.dump();
  EXPECT_FALSE(second["timings_ms"].contains("scene_load")) << second.dump();
  EXPECT_EQ(metric("scatter_scene_loads_total"), 1);
}

TEST_F(ServiceTest, ABakeDoesNotHoldRenders) {
  TearDown();
  ServerOptions o;
  o.api.max_render_s = 1e5;
  o.cache = std::make_shared<BakeCache>();
  start(o);
  nlohmann::json scene = test::minimal_scene();
  scene["medium"]["density"] = {{"type", "noise"}};
  auto bake = post("/api/bakes", {{"scene", scene},
                                  {"pipeline", "single"},
                                  {"settings", {{"samples", 60000}, {"directions", 128}}}});
  ASSERT_EQ(bake.result_int(), 202) << bake.body();
  std::string id = nlohmann::json::parse(bake.body())["id"];
  for (int i = 0; i < 500; ++i) {
    auto s = nlohmann::json::parse(request(port(), http::verb::get, "/api/bakes/" + id).body());
    if (s["state"] == "running") break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  auto r = post("/api/render",
                {{"scene", test::minimal_scene()}, {"pipeline", "surface"}, {"format", "json"}});
  EXPECT_EQ(r.result_int(), 200);
  auto s = nlohmann::json::parse(request(port(), http::verb::get, "/api/bakes/" + id).body());
  EXPECT_EQ(s["state"], "running") << "the render waited for the bake: " << s.dump();
  // A cancel is answered at once, while the bake runs.
  auto t = Clock::now();
  EXPECT_EQ(request(port(), http::verb::delete_, "/api/bakes/" + id).result_int(), 202);
  EXPECT_LT(ms_since(t), 1000);
}

// A scripted WebSocket client.
struct Ws {
  boost::asio::io_context io;
  websocket::stream<beast::tcp_stream> ws{io};
  explicit Ws(unsigned short port, const std::string& target = "/api/ws") {
    beast::get_lowest_layer(ws).connect({boost::asio::ip::make_address("127.0.0.1"), port});
    ws.handshake("127.0.0.1", target);
  }
  void send(const nlohmann::json& j) { ws.write(boost::asio::buffer(j.dump())); }
  nlohmann::json next_json() {
    for (;;) {
      beast::flat_buffer b;
      ws.read(b);
      if (!ws.got_binary()) return nlohmann::json::parse(beast::buffers_to_string(b.data()));
    }
  }
};

TEST_F(ServiceTest, AnAckCountsOnlyForTheFrameInFlight) {
  Ws c(port());
  c.send({{"type", "hello"}, {"scene", test::minimal_scene()}, {"pipeline", "surface"}});
  nlohmann::json h = c.next_json();
  ASSERT_EQ(h["type"], "frame") << h.dump();
  // Poses and acks for frames that were never sent: no frame beyond the one in flight renders.
  for (int i = 0; i < 200; ++i) {
    c.send({{"type", "camera"}, {"position", {0.01 * i, 0, 4}}, {"revision", i + 1}});
    c.send({{"type", "ack"}, {"frame", 1000 + i}});
  }
  c.send({{"type", "ping"}});
  EXPECT_EQ(c.next_json()["type"], "pong");  // messages are in order: no frame came before it
  c.send({{"type", "ack"}, {"frame", h["frame"]}});
  nlohmann::json next = c.next_json();
  EXPECT_EQ(next["type"], "frame");
  EXPECT_EQ(next["camera_revision"], 200);  // the newest pose, once the real frame is acked
}

TEST_F(ServiceTest, SilentSessionsGiveTheirSlotBack) {
  TearDown();
  ServerOptions o;
  o.api.max_sessions = 1;
  o.api.session_idle_s = 1;
  start(o);
  Ws silent(port());
  EXPECT_THROW(Ws{port()}, boost::system::system_error);  // the one slot is held
  bool admitted = false;
  auto t = Clock::now();
  while (!admitted && ms_since(t) < 5000) {
    try {
      Ws next(port());
      admitted = true;
    } catch (const boost::system::system_error&) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  }
  EXPECT_TRUE(admitted);
  EXPECT_GT(ms_since(t), 500);  // not before the idle time
}

TEST_F(ServiceTest, PercentEncodedTokensMatch) {
  TearDown();
  ServerOptions o;
  o.api.token = "a+b/c=d&e";
  start(o);
  EXPECT_EQ(request(port(), http::verb::get, "/api/health?token=a%2Bb%2Fc%3Dd%26e").result_int(),
            200);
  EXPECT_EQ(request(port(), http::verb::get, "/api/health?token=a+b/c=d").result_int(), 401);
  EXPECT_EQ(request(port(), http::verb::get, "/api/health").result_int(), 401);
  EXPECT_NO_THROW(Ws(port(), std::string("/api/ws?token=a%2Bb%2Fc%3Dd%26e")));
}

// The page opened with /?token=T sets a cookie that later requests carry instead of the token;
// a wrong token on the page is an HTML page, on the API JSON.
TEST_F(ServiceTest, ThePageKeepsItsTokenInACookie) {
  TearDown();
  ServerOptions o;
  o.api.token = "a+b/c=d&e";
  start(o);
  auto page = request(port(), http::verb::get, "/?token=a%2Bb%2Fc%3Dd%26e");
  EXPECT_EQ(page.result_int(), 200);
  std::string cookie(page[http::field::set_cookie]);
  EXPECT_EQ(cookie.substr(0, cookie.find(';')), "scatter_token=a%2Bb%2Fc%3Dd%26e") << cookie;
  EXPECT_NE(cookie.find("HttpOnly"), std::string::npos);
  auto with_cookie = [&](const std::string& target, const std::string& value) {
    boost::asio::io_context io;
    beast::tcp_stream stream(io);
    stream.connect({boost::asio::ip::make_address("127.0.0.1"), port()});
    http::request<http::string_body> req{http::verb::get, target, 11};
    req.set(http::field::host, "127.0.0.1");
    req.set(http::field::cookie, "other=1; " + value);
    http::write(stream, req);
    beast::flat_buffer buffer;
    http::response<http::string_body> res;
    http::read(stream, buffer, res);
    return res.result_int();
  };
  EXPECT_EQ(with_cookie("/app.js", cookie.substr(0, cookie.find(';'))), 200);
  EXPECT_EQ(with_cookie("/api/health", cookie.substr(0, cookie.find(';'))), 200);
  EXPECT_EQ(with_cookie("/app.js", "scatter_token=wrong"), 401);
  auto wrong = request(port(), http::verb::get, "/?token=wrong");
  EXPECT_EQ(wrong.result_int(), 401);
  EXPECT_NE(std::string(wrong[http::field::content_type]).find("text/html"), std::string::npos);
  EXPECT_NE(wrong.body().find("needs a token"), std::string::npos);
  EXPECT_EQ(request(port(), http::verb::get, "/api/health?token=wrong").body().substr(0, 9),
            "{\"error\":");
}

}  // namespace
}  // namespace scatter::server
