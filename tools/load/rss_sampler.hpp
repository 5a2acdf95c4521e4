// Samples the daemon's resident memory every rss_interval_s on a thread of its own: the
// process_resident_memory_bytes gauge of GET /metrics, or, for a daemon without it, VmRSS of
// /proc/PID/status when --pid is given (same machine only).
#pragma once

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "tools/load/http_client.hpp"
#include "tools/load/latency_stats.hpp"
#include "tools/load/load_options.hpp"

namespace scatter::load {

class RssSampler {
 public:
  explicit RssSampler(const LoadOptions& options);
  ~RssSampler();
  void start();  // takes the first sample at once
  void stop();   // takes the last sample, then joins
  // {"source", "start_bytes", "end_bytes", "min_bytes", "max_bytes", "growth_pct", "range_pct",
  //  "samples", "interval_s", "metrics_ms" (how long GET /metrics took), "series": [[t_s, bytes],
  //  ...]}; source null when nothing was read.
  nlohmann::json report() const;

  // The gauge's value in a Prometheus text exposition, if the line is there.
  static std::optional<double> parse_metric(const std::string& text, const std::string& name);

 private:
  void sample();
  std::optional<double> from_proc() const;

  const LoadOptions& options_;
  HttpClient http_;
  std::string source_;
  std::vector<std::pair<double, double>> series_;  // seconds since start, bytes
  LatencyStats metrics_ms_;
  std::chrono::steady_clock::time_point started_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace scatter::load
