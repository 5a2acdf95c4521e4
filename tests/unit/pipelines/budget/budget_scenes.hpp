// Scenes of the budget tests: the shipped sphere with its medium set.
#pragma once

#include <fstream>

#include "../../test_util.hpp"
#include "scene/scene.hpp"

namespace scatter::test {

// scenes/sphere.json at albedo, optical diameter tau and g, size x size pixels, 32 voxels.
inline Scene sphere_scene(double albedo, double tau, double g, int size = 32) {
  nlohmann::json j = nlohmann::json::parse(std::ifstream(test::source_path("scenes/sphere.json")));
  double sigma_t = tau / 2;
  j["medium"]["sigma_s"] = {sigma_t * albedo, sigma_t * albedo, sigma_t * albedo};
  j["medium"]["sigma_a"] = {sigma_t * (1 - albedo), sigma_t * (1 - albedo), sigma_t * (1 - albedo)};
  j["medium"]["g"] = g;
  j["image"] = {{"width", size}, {"height", size}};
  j["voxels"] = 32;
  return parse_scene(j, ".");
}

}  // namespace scatter::test
