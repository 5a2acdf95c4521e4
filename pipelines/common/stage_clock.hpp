// Wall-clock milliseconds per pipeline stage. The caller waits for the device (glFinish,
// queue.finish) before stop() so that the time lands on the stage that issued the work.
#pragma once

#include <chrono>
#include <string>
#include <vector>

#include "bake/bake_result.hpp"

namespace scatter {

class StageClock {
 public:
  explicit StageClock(std::vector<StageTime>& out) : out_(out) {}
  void stop(const std::string& stage) {
    auto now = std::chrono::steady_clock::now();
    out_.push_back({stage, std::chrono::duration<double, std::milli>(now - start_).count()});
    start_ = now;
  }
  // Starts the next stage now, without recording the time since the last stop (for stages the
  // caller timed itself).
  void restart() { start_ = std::chrono::steady_clock::now(); }

 private:
  std::vector<StageTime>& out_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace scatter
