// One run of scatter-load: checks that the daemon answers, starts the RSS sampler, runs the live
// sessions or the REST clients to their bound, and puts everything into one JSON report.
#pragma once

#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tools/load/live_session.hpp"
#include "tools/load/load_options.hpp"
#include "tools/load/rest_client.hpp"

namespace scatter::load {

class LoadRun {
 public:
  explicit LoadRun(LoadOptions options) : options_(std::move(options)) {}
  // Throws std::runtime_error when the daemon cannot be reached or refuses the token (a
  // client-side failure); anything that happens once the run has started is counted instead.
  nlohmann::json live();
  nlohmann::json rest();

 private:
  nlohmann::json preflight();  // GET /api/health
  // Preflight, RSS sampling around `run`, and the fields every report has, with run's own.
  nlohmann::json measured(const std::string& mode, const std::function<nlohmann::json()>& run);
  static nlohmann::json live_report(const std::vector<SessionResult>& sessions);
  static nlohmann::json rest_report(const std::vector<RestResult>& clients);

  LoadOptions options_;
};

}  // namespace scatter::load
