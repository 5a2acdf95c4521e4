// Shared by the single pipeline's tests: small scenes, the reference marcher's single term, and
// a fixture holding one pipeline for the whole test binary.
#pragma once

#include <gtest/gtest.h>

#include "../../test_util.hpp"
#include "pipelines/metrics.hpp"
#include "pipelines/reference/reference_pipeline.hpp"
#include "pipelines/single/single_pipeline.hpp"

namespace scatter::single_test {

// The homogeneous sphere of scenes/sphere.json, small enough for a unit test.
inline Scene small_sphere(int size = 64, int voxels = 32) {
  Scene s = load_scene(test::source_path("scenes/sphere.json"));
  s.width = s.height = size;
  s.voxels = voxels;
  return s;
}

// The paper's path (SH of transmittance); the exact_tr tests set it to 1, the default.
inline const Settings kQuick = {{"samples", 20000}, {"directions", 64}, {"exact_tr", 0}};

// A homogeneous box seen over a corner, lit from behind and the side (cube-torus without the
// torus): flat faces, edges and corners.
inline Scene small_box() {
  Scene s = load_scene(test::source_path("scenes/cube-torus.json"));
  s.medium.density = small_sphere().medium.density;  // constant
  s.width = s.height = 64;
  s.voxels = 32;
  return s;
}

// The reference marcher's single term for `s`, and the pixels its medium covers.
struct Expected {
  Image image;
  std::vector<uint8_t> mask;
};
inline Expected reference_single(const Scene& s) {
  ReferencePipeline ref(test::shared_gpu());
  return {ref.render(s, {Terms::Single, {{"step", 0.25}}, nullptr}).image,
          coverage_mask(s, voxelize(s, {.resolution = s.voxels}))};
}

// Sum of a's pixels over sum of b's.
inline double mean_ratio(const Image& a, const Image& b) {
  double x = 0, y = 0;
  for (size_t i = 0; i < a.rgb.size(); ++i) {
    x += a.rgb[i];
    y += b.rgb[i];
  }
  return x / y;
}

class SinglePipelineTest : public ::testing::Test {
 protected:
  static SinglePipeline& pipeline() {
    static SinglePipeline p(test::shared_gpu(), nullptr);
    return p;
  }
};


}  // namespace scatter::single_test
