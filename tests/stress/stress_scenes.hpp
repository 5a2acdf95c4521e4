// The numerical stress suite's scenes (docs/STRESS.md): extreme values of each parameter class,
// one class at a time over a small base scene, and seeded random mixtures of all of them. Each
// scene is JSON, so it passes through parse_scene() like a user's; an extreme the parser rejects
// is recorded with its error and replaced by the most extreme value it accepts.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace scatter::stress {

// SCATTER_STRESS=long: more mixtures, larger images and grids (docs/STRESS.md).
enum class Mode { Quick, Long };
Mode mode_from_env();

// What a stress scene is built from; every member is one axis of the suite.
struct Params {
  double tau_voxel = 0.5;  // sigma_t x voxel size
  double albedo = 0.8;     // sigma_s / sigma_t
  double g = 0.3;
  double ior = 1;
  double scale = 1;               // the object's size and the camera distance scale by this
  std::string shape = "box";      // box [-1, 1]^3, sphere r 1, torus, slab (one voxel thick)
  std::string density = "const";  // const, layers, noise, blocker, shell (a one-voxel grid shell)
  std::string light = "front";    // see light_json() in stress_scenes.cpp
  double power = 1;               // directional irradiance, or point / spot intensity
  double color = 1;               // the lights' colour, all channels
  std::string camera = "axis";    // axis (+z), oblique, inside (in the medium)
  int voxels = 8;
  int image = 16;
};

struct StressCase {
  std::string name;   // "optical/tau=1e-06", unique
  std::string klass;  // optical, albedo, phase, ior, scale, shell, light, intensity, mixed
  Params params;
  nlohmann::json scene;
  std::vector<std::string> pipelines;  // the pipelines that render it
  std::string rejected;  // when an extreme was out of range: parse_scene's error for it
};

// The suite for `mode`; grid files (the shells) are written under `data_dir`.
std::vector<StressCase> stress_cases(Mode mode, const std::filesystem::path& data_dir);

// `p` with sigma_t lowered to the most the parser accepts (1e6 per unit), the albedo kept.
Params accepted(Params p);

// The scene JSON of `p` (sigma_t is clamped to what the parser accepts only by stress_cases()).
nlohmann::json scene_json(const Params& p, const std::filesystem::path& data_dir);

}  // namespace scatter::stress
