#include "tools/load/rss_sampler.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

namespace scatter::load {

RssSampler::RssSampler(const LoadOptions& options) : options_(options), http_(options) {}

RssSampler::~RssSampler() {
  stop();
}

void RssSampler::start() {
  started_ = std::chrono::steady_clock::now();
  sample();
  thread_ = std::thread([this] {
    auto interval = std::chrono::duration<double>(options_.rss_interval_s);
    std::unique_lock lock(mutex_);
    while (!wake_.wait_for(lock, interval, [this] { return stopping_; })) {
      lock.unlock();
      sample();
      lock.lock();
    }
  });
}

void RssSampler::stop() {
  if (!thread_.joinable()) return;
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  thread_.join();
  sample();
}

std::optional<double> RssSampler::parse_metric(const std::string& text, const std::string& name) {
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line))
    if (line.rfind(name + " ", 0) == 0) return std::stod(line.substr(name.size() + 1));
  return std::nullopt;
}

std::optional<double> RssSampler::from_proc() const {
  std::ifstream status("/proc/" + std::to_string(options_.pid) + "/status");
  std::string key;
  double kb = 0;
  while (status >> key)
    if (key == "VmRSS:" && status >> kb) return kb * 1024;
  return std::nullopt;
}

// Called from the sampling thread only (and from start/stop when it is not running).
void RssSampler::sample() {
  std::optional<double> bytes;
  std::string source;
  try {
    HttpReply r = http_.request(boost::beast::http::verb::get, "/metrics");
    if (r.status == 200) bytes = parse_metric(r.body, "process_resident_memory_bytes");
    source = "metrics";
    metrics_ms_.add(r.ms);
  } catch (const std::exception&) {
    // The daemon is busy or gone: this sample is missing; a /proc reading may stand in.
  }
  if (!bytes && options_.pid > 0) {
    bytes = from_proc();
    source = "proc:" + std::to_string(options_.pid);
  }
  if (!bytes) return;
  if (source_.empty()) source_ = source;
  series_.emplace_back(
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count(), *bytes);
}

nlohmann::json RssSampler::report() const {
  nlohmann::json j = {{"source", source_.empty() ? nlohmann::json() : nlohmann::json(source_)},
                      {"samples", series_.size()},
                      {"interval_s", options_.rss_interval_s},
                      {"metrics_ms", metrics_ms_.summary()}};
  if (series_.empty()) return j;
  auto [lo, hi] =
      std::minmax_element(series_.begin(), series_.end(),
                          [](const auto& a, const auto& b) { return a.second < b.second; });
  double first = series_.front().second, last = series_.back().second;
  auto pct = [](double v) { return std::round(v * 1000) / 10; };
  j["start_bytes"] = first;
  j["end_bytes"] = last;
  j["min_bytes"] = lo->second;
  j["max_bytes"] = hi->second;
  j["growth_pct"] = pct((last - first) / first);
  j["range_pct"] = pct((hi->second - lo->second) / lo->second);
  nlohmann::json series = nlohmann::json::array();
  for (const auto& [t, b] : series_) series.push_back({std::round(t * 10) / 10, b});
  j["series"] = series;
  return j;
}

}  // namespace scatter::load
