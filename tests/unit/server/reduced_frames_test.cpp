#include "server/reduced_frames.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "pipelines/registry.hpp"

namespace scatter::server {
namespace {

// Frames over the budget shrink by sqrt(budget / ms) a side, down to the smallest scale; once
// there and still over, the draft frame settings come in; frames under it grow back to the
// largest. Pipelines are steered apart.
TEST(ReducedFrames, SizeFollowsTheBudgetThenDraftSettings) {
  ReducedFrames r;
  const double budget = ReducedFrames::kFrameBudgetMs;
  EXPECT_EQ(r.choice("thickness").scale, ReducedFrames::kStartScale);
  r.measured("thickness", 4 * budget);  // twice the side's cost: half the side
  EXPECT_DOUBLE_EQ(r.choice("thickness").scale, ReducedFrames::kStartScale / 2);
  EXPECT_FALSE(r.choice("thickness").draft);
  EXPECT_EQ(r.settings("thickness", {}), Settings{});
  r.measured("thickness", 2 * budget);  // at the smallest and still over: draft
  EXPECT_EQ(r.choice("thickness").scale, ReducedFrames::kMinScale);
  EXPECT_TRUE(r.choice("thickness").draft);
  Settings draft = r.settings("thickness", {{"steps", 40}});
  for (const Quality& q : pipeline_info("thickness").qualities)
    if (q.name == "draft")
      for (const auto& [key, value] : q.settings) EXPECT_EQ(draft.at(key), value) << key;
  r.measured("thickness", budget / 16);  // fast again: as large as allowed
  EXPECT_EQ(r.choice("thickness").scale, ReducedFrames::kMaxScale);
  EXPECT_EQ(r.choice("surface").scale, ReducedFrames::kStartScale);  // its own
  // Nothing measured: unchanged.
  r.measured("surface", 0);
  EXPECT_EQ(r.choice("surface").scale, ReducedFrames::kStartScale);
}

// Only frame-shaping settings of the draft preset: none that would make another bake product.
TEST(ReducedFrames, DraftTakesOnlyTheFrameShapingSettings) {
  const PipelineInfo& single = pipeline_info("single");
  Settings s = with_draft("single", {});
  for (const auto& [key, value] : s) {
    bool frame = false;
    for (const SettingInfo& setting : single.settings)
      if (setting.key == key) frame = setting.shapes.what == Shapes::What::Frame;
    EXPECT_TRUE(frame) << key;
  }
  EXPECT_EQ(s.count("samples"), 0u);  // a bake setting of single's draft
}

}  // namespace
}  // namespace scatter::server
