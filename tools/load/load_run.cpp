#include "tools/load/load_run.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <stdexcept>
#include <thread>

#include "tools/load/http_client.hpp"
#include "tools/load/rss_sampler.hpp"

namespace scatter::load {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

double round2(double v) {
  return std::round(v * 100) / 100;
}

}  // namespace

nlohmann::json LoadRun::preflight() {
  HttpClient http(options_);
  std::string where = options_.host + ":" + options_.port;
  HttpReply r;
  try {
    r = http.request(boost::beast::http::verb::get, "/api/health");
  } catch (const std::exception& e) {
    throw std::runtime_error("cannot reach scatterd at " + where + ": " + e.what());
  }
  if (r.status == 401)
    throw std::runtime_error("scatterd at " + where +
                             " refused the token (401): give the right --token");
  nlohmann::json health = nlohmann::json::parse(r.body, nullptr, false);
  if (r.status != 200 || !health.is_object())
    throw std::runtime_error("GET /api/health at " + where + " answered " +
                             std::to_string(r.status) + ": is this scatterd?");
  return health;
}

nlohmann::json LoadRun::measured(const std::string& mode,
                                 const std::function<nlohmann::json()>& run) {
  nlohmann::json health = preflight();
  RssSampler rss(options_);
  rss.start();
  auto start = Clock::now();
  nlohmann::json results = run();
  double seconds = seconds_since(start);
  rss.stop();
  nlohmann::json report = {{"mode", mode},
                           {"target", options_.host + ":" + options_.port},
                           {"daemon_version", health.value("version", "")},
                           {"scene", options_.scene},
                           {"pipeline", options_.pipeline},
                           {"terms", options_.terms},
                           {"format", options_.format},
                           {"settings", options_.settings},
                           {"duration_s", round2(seconds)}};
  report.update(results);
  report["rss"] = rss.report();
  return report;
}

nlohmann::json LoadRun::live() {
  return measured("live", [this] {
    boost::asio::io_context io;
    auto endpoints = boost::asio::ip::tcp::resolver(io).resolve(options_.host, options_.port);
    std::vector<std::shared_ptr<LiveSession>> sessions;
    for (int i = 0; i < options_.sessions; ++i) {
      sessions.push_back(std::make_shared<LiveSession>(io, options_, i));
      sessions.back()->start(endpoints);
    }
    io.run();  // every session on this thread; returns when the last one has closed
    std::vector<SessionResult> results;
    for (const auto& s : sessions) results.push_back(s->result());
    nlohmann::json report = live_report(results);
    report["path"] = options_.path;
    report["rate_hz"] = options_.rate_hz;
    return report;
  });
}

nlohmann::json LoadRun::live_report(const std::vector<SessionResult>& sessions) {
  nlohmann::json per_session = nlohmann::json::array();
  LatencyStats pose_to_frame, render, minus_render, header_to_image;
  ErrorTally errors;
  long long frames = 0, poses = 0, coalesced = 0, unanswered = 0, admitted = 0;
  double fps_sum = 0, fps_min = 0, fps_max = 0;
  for (const auto& s : sessions) {
    per_session.push_back(s.to_json());
    errors.merge(s.errors);
    if (!s.admitted) continue;
    pose_to_frame.merge(s.pose_to_frame);
    render.merge(s.render);
    minus_render.merge(s.minus_render);
    header_to_image.merge(s.header_to_image);
    frames += s.frames;
    poses += s.poses_sent;
    coalesced += s.poses_coalesced;
    unanswered += s.poses_unanswered;
    fps_min = admitted == 0 ? s.fps() : std::min(fps_min, s.fps());
    fps_max = admitted == 0 ? s.fps() : std::max(fps_max, s.fps());
    fps_sum += s.fps();
    ++admitted;
  }
  return {{"sessions_requested", sessions.size()},
          {"sessions_admitted", admitted},
          {"frames", frames},
          {"fps_total", round2(fps_sum)},
          {"poses_sent", poses},
          {"poses_coalesced", coalesced},
          {"poses_unanswered", unanswered},
          {"pose_to_frame_ms", pose_to_frame.summary()},
          {"render_ms", render.summary()},
          {"pose_to_frame_minus_render_ms", minus_render.summary()},
          {"header_to_image_ms", header_to_image.summary()},
          {"fairness",
           {{"min_fps", round2(fps_min)},
            {"max_fps", round2(fps_max)},
            {"min_over_max", fps_max > 0 ? round2(fps_min / fps_max) : 0.0}}},
          {"errors", errors.to_json()},
          {"per_session", per_session}};
}

nlohmann::json LoadRun::rest() {
  return measured("rest", [this] {
    auto deadline = options_.duration_s > 0 ? Clock::now() + span(options_.duration_s)
                                            : Clock::time_point::max();
    std::vector<std::unique_ptr<RestClient>> clients;
    for (int i = 0; i < options_.clients; ++i)
      clients.push_back(std::make_unique<RestClient>(options_, i));
    std::vector<std::thread> threads;
    for (auto& c : clients) threads.emplace_back([&c, deadline] { c->run(deadline); });
    for (auto& t : threads) t.join();
    std::vector<RestResult> results;
    for (const auto& c : clients) results.push_back(c->result());
    nlohmann::json report = rest_report(results);
    report["ops"] = options_.ops;
    return report;
  });
}

nlohmann::json LoadRun::rest_report(const std::vector<RestResult>& clients) {
  std::map<std::string, RouteResult> routes;
  std::map<std::string, long long> bake_states;
  ErrorTally errors;
  nlohmann::json per_client = nlohmann::json::array();
  long long cycles = 0;
  for (const auto& c : clients) {
    for (const auto& [name, r] : c.routes) routes[name].merge(r);
    for (const auto& [state, n] : c.bake_states) bake_states[state] += n;
    errors.merge(c.errors);
    cycles += c.cycles;
    per_client.push_back({{"index", c.index},
                          {"cycles", c.cycles},
                          {"seconds", round2(c.seconds)},
                          {"errors", c.errors.to_json()}});
  }
  nlohmann::json by_route = nlohmann::json::object();
  for (const auto& [name, r] : routes) by_route[name] = r.to_json();
  return {{"clients", clients.size()},  {"cycles", cycles},           {"routes", by_route},
          {"bake_states", bake_states}, {"errors", errors.to_json()}, {"per_client", per_client}};
}

}  // namespace scatter::load
