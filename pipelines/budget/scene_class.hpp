// What the budget planner knows of a scene before it renders it: the class the calibration table
// is indexed by (docs/pipelines/auto.md). Computed from the scene alone in microseconds.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "pipelines/pipeline.hpp"
#include "scene/scene.hpp"

namespace scatter {

struct SceneClass {
  Terms terms = Terms::All;
  bool homogeneous = true;    // a constant density and no blocker
  bool index_matched = true;  // ior 1: no Fresnel boundary
  double albedo = 0.9;        // sigma_s / sigma_t, mean over the channels
  double tau = 1;             // optical size: mean sigma_t x mean density x the object's size
  double g = 0;
  bool light_inside = false;  // a point or spot light inside the object's bounding sphere
  // The largest density over the smallest (> 0) on the same lattice as tau's; 1 for a constant
  // field. Not a calibration feature: it marks what psf's multiple term cannot render.
  double contrast = 1;
  // Where the lights stand seen from the camera: the cosine between the directions from the
  // object's centre to each light and to the camera, averaged with each light's irradiance at the
  // centre as its weight (a spot's through its cone; lights inside the object's bounding sphere
  // left out): 1 lit from the camera's side, 0 from the side, -1 from behind; 1 with the camera
  // inside the object's bounds. Not a grid feature: the calibration measures pairs lit from the
  // calibration's front and from further round, and the planner scales a prediction by their
  // ratio (CalibrationTable::predict_error).
  double facing = 1;

  // The continuous features, scaled so that one unit is about one step of the calibration grid:
  // log2(tau) / 2, -log10(1 - albedo) and g / kGStep.
  double feature(int i) const;
  static constexpr double kGStep = 0.7;
  static constexpr int kFeatures = 3;
  static const char* feature_name(int i);
};

SceneClass classify(const Scene& scene, Terms terms);

// "homogeneous, index matched, albedo 0.97, tau 5.2, g 0"
std::string describe(const SceneClass& c);

void to_json(nlohmann::json& j, const SceneClass& c);
void from_json(const nlohmann::json& j, SceneClass& c);

}  // namespace scatter
