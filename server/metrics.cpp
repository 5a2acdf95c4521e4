#include "server/metrics.hpp"

#include <sstream>

namespace scatter::server {

const std::vector<double>& Metrics::buckets() {
  static const std::vector<double> b = {0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1, 2.5, 5, 10, 30};
  return b;
}

void Metrics::observe(Histogram& h, double v) {
  if (h.counts.empty()) h.counts.assign(buckets().size(), 0);
  for (size_t i = 0; i < buckets().size(); ++i)
    if (v <= buckets()[i]) {
      ++h.counts[i];
      break;
    }
  h.sum += v;
  ++h.count;
}

void Metrics::count_request(const std::string& route, int status) {
  std::lock_guard lock(mutex_);
  ++requests_[{route, status}];
}

void Metrics::count_cancelled() {
  std::lock_guard lock(mutex_);
  ++cancelled_;
}

void Metrics::observe_render(const std::string& pipeline, double seconds,
                             const std::vector<std::pair<std::string, double>>& stages) {
  std::lock_guard lock(mutex_);
  observe(frames_[pipeline], seconds);
  for (const auto& [stage, s] : stages) observe(stages_[{pipeline, stage}], s);
}

void Metrics::print(std::string& out, const std::string& name, const std::string& labels,
                    const Histogram& h) {
  std::ostringstream s;
  double cumulative = 0;
  for (size_t i = 0; i < buckets().size(); ++i) {
    cumulative += h.counts.empty() ? 0 : h.counts[i];
    s << name << "_bucket{" << labels << ",le=\"" << buckets()[i] << "\"} " << cumulative << "\n";
  }
  s << name << "_bucket{" << labels << ",le=\"+Inf\"} " << h.count << "\n";
  s << name << "_sum{" << labels << "} " << h.sum << "\n";
  s << name << "_count{" << labels << "} " << h.count << "\n";
  out += s.str();
}

std::string Metrics::text(size_t queue_depth) const {
  std::lock_guard lock(mutex_);
  std::string out;
  out += "# HELP scatter_http_requests_total HTTP requests by route and status.\n";
  out += "# TYPE scatter_http_requests_total counter\n";
  for (const auto& [key, n] : requests_)
    out += "scatter_http_requests_total{route=\"" + key.first + "\",status=\"" +
           std::to_string(key.second) + "\"} " + std::to_string(n) + "\n";
  out += "# HELP scatter_frame_seconds Render time per frame, by pipeline.\n";
  out += "# TYPE scatter_frame_seconds histogram\n";
  for (const auto& [pipeline, h] : frames_) print(out, "scatter_frame_seconds", "pipeline=\"" + pipeline + "\"", h);
  out += "# HELP scatter_stage_seconds Render time per stage, by pipeline and stage.\n";
  out += "# TYPE scatter_stage_seconds histogram\n";
  for (const auto& [key, h] : stages_)
    print(out, "scatter_stage_seconds", "pipeline=\"" + key.first + "\",stage=\"" + key.second + "\"", h);
  out += "# HELP scatter_renders_cancelled_total Renders dropped or stopped: client gone, shutdown, time limit.\n";
  out += "# TYPE scatter_renders_cancelled_total counter\n";
  out += "scatter_renders_cancelled_total " + std::to_string(cancelled_) + "\n";
  out += "# HELP scatter_render_queue_depth Jobs waiting for the render thread.\n";
  out += "# TYPE scatter_render_queue_depth gauge\n";
  out += "scatter_render_queue_depth " + std::to_string(queue_depth) + "\n";
  return out;
}

}  // namespace scatter::server
