// A set of durations (milliseconds) and their percentiles, nearest-rank.
#pragma once

#include <nlohmann/json.hpp>
#include <vector>

namespace scatter::load {

class LatencyStats {
 public:
  void add(double ms) { samples_.push_back(ms); }
  void merge(const LatencyStats& other);
  size_t count() const { return samples_.size(); }
  // The smallest sample with at least p % of the samples at or below it; 0 when there are none.
  double percentile(double p) const;
  // {"count", "p50", "p95", "p99", "mean", "max"}; the figures are null when there are no samples.
  nlohmann::json summary() const;

 private:
  std::vector<double> samples_;
};

}  // namespace scatter::load
