#include "tools/load/latency_stats.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace scatter::load {
namespace {

double rounded(double ms) {
  return std::round(ms * 100) / 100;
}

}  // namespace

void LatencyStats::merge(const LatencyStats& other) {
  samples_.insert(samples_.end(), other.samples_.begin(), other.samples_.end());
}

double LatencyStats::percentile(double p) const {
  if (samples_.empty()) return 0;
  std::vector<double> sorted = samples_;
  std::sort(sorted.begin(), sorted.end());
  auto rank = static_cast<size_t>(std::ceil(p / 100 * double(sorted.size())));
  return sorted[std::clamp<size_t>(rank, 1, sorted.size()) - 1];
}

nlohmann::json LatencyStats::summary() const {
  nlohmann::json j = {{"count", samples_.size()}};
  if (samples_.empty()) {
    for (const char* k : {"p50", "p95", "p99", "mean", "max"}) j[k] = nullptr;
    return j;
  }
  j["p50"] = rounded(percentile(50));
  j["p95"] = rounded(percentile(95));
  j["p99"] = rounded(percentile(99));
  j["mean"] =
      rounded(std::accumulate(samples_.begin(), samples_.end(), 0.0) / double(samples_.size()));
  j["max"] = rounded(*std::max_element(samples_.begin(), samples_.end()));
  return j;
}

}  // namespace scatter::load
