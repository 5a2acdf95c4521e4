#include "tools/load/pose_script.hpp"

#include <algorithm>
#include <cmath>

namespace scatter::load {

PoseScript::PoseScript(const LoadOptions& options, int session)
    : path_(options.path),
      rate_hz_(options.rate_hz),
      orbit_rad_s_(options.orbit_deg_s * M_PI / 180),
      burst_poses_(options.burst_poses),
      burst_pause_ticks_(
          static_cast<int>(std::ceil(options.burst_pause_ms / 1000.0 * options.rate_hz))),
      // Sessions start spread around the object, so that their frames differ.
      yaw_(session * 2.399963),
      rng_(options.seed + 7919u * unsigned(session)) {}

Pose PoseScript::place() const {
  return {{radius_ * std::sin(yaw_) * std::cos(pitch_), radius_ * std::sin(pitch_),
           radius_ * std::cos(yaw_) * std::cos(pitch_)}};
}

std::optional<Pose> PoseScript::at(long long tick) {
  double dt = 1 / rate_hz_;
  if (path_ == "random-walk") {
    std::normal_distribution<double> step(0, 0.05);
    yaw_ += step(rng_);
    pitch_ = std::clamp(pitch_ + step(rng_), -1.2, 1.2);  // never up along the view
    radius_ = std::clamp(radius_ + step(rng_), 2.5, 5.0);
    return place();
  }
  if (path_ == "burst" && tick % (burst_poses_ + burst_pause_ticks_) >= burst_poses_)
    return std::nullopt;
  yaw_ += orbit_rad_s_ * dt;
  return place();
}

std::array<double, 3> PoseScript::light(long long n) {
  double a = 0.3 * double(n);
  return {3 * std::cos(a), 3, 3 * std::sin(a)};
}

}  // namespace scatter::load
