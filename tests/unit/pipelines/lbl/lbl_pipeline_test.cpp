#include "pipelines/lbl/lbl_pipeline.hpp"

#include <gtest/gtest.h>

#include <numbers>

#include "../../test_util.hpp"
#include "pipelines/metrics.hpp"
#include "protocol/json_reader.hpp"

namespace scatter {
namespace {

// Box [-1, 1]^3 lit along -z by a directional light, seen from +z on the axis: the singly
// scattered radiance on the centre ray is sigma_s E (1 - exp(-4 sigma_t)) / (4 pi 2 sigma_t)
// (isotropic phase).
Scene axis_box(double sigma_s, double sigma_a, int voxels) {
  nlohmann::json j = test::minimal_scene();
  j["mesh"] = {{"shape", "box"}, {"size", {2, 2, 2}}};
  j["medium"] = {{"sigma_s", sigma_s}, {"sigma_a", sigma_a}};
  j["lights"] = {{{"type", "directional"}, {"direction", {0, 0, -1}}, {"irradiance", 2.0}}};
  j["camera"] = {{"position", {0, 0, 4}}, {"fov_deg", 30}};
  j["image"] = {{"width", 9}, {"height", 9}};
  j["voxels"] = voxels;
  return parse_scene(j, ".");
}

const StagePlan* stage(const Plan& p, const std::string& name) {
  for (const auto& s : p.stages)
    if (s.name == name) return &s;
  return nullptr;
}

TEST(LblPipeline, SingleTermMatchesClosedFormOnTheAxis) {
  LblPipeline p(test::shared_gpu());
  for (double st : {0.5, 2.0}) {
    Scene s = axis_box(0.8 * st, 0.2 * st, 32);
    double expected = 0.8 * st * 2.0 * -std::expm1(-4 * st) / (4 * std::numbers::pi * 2 * st);
    Vec3 got = p.render(s, {Terms::Single, {}}).image.at(4, 4);
    EXPECT_NEAR(got.x, expected, 0.02 * expected) << "sigma_t " << st;
  }
}

}  // namespace
}  // namespace scatter
