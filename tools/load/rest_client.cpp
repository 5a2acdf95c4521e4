#include "tools/load/rest_client.hpp"

#include <thread>

namespace scatter::load {

namespace http = boost::beast::http;

void RouteResult::merge(const RouteResult& other) {
  ms.merge(other.ms);
  for (const auto& [status, n] : other.statuses) statuses[status] += n;
}

nlohmann::json RouteResult::to_json() const {
  nlohmann::json by_status = nlohmann::json::object();
  for (const auto& [status, n] : statuses) by_status[std::to_string(status)] = n;
  return {{"ms", ms.summary()}, {"status", by_status}};
}

RestClient::RestClient(const LoadOptions& options, int index) : options_(options), http_(options) {
  result_.index = index;
}

nlohmann::json RestClient::body() const {
  nlohmann::json j = {{"scene_name", options_.scene}, {"pipeline", options_.pipeline}};
  if (!options_.settings.empty()) j["settings"] = options_.settings;
  return j;
}

// One request, timed and counted under `route`; a status >= 400 is an error of kind "http".
// A failed exchange is an error of kind "network" and gives status 0.
HttpReply RestClient::call(const std::string& route, http::verb method, const std::string& target,
                           const std::string& payload) {
  HttpReply reply;
  try {
    reply = http_.request(method, target, payload);
  } catch (const std::exception& e) {
    result_.errors.add("network", route + ": " + e.what());
    ++result_.routes[route].statuses[0];
    return reply;
  }
  RouteResult& r = result_.routes[route];
  r.ms.add(reply.ms);
  ++r.statuses[reply.status];
  if (reply.status >= 400) {
    nlohmann::json j = nlohmann::json::parse(reply.body, nullptr, false);
    std::string what = j.is_object() && j.contains("error") ? j["error"].dump() : "(no JSON error)";
    result_.errors.add("http", route + " " + std::to_string(reply.status) + ": " + what);
  }
  return reply;
}

void RestClient::render() {
  nlohmann::json j = body();
  j["format"] = options_.format;
  if (!options_.terms.empty()) j["terms"] = options_.terms;
  call("POST /api/render", http::verb::post, "/api/render", j.dump());
}

void RestClient::bake(Clock::time_point deadline) {
  auto start = Clock::now();
  HttpReply reply = call("POST /api/bakes", http::verb::post, "/api/bakes", body().dump());
  if (reply.status != 200 && reply.status != 202) return;
  nlohmann::json job = nlohmann::json::parse(reply.body, nullptr, false);
  if (!job.is_object() || !job.contains("id")) {
    result_.errors.add("protocol", "POST /api/bakes answered without a job id");
    return;
  }
  std::string target = "/api/bakes/" + job["id"].get<std::string>();
  auto finished = [&] {
    std::string state = job.value("state", "");
    return state == "done" || state == "failed" || state == "cancelled";
  };
  while (!finished()) {
    if (Clock::now() > deadline) {
      ++result_.bake_states["unfinished at the end"];
      return;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(options_.poll_ms));
    reply = call("GET /api/bakes/{id}", http::verb::get, target);
    if (reply.status != 200) return;
    job = nlohmann::json::parse(reply.body, nullptr, false);
    if (!job.is_object())
      return result_.errors.add("protocol", "GET " + target + " is not a JSON object");
  }
  ++result_.bake_states[job["state"].get<std::string>()];
  result_.routes["bake"].ms.add(
      std::chrono::duration<double, std::milli>(Clock::now() - start).count());
  ++result_.routes["bake"].statuses[200];
}

void RestClient::run(Clock::time_point deadline) {
  auto start = Clock::now();
  while (Clock::now() < deadline && (options_.cycles == 0 || result_.cycles < options_.cycles)) {
    for (const auto& op : options_.ops) {
      if (op == "render") render();
      if (op == "bake") bake(deadline);
    }
    ++result_.cycles;
  }
  result_.seconds = std::chrono::duration<double>(Clock::now() - start).count();
}

}  // namespace scatter::load
