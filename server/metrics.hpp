// Counters and histograms for GET /metrics (Prometheus text format). Thread safe.
#pragma once

#include <map>
#include <mutex>
#include <string>
#include <vector>

namespace scatter::server {

class Metrics {
 public:
  void count_request(const std::string& route, int status);
  // A finished render: total seconds and seconds per stage.
  void observe_render(const std::string& pipeline, double seconds,
                      const std::vector<std::pair<std::string, double>>& stages);
  // A render dropped before it ran or stopped while running (client gone, shutdown, time limit).
  void count_cancelled();
  // Prometheus text exposition; `queue_depth` is sampled by the caller. Ends with the standard
  // process metrics process_resident_memory_bytes and process_start_time_seconds (from /proc).
  std::string text(size_t queue_depth) const;

 private:
  struct Histogram {
    std::vector<double> counts;  // per bucket (cumulative when printed)
    double sum = 0;
    long long count = 0;
  };
  static const std::vector<double>& buckets();
  static void observe(Histogram& h, double v);
  static void print(std::string& out, const std::string& name, const std::string& labels,
                    const Histogram& h);

  mutable std::mutex mutex_;
  std::map<std::pair<std::string, int>, long long> requests_;
  long long cancelled_ = 0;
  std::map<std::string, Histogram> frames_;                          // by pipeline
  std::map<std::pair<std::string, std::string>, Histogram> stages_;  // by pipeline, stage
};

}  // namespace scatter::server
