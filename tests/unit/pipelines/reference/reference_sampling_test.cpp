// The path tracer's sampling against time and a budget: max_seconds, a caller's time limit, and a
// budget sampled as far as its measured standard error says it needs.
#include <gtest/gtest.h>

#include <cmath>

#include "../../test_util.hpp"
#include "pipelines/metrics.hpp"
#include "pipelines/reference/reference_pipeline.hpp"
#include "reference_render.hpp"

namespace scatter {
namespace {

using test::reference_render;
using test::small_scene;

// max_seconds stops the path tracer's passes: far fewer samples than asked (a million would take
// hours), at least three, the plan says how many, and the image is their mean: the same as a
// render of just those samples (the same seed and batches; the passes add in another order).
// Its cost estimate stops there too, naming the setting.
TEST(ReferencePipeline, MaxSecondsStopsThePassesAtTheSamplesDrawn) {
  Scene s = small_scene("sphere", 16, 16);
  const Settings stopped{{"spp", 1 << 20}, {"max_seconds", 0.3}, {"seed", 3}, {"batch", 4}};
  RenderResult r = reference_render(s, Terms::Multiple, stopped);
  const std::string reason = plan_stage(r.plan, "trace").reason;
  const std::string of = " of " + std::to_string(1 << 20) + " samples per pixel";
  ASSERT_NE(reason.find(of), std::string::npos) << reason;
  EXPECT_NE(reason.find("max_seconds"), std::string::npos) << reason;
  const int drawn = std::stoi(reason.substr(0, reason.find(of)));
  EXPECT_GE(drawn, 3);
  EXPECT_LT(drawn, 1 << 20);
  RenderResult same =
      reference_render(s, Terms::Multiple, {{"spp", drawn}, {"seed", 3}, {"batch", 4}});
  ASSERT_EQ(same.image.rgb.size(), r.image.rgb.size());
  for (size_t i = 0; i < r.image.rgb.size(); ++i) {
    EXPECT_NEAR(r.image.rgb[i], same.image.rgb[i], 1e-5 * (1 + std::abs(same.image.rgb[i])));
    EXPECT_NEAR(r.std_error->rgb[i], same.std_error->rgb[i],
                1e-4 * (1 + std::abs(same.std_error->rgb[i])));
  }
  ASSERT_TRUE(r.error_estimate);
  EXPECT_GT(*r.error_estimate, 0);

  // The estimate: the upload, then at most one sample past max_seconds.
  auto estimate = [&](Settings set) {
    return ReferencePipeline::estimate(s, {Terms::Multiple, std::move(set), {}}, false);
  };
  const CostEstimate all = estimate({{"spp", 1 << 20}}), three = estimate({{"spp", 3}});
  const CostEstimate cut = estimate({{"spp", 1 << 20}, {"max_seconds", 5}});
  const double per_sample = (all.seconds - three.seconds) / ((1 << 20) - 3);
  EXPECT_EQ(all.time_field, "settings.spp");
  EXPECT_EQ(cut.time_field, "settings.max_seconds");
  EXPECT_NEAR(cut.seconds, three.seconds - 3 * per_sample + 5 + per_sample, 1e-6);
}

// The samples drawn, from the trace stage's reason ("N samples per pixel: ..." or "N of M ...").
int samples_drawn(RenderResult& r) {
  return std::stoi(plan_stage(r.plan, "trace").reason);
}

// With a budget the path tracer samples as many as its standard error says the budget needs,
// past 8x the expected count where that count was far too low (a calibration outside its
// range): here a budget that needs about 25x the 12 samples asked for (31x with the margin the
// passes aim at) is met.
TEST(ReferencePipeline, ABudgetTakesTheSamplesItsStandardErrorSaysItNeeds) {
  Scene s = small_scene("sphere", 16, 16);
  ReferencePipeline p(test::shared_gpu());
  RenderResult twelve = p.render(s, {Terms::Multiple, {{"spp", 12}, {"seed", 3}}});
  ASSERT_TRUE(twelve.error_estimate);
  const double budget = *twelve.error_estimate * std::sqrt(12.0 / 300);
  RenderResult r = p.render(s, {Terms::Multiple, {{"spp", 12}, {"seed", 3}}, {}, budget});
  const std::string reason = plan_stage(r.plan, "trace").reason;
  ASSERT_TRUE(r.error_estimate);
  // Met with the scatter of one image's error taken two deviations up (its standard error is
  // under the aim by more than the scatter's factor).
  const double scatter = error_scatter(*r.std_error);
  EXPECT_GT(scatter, 0.05) << reason;
  EXPECT_LE(*r.error_estimate * std::sqrt(1 + 2 * scatter), RenderRequest::kBudgetMargin * budget)
      << reason;
  EXPECT_NE(reason.find("with the scatter of one image's error"), std::string::npos) << reason;
  EXPECT_GT(samples_drawn(r), 8 * 12) << reason;
  EXPECT_NE(reason.find("under the budget"), std::string::npos) << reason;
  // auto's default budget (none asked for) stops at 8x.
  RenderRequest soft{Terms::Multiple, {{"spp", 12}, {"seed", 3}}, {}, budget};
  soft.soft_budget = true;
  RenderResult d = p.render(s, soft);
  EXPECT_EQ(samples_drawn(d), 8 * 12) << plan_stage(d.plan, "trace").reason;
  EXPECT_NE(plan_stage(d.plan, "trace").reason.find("the default budget's most"), std::string::npos)
      << plan_stage(d.plan, "trace").reason;
}

// A caller's time limit (the daemon's --max-render-s) stops the passes in time to return the
// samples drawn, with or without a budget, and the plan says why.
TEST(ReferencePipeline, ATimeLimitStopsThePassesInTime) {
  Scene s = small_scene("sphere", 16, 16);
  ReferencePipeline p(test::shared_gpu());
  RenderRequest budget{Terms::Multiple, {{"spp", 600}}, {}, 1e-4};  // 64x: tens of seconds
  budget.time_limit_s = 0.5;
  RenderResult r = p.render(s, budget);
  std::string reason = plan_stage(r.plan, "trace").reason;
  EXPECT_NE(reason.find("still over, at the render's time limit (0.5 s)"), std::string::npos)
      << reason;
  EXPECT_GE(samples_drawn(r), 3);
  ASSERT_TRUE(r.error_estimate);
  EXPECT_GT(*r.error_estimate, 1e-4);

  RenderRequest many{Terms::Multiple, {{"spp", 1 << 20}}, {}};
  many.time_limit_s = 0.5;
  RenderResult m = p.render(s, many);
  reason = plan_stage(m.plan, "trace").reason;
  EXPECT_NE(reason.find(" of 1048576 samples per pixel, what the render's time limit (0.5 s)"),
            std::string::npos)
      << reason;
  EXPECT_LT(samples_drawn(m), 1 << 20);
}

}  // namespace
}  // namespace scatter
