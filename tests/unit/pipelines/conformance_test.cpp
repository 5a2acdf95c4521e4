// What every registered pipeline promises (pipelines/registry.hpp, pipelines/pipeline.hpp),
// instantiated over the registry: plan() is pure, the settings table is what validation enforces,
// the plan render() returns is the plan plan() predicted, the axis box's single term matches its
// closed form, and row 0 is the top of the image.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "../test_util.hpp"
#include "axis_box.hpp"
#include "core/errors.hpp"
#include "pipelines/registry.hpp"
#include "protocol/json_reader.hpp"

namespace scatter {
namespace {

// Settings that keep each pipeline's frames on the 9 x 9 box quick (single's bake is the slow one).
Settings quick(const std::string& pipeline) {
  if (pipeline == "single") return {{"samples", 4000}, {"directions", 32}};
  if (pipeline == "reference") return {{"spp", 48}};
  return {};
}

// Relative tolerance on the axis box's centre pixel (tests/unit/pipelines/axis_box.hpp) for the
// single term, per pipeline: the deterministic ones near their own tests' bounds, single's
// baked Gaussians and the reference marcher at 32 voxels looser.
double tolerance(const std::string& pipeline) {
  if (pipeline == "single") return 0.08;
  if (pipeline == "lbl") return 0.03;
  return 0.02;
}

// The phase's g on the box: lbl's view pass takes the phase as isotropic (its plan says so; the
// anisotropic view pass is open work), so it is held to the isotropic closed form.
double box_g(const std::string& pipeline) {
  return pipeline == "lbl" ? 0.0 : 0.3;
}

class Conformance : public ::testing::TestWithParam<std::string> {
 protected:
  const PipelineInfo& info() const { return pipeline_info(GetParam()); }
  RenderRequest request(Terms terms) const { return {terms, quick(GetParam()), nullptr}; }
};

std::string test_name(const ::testing::TestParamInfo<std::string>& p) {
  return p.param;
}

INSTANTIATE_TEST_SUITE_P(EveryPipeline, Conformance, ::testing::ValuesIn(pipeline_names()),
                         test_name);

TEST_P(Conformance, PlanTouchesNoGpu) {
  gpu::Gpu none({.unavailable = "plan() must not touch the GPU"});
  auto p = make_pipeline(GetParam(), none);
  EXPECT_EQ(p->name(), GetParam());
  Scene box = test::axis_box(0.8, 0.2, 0.3);
  for (Terms t : info().terms) {
    try {
      Plan plan = p->plan(box, request(t));
      EXPECT_FALSE(plan.stages.empty()) << to_string(t);
    } catch (const gpu::GpuError& e) {
      ADD_FAILURE() << GetParam() << " plan(" << to_string(t) << ") used the GPU: " << e.what();
    }
  }
}

TEST_P(Conformance, SettingsTableIsWhatValidationEnforces) {
  const PipelineInfo& i = info();
  EXPECT_THROW(i.validate({{"no_such_setting", 1}}), ValidationError);
  gpu::Gpu none({.unavailable = "validation must not touch the GPU"});
  auto p = make_pipeline(GetParam(), none);
  Scene box = test::axis_box(0.8, 0.2, 0.3);
  try {
    p->plan(box, {i.default_terms, {{"no_such_setting", 1}}, nullptr});
    ADD_FAILURE() << "plan() accepted an unknown setting";
  } catch (const ValidationError& e) {
    EXPECT_EQ(e.field(), "settings.no_such_setting");
  }
  for (const SettingInfo& s : i.settings) {
    SCOPED_TRACE(s.key);
    EXPECT_FALSE(s.doc.empty());
    EXPECT_LE(s.lo, s.def);
    EXPECT_LE(s.def, s.hi);
    EXPECT_NO_THROW(i.validate({{s.key, s.def}}));
    EXPECT_THROW(i.validate({{s.key, s.hi + std::max(1.0, std::abs(s.hi))}}), ValidationError);
    EXPECT_THROW(i.validate({{s.key, s.lo - std::max(1.0, std::abs(s.lo))}}), ValidationError);
    if (s.kind != SettingKind::Number) {
      EXPECT_THROW(i.validate({{s.key, s.lo + 0.5}}), ValidationError);
    }
  }
  for (const Quality& q : i.qualities) EXPECT_NO_THROW(i.validate(q.settings)) << q.name;
  EXPECT_TRUE(std::find(i.terms.begin(), i.terms.end(), i.default_terms) != i.terms.end());
}

// The plan render() returns is the plan plan() gave just before it: the same stages, run or
// skipped alike; on the second, unchanged frame too (what is kept is reused, and said so).
TEST_P(Conformance, RenderRunsThePlannedStages) {
  auto p = make_pipeline(GetParam(), test::shared_gpu());
  Scene box = test::axis_box(0.8, 0.2, 0.3);
  const RenderRequest r = request(info().default_terms);
  for (int frame = 0; frame < 2; ++frame) {
    SCOPED_TRACE("frame " + std::to_string(frame));
    Plan planned = p->plan(box, r);
    Plan ran = p->render(box, r).plan;
    ASSERT_EQ(planned.stages.size(), ran.stages.size());
    for (size_t k = 0; k < ran.stages.size(); ++k) {
      EXPECT_EQ(planned.stages[k].name, ran.stages[k].name);
      EXPECT_EQ(planned.stages[k].run, ran.stages[k].run)
          << ran.stages[k].name << ": " << ran.stages[k].reason;
    }
    EXPECT_EQ(planned.pipeline, ran.pipeline);
  }
}

TEST_P(Conformance, AxisBoxSingleTermMatchesClosedForm) {
  if (!info().renders(Terms::Single))
    GTEST_SKIP() << GetParam() << " does not render the single term";
  const double ss = 0.8, sa = 0.2, g = box_g(GetParam());
  auto p = make_pipeline(GetParam(), test::shared_gpu());
  Image img = p->render(test::axis_box(ss, sa, g), request(Terms::Single)).image;
  const double expected = test::axis_box_radiance(ss, sa, g);
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(img.at(4, 4)[c], expected, tolerance(GetParam()) * expected) << c;
}

// The same box seen from inside, on its axis halfway between the centre and the lit face: every
// view ray starts in the medium, and the first surface depth peeling finds is where it leaves.
TEST_P(Conformance, AxisBoxSingleTermFromInside) {
  if (!info().renders(Terms::Single))
    GTEST_SKIP() << GetParam() << " does not render the single term";
  const double ss = 0.8, sa = 0.2, g = box_g(GetParam()), z0 = 0.5;
  Scene box = test::axis_box(ss, sa, g);
  box.camera.position = {0, 0, z0};
  box.camera.target = {0, 0, -1};
  box.camera.fov_deg = 60;
  auto p = make_pipeline(GetParam(), test::shared_gpu());
  Image img = p->render(box, request(Terms::Single)).image;
  const double expected = test::axis_box_radiance(ss, sa, g, z0);
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(img.at(4, 4)[c], expected, tolerance(GetParam()) * expected) << c;
}

// The same box seen from a point on its faces: on the lit face looking in (as from outside), and
// on the opposite face looking in towards the light, where every point of the axis lies 2 from
// the eye and the lit face together: L = sigma_s HG(1) E 2 exp(-2 sigma_t). The eye's own face
// is edge-on to it (never drawn): a hair ahead of the eye is inside.
TEST_P(Conformance, AxisBoxSingleTermFromItsFaces) {
  if (!info().renders(Terms::Single))
    GTEST_SKIP() << GetParam() << " does not render the single term";
  const double ss = 0.8, sa = 0.2, st = ss + sa, g = box_g(GetParam());
  auto p = make_pipeline(GetParam(), test::shared_gpu());
  Scene box = test::axis_box(ss, sa, g);
  box.camera.fov_deg = 60;
  box.camera.position = {0, 0, 1};
  box.camera.target = {0, 0, -1};
  const double top = test::axis_box_radiance(ss, sa, g, 1);
  Image img = p->render(box, request(Terms::Single)).image;
  EXPECT_NEAR(img.at(4, 4).x, top, tolerance(GetParam()) * top) << "on the lit face";
  box.camera.position = {0, 0, -1};
  box.camera.target = {0, 0, 1};
  const double forward = (1 - g * g) / (4 * std::numbers::pi * std::pow(1 - g, 3));
  const double bottom = ss * forward * 2.0 * 2 * std::exp(-2 * st);
  img = p->render(box, request(Terms::Single)).image;
  EXPECT_NEAR(img.at(4, 4).x, bottom, tolerance(GetParam()) * bottom) << "on the far face";
}

// The box seen from below its centre sits in the image's upper half: rows 0-3 hold more light
// than rows 5-8.
TEST_P(Conformance, RowZeroIsTheTop) {
  Scene box = test::axis_box(0.8, 0.2, 0.3);
  box.camera.position = {0, -1.2, 4};
  box.camera.target = {0, -1.2, 0};
  box.width = box.height = 9;
  auto p = make_pipeline(GetParam(), test::shared_gpu());
  Image img = p->render(box, request(info().default_terms)).image;
  double top = 0, bottom = 0;
  for (int y = 0; y < 9; ++y)
    for (int x = 0; x < 9; ++x) {
      Vec3 v = img.at(x, y);
      (y < 4 ? top : y > 4 ? bottom : top) += y == 4 ? 0 : v.x + v.y + v.z;
    }
  EXPECT_GT(top, 0);
  EXPECT_GT(top, 4 * bottom) << "top " << top << ", bottom " << bottom;
}

}  // namespace
}  // namespace scatter
