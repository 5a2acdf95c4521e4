// scatterd bench --calibrate OUT.json: the budget planner's calibration table
// (pipelines/budget/calibration.hpp). Renders each calibration scene with every calibrated way
// and the reference, and writes each way's relative RMSE against the reference of its terms,
// its frame time, and the reference path tracer's noise per sample.
#pragma once

#include <string>
#include <vector>

#include "scene/scene.hpp"

namespace scatter::tools {

struct CalibrateOptions {
  std::string out;                  // the table to write (its version is the old file's + 1)
  std::vector<std::string> scenes;  // scene files instead of the calibration set (a Pareto run)
  int size = 48;                    // image side
  int voxels = 64;
  double target_noise = 0.01;  // the references' relative noise
  int max_spp = 4096;
  bool quick = false;  // a few scenes: to try the command, not to ship
  // Scenes `out` already holds (by name) keep their rows (errors, times, noise), classified
  // anew; only the others are rendered. For scenes added to the set: the rows kept are the same
  // as a full run's but for their times.
  bool reuse = false;
  std::string device;
};

struct NamedScene {
  std::string name;
  Scene scene;
  std::string twin;  // the scene of the set it is lit from further round than (CalibrationEntry)
};

// The calibration set (72 scenes). 46 lit from the front: constant-density spheres at albedo 0.6,
// 0.9, 0.99, tau 1, 4, 16, g -0.7, 0 and 0.7; boxes of noise density at albedo 0.6, 0.9, 0.99,
// tau 2 and 8 (and two at g -0.7 and 0.7); noise-density spheres at albedo 0.9, tau 2 and 8,
// g -0.7, 0 and 0.7; two dielectric spheres (ior 1.4); dielectric noise density (ior 1.4,
// albedo 0.9): spheres at tau 2 and 8, and 8 at g -0.7. And twins of 13 of them
// lit from the side and from behind: constant spheres at albedo 0.9, tau 1, 4, 16 and albedo
// 0.99, tau 4, 16, and at albedo 0.9, tau 4, g 0.7 and -0.7; noise spheres at tau 2 and 8, and
// tau 8 at g -0.7; the noise box at albedo 0.9, tau 8; the dielectric sphere at albedo 0.9; the
// dielectric noise sphere at tau 8. None of the shipped scenes is among them.
std::vector<NamedScene> calibration_scenes(const CalibrateOptions& o);

// Writes the table of the scenes it measured; 1 if one was left out (it could not be measured:
// its message says why), else 0.
int run_calibration(const CalibrateOptions& o);

}  // namespace scatter::tools
