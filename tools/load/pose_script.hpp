// The camera path a scripted live session follows, as the web client's orbit control moves it:
// the camera on a sphere around the origin, looking at it, y up.
//
//   orbit        yaw grows steadily (orbit_deg_s), a pose at every tick
//   random-walk  yaw, pitch and radius take small random steps (seeded per session)
//   burst        the orbit's poses in bursts of burst_poses ticks, then burst_pause_ms without
//                any (the server refines the still view in the pauses)
#pragma once

#include <array>
#include <optional>
#include <random>
#include <string>

#include "tools/load/load_options.hpp"

namespace scatter::load {

struct Pose {
  std::array<double, 3> position;
};

class PoseScript {
 public:
  PoseScript(const LoadOptions& options, int session);
  // The pose for tick `tick` (ticks come at options.rate_hz), or none while a burst pauses.
  std::optional<Pose> at(long long tick);
  // The point light's position for the n-th lights message: circling above the object.
  static std::array<double, 3> light(long long n);

 private:
  Pose place() const;

  std::string path_;
  double rate_hz_, orbit_rad_s_;
  int burst_poses_, burst_pause_ticks_;
  double yaw_, pitch_ = 0.05, radius_ = 3.6;
  std::mt19937 rng_;
};

}  // namespace scatter::load
