#include "server/metrics.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <sstream>
#include <string>

namespace scatter::server {
namespace {

// The value of the sample line `name VALUE` in Prometheus text; fails the test when absent, or
// when the HELP and TYPE lines do not come right before it.
double sample(const std::string& text, const std::string& name, const std::string& type) {
  std::istringstream lines(text);
  std::string line, help, type_line;
  while (std::getline(lines, line)) {
    if (line.rfind(name + " ", 0) == 0) {
      EXPECT_EQ(help.rfind("# HELP " + name + " ", 0), 0u) << text;
      EXPECT_EQ(type_line, "# TYPE " + name + " " + type) << text;
      return std::stod(line.substr(name.size() + 1));
    }
    help = type_line;
    type_line = line;
  }
  ADD_FAILURE() << name << " is not in the metrics:\n" << text;
  return 0;
}

TEST(MetricsTest, ProcessResidentMemoryIsAPlausibleGauge) {
  Metrics metrics;
  double rss = sample(metrics.text(0), "process_resident_memory_bytes", "gauge");
  EXPECT_GT(rss, 1e6);   // this test binary alone holds more than a megabyte
  EXPECT_LT(rss, 1e12);  // and its pages are counted in bytes, not kilobytes of kilobytes
  // Touching 64 MB more shows up in the next sample.
  std::string block(64 << 20, 'x');
  double grown = sample(metrics.text(0), "process_resident_memory_bytes", "gauge");
  EXPECT_GT(grown, rss + 32e6) << block[block.size() / 2];
}

TEST(MetricsTest, ProcessStartTimeIsBeforeNowAndRecent) {
  double start = sample(Metrics().text(0), "process_start_time_seconds", "gauge");
  double now =
      std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  EXPECT_LE(start, now + 1);
  EXPECT_GT(start, now - 3600) << "the test process started within the hour";
}

}  // namespace
}  // namespace scatter::server
