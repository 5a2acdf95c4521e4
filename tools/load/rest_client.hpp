// One scripted REST client on a thread of its own: cycles of POST /api/render and/or a bake
// (POST /api/bakes, then GET /api/bakes/{id} every poll_ms until it is done, failed or
// cancelled), until the duration or the number of cycles is reached. Latencies per route.
#pragma once

#include <chrono>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "tools/load/error_tally.hpp"
#include "tools/load/http_client.hpp"
#include "tools/load/latency_stats.hpp"
#include "tools/load/load_options.hpp"

namespace scatter::load {

struct RouteResult {
  LatencyStats ms;
  std::map<int, long long> statuses;
  void merge(const RouteResult& other);
  nlohmann::json to_json() const;
};

struct RestResult {
  int index = 0;
  long long cycles = 0;
  double seconds = 0;
  // "POST /api/render", "POST /api/bakes", "GET /api/bakes/{id}", and "bake" (from the POST to
  // the job's end, polls included).
  std::map<std::string, RouteResult> routes;
  std::map<std::string, long long> bake_states;  // how each bake ended
  ErrorTally errors;
};

class RestClient {
 public:
  using Clock = std::chrono::steady_clock;
  RestClient(const LoadOptions& options, int index);
  // Runs the cycles; returns when done. Network failures are counted, never thrown.
  void run(Clock::time_point deadline);
  const RestResult& result() const { return result_; }

 private:
  nlohmann::json body() const;
  HttpReply call(const std::string& route, boost::beast::http::verb method,
                 const std::string& target, const std::string& payload = "");
  void render();
  void bake(Clock::time_point deadline);

  const LoadOptions& options_;
  HttpClient http_;
  RestResult result_;
};

}  // namespace scatter::load
