// The OpenCL library the pipelines' kernels share (kernels/common/), and the file lists for
// gpu::ClContext::program that start with it.
#pragma once

#include <initializer_list>
#include <string>
#include <vector>

namespace scatter {

// The library's files, each after those whose names it uses: rng (PCG32), dda (the voxel medium,
// grid traversal, exact optical depth), phase (Henyey-Greenstein, PI, INV_4PI), fresnel, lights,
// camera, tracking (delta and ratio tracking with per-brick majorants); then `files`, a program's
// own, in order.
inline std::vector<std::string> with_cl_library(std::initializer_list<std::string> files) {
  std::vector<std::string> all = {"kernels/common/rng.cl",     "kernels/common/dda.cl",
                                  "kernels/common/phase.cl",   "kernels/common/fresnel.cl",
                                  "kernels/common/lights.cl",  "kernels/common/camera.cl",
                                  "kernels/common/tracking.cl"};
  all.insert(all.end(), files);
  return all;
}

}  // namespace scatter
