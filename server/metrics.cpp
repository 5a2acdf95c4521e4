#include "server/metrics.hpp"

#include <unistd.h>

#include <fstream>
#include <sstream>

namespace scatter::server {
namespace {

// Resident set size from /proc/self/statm (its second field, in pages); 0 where there is none.
double resident_bytes() {
  std::ifstream statm("/proc/self/statm");
  long long size = 0, resident = 0;
  if (!(statm >> size >> resident)) return 0;
  return double(resident) * double(sysconf(_SC_PAGESIZE));
}

// Seconds since the epoch at which this process started: the boot time (btime in /proc/stat)
// plus the process's start in clock ticks after boot (field 22 of /proc/self/stat); 0 if unknown.
double start_time_seconds() {
  std::ifstream stat_file("/proc/stat");
  std::string key;
  double btime = 0;
  while (stat_file >> key)
    if (key == "btime" && (stat_file >> btime)) break;
  std::ifstream self("/proc/self/stat");
  std::string line;
  if (btime <= 0 || !std::getline(self, line)) return 0;
  // The command name (field 2) may hold spaces: count fields after its closing parenthesis.
  std::istringstream rest(line.substr(line.rfind(')') + 1));
  std::string field;
  for (int i = 3; i <= 22 && rest >> field; ++i)
    if (i == 22) return btime + std::stod(field) / double(sysconf(_SC_CLK_TCK));
  return 0;
}

}  // namespace

const std::vector<double>& Metrics::buckets() {
  static const std::vector<double> b = {0.005, 0.01, 0.025, 0.05, 0.1, 0.25,
                                        0.5,   1,    2.5,   5,    10,  30};
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
  for (const auto& [pipeline, h] : frames_)
    print(out, "scatter_frame_seconds", "pipeline=\"" + pipeline + "\"", h);
  out += "# HELP scatter_stage_seconds Render time per stage, by pipeline and stage.\n";
  out += "# TYPE scatter_stage_seconds histogram\n";
  for (const auto& [key, h] : stages_)
    print(out, "scatter_stage_seconds",
          "pipeline=\"" + key.first + "\",stage=\"" + key.second + "\"", h);
  out +=
      "# HELP scatter_renders_cancelled_total Renders dropped or stopped: client gone, shutdown, "
      "time limit.\n";
  out += "# TYPE scatter_renders_cancelled_total counter\n";
  out += "scatter_renders_cancelled_total " + std::to_string(cancelled_) + "\n";
  out += "# HELP scatter_render_queue_depth Jobs waiting for the render thread.\n";
  out += "# TYPE scatter_render_queue_depth gauge\n";
  out += "scatter_render_queue_depth " + std::to_string(queue_depth) + "\n";
  std::ostringstream process;
  process.precision(15);
  process << "# HELP process_resident_memory_bytes Resident memory size in bytes.\n"
          << "# TYPE process_resident_memory_bytes gauge\n"
          << "process_resident_memory_bytes " << resident_bytes() << "\n"
          << "# HELP process_start_time_seconds Start time of the process since unix epoch in "
             "seconds.\n"
          << "# TYPE process_start_time_seconds gauge\n"
          << "process_start_time_seconds " << start_time_seconds() << "\n";
  return out + process.str();
}

}  // namespace scatter::server
