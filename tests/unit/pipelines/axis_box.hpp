// The box every pipeline's single term is checked on: [-1, 1]^3 lit from +z by a directional light
// of irradiance 2, seen from +z along the axis; on the centre ray (pixel (4, 4) of 9 x 9) the
// single-scattered radiance is sigma_s p(-1) E (1 - exp(-4 sigma_t)) / (2 sigma_t).
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>

#include "../test_util.hpp"
#include "scene/scene.hpp"

namespace scatter::test {

inline Scene axis_box(double sigma_s, double sigma_a, double g) {
  nlohmann::json j = minimal_scene();
  j["mesh"] = {{"shape", "box"}, {"size", {2, 2, 2}}};
  j["medium"] = {{"sigma_s", sigma_s}, {"sigma_a", sigma_a}, {"g", g}};
  j["lights"] = {{{"type", "directional"}, {"direction", {0, 0, -1}}, {"irradiance", 2.0}}};
  j["camera"] = {{"position", {0, 0, 4}}, {"fov_deg", 30}};
  j["image"] = {{"width", 9}, {"height", 9}};  // odd: the centre pixel's ray is the axis
  j["voxels"] = 32;                            // voxel faces fall on the box's faces
  return parse_scene(j, ".");
}

// The centre ray's radiance seen from (0, 0, z0) on the axis, z0 in [-1, 1] inside the box or
// z0 >= 1 outside: the point at height z lies 1 - z from the lit face and min(z0, 1) - z from
// where the ray enters, so L = sigma_s p E integral_{-1}^{z1} exp(-sigma_t (1 + z1 - 2 z)) dz
// = sigma_s p E (exp(-sigma_t (1 - z1)) - exp(-sigma_t (3 + z1))) / (2 sigma_t), z1 = min(z0, 1).
inline double axis_box_radiance(double sigma_s, double sigma_a, double g, double z0 = 4) {
  double st = sigma_s + sigma_a, z1 = std::min(z0, 1.0);
  double p = (1 - g * g) / (4 * std::numbers::pi * std::pow(1 + g, 3));  // HG at cos = -1
  return sigma_s * p * 2.0 * (std::exp(-st * (1 - z1)) - std::exp(-st * (3 + z1))) / (2 * st);
}

}  // namespace scatter::test
