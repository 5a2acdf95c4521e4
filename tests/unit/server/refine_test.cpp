#include "server/refine.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "../test_util.hpp"
#include "pipelines/budget/calibration.hpp"
#include "pipelines/metrics.hpp"

namespace scatter::server {
namespace {

using Stage = RefineStep::Stage;
using State = Refinement::State;

Scene sphere() {
  return parse_scene(test::minimal_scene(), ".");
}

// A render's result as a pipeline would give it: a flat image of 1, the stage time, and for a
// Monte Carlo pass a standard error c / sqrt(spp) per value.
RenderResult result(double seconds, std::optional<double> estimate = std::nullopt, int spp = 0,
                    double c = 0) {
  RenderResult r;
  r.image = Image(4, 4);
  std::fill(r.image.rgb.begin(), r.image.rgb.end(), 1.f);
  r.timings = {{"trace", seconds * 1000}};
  r.error_estimate = estimate;
  if (spp > 0) {
    r.std_error = Image(4, 4);
    std::fill(r.std_error->rgb.begin(), r.std_error->rgb.end(), float(c / std::sqrt(spp)));
  }
  return r;
}

TEST(RefineTest, AFrameIsWorthSendingOnceItsEstimateDroppedByATenth) {
  EXPECT_TRUE(worth_sending(0.09, 0.1));
  EXPECT_TRUE(worth_sending(0.01, 0.1));
  EXPECT_FALSE(worth_sending(0.0901, 0.1));
  EXPECT_FALSE(worth_sending(0.2, 0.1));  // worse
  EXPECT_TRUE(worth_sending(std::nullopt, 0.1));
  EXPECT_TRUE(worth_sending(0.5, std::nullopt));
}

TEST(RefineTest, HigherQualitiesAreThoseAboveTheSessionsAndReplaceItsPresetsKeys) {
  const PipelineInfo& t = pipeline_info("thickness");  // draft, normal ({}), high
  Settings high = t.qualities[2].settings, draft = t.qualities[0].settings;
  auto above = higher_qualities(t, {});  // the defaults: normal
  ASSERT_EQ(above.size(), 1u);
  EXPECT_EQ(above[0].first, "high");
  EXPECT_EQ(above[0].second, high);
  above = higher_qualities(t, draft);  // normal drops draft's keys, high replaces them
  ASSERT_EQ(above.size(), 2u);
  EXPECT_EQ(above[0].first, "normal");
  EXPECT_EQ(above[0].second, Settings{});
  EXPECT_EQ(above[1].second, high);
  EXPECT_TRUE(higher_qualities(t, high).empty());
  // Settings of the session's own beyond the preset's are kept.
  Settings own = draft;
  own["other"] = 2;
  above = higher_qualities(t, own);
  ASSERT_EQ(above.size(), 2u);
  EXPECT_EQ(above[1].second.at("other"), 2);
  EXPECT_TRUE(higher_qualities(pipeline_info("surface"), {}).empty());  // normal only
}

TEST(RefineTest, PassesAimAtTheirTimeInMultiplesOfThree) {
  EXPECT_EQ(next_pass_spp(30, 0.5, 0, 1.0), 60);
  EXPECT_EQ(next_pass_spp(30, 2.0, 0, 1.0), 15);
  EXPECT_EQ(next_pass_spp(30, 0.4, 0.2, 1.0), 60);  // 0.8 s left to sample after the rest
  EXPECT_EQ(next_pass_spp(30, 1e-3, 0, 1.0), 120);  // at most 4x more
  EXPECT_EQ(next_pass_spp(30, 100, 0, 1.0), 15);    // at most 2x fewer
  EXPECT_EQ(next_pass_spp(30, 0.1, 2.0, 1.0), 15);  // the rest alone is over: fewer
  EXPECT_EQ(next_pass_spp(kMinPassSpp, 100, 0, 1.0), kMinPassSpp);
  EXPECT_EQ(next_pass_spp(kMaxPassSpp, 0.01, 0, 1.0), kMaxPassSpp);
  EXPECT_EQ(next_pass_spp(30, 0.7, 0, 1.0) % 3, 0);
}

TEST(RefineTest, AStillViewGoesFullThenHighThenAccumulatedReferencePasses) {
  RefineOptions o{.floor = 0.0501, .max_passes = 100, .pass_seconds = 1.0};
  Refinement r(sphere(), "thickness", "", {}, o);
  auto step = r.next();
  ASSERT_TRUE(step);
  EXPECT_EQ(step->stage, Stage::Full);
  EXPECT_EQ(step->terms, "single");  // thickness renders only the single term
  RenderResult full = result(0.1);
  auto out = r.take(*step, full);
  EXPECT_TRUE(out.send);
  EXPECT_EQ(out.state, State::Converging);
  EXPECT_EQ(r.describe(*step, out.state)["stage"], "full");

  step = r.next();
  ASSERT_TRUE(step);
  EXPECT_EQ(step->stage, Stage::Quality);
  EXPECT_EQ(step->quality, "high");
  EXPECT_EQ(step->settings, pipeline_info("thickness").qualities[2].settings);
  RenderResult high = result(0.2);
  EXPECT_TRUE(r.take(*step, high).send);  // no estimate either: nothing says it is worse

  // Reference passes of the single term by Monte Carlo, a new seed each, error c / sqrt(N): 0.2
  // after the first pass (its spp comes from the cost estimate; each pass takes the 1 s aimed at,
  // so the spp stay), 0.2 / sqrt(k) after k.
  double c = 0;
  std::vector<int> sent_at;
  std::vector<double> sent;
  int passes = 0;
  long long spp = 0;
  while ((step = r.next())) {
    ASSERT_EQ(step->stage, Stage::Reference);
    EXPECT_EQ(step->pipeline, "reference");
    EXPECT_EQ(step->settings.at("mc"), 1);
    EXPECT_EQ(step->settings.at("seed"), 1 + step->pass);
    EXPECT_EQ(step->spp % 3, 0);
    EXPECT_EQ(step->pass, ++passes);
    spp += step->spp;
    if (c == 0) c = 0.2 * std::sqrt(double(step->spp));
    RenderResult pass = result(1.0, std::nullopt, step->spp, c);
    out = r.take(*step, pass);
    ASSERT_TRUE(pass.error_estimate);
    EXPECT_NEAR(*pass.error_estimate, c / std::sqrt(double(spp)), 1e-6);  // accumulated
    EXPECT_EQ(r.reference_samples(), spp);
    if (out.send) {
      sent_at.push_back(step->pass);
      sent.push_back(*out.estimate);
      EXPECT_EQ(r.describe(*step, out.state)["spp"], spp);
    }
    if (out.state != State::Converging) break;
  }
  EXPECT_EQ(out.state, State::Converged);
  EXPECT_TRUE(r.over());
  ASSERT_GE(sent.size(), 2u);
  // Over a frame without an estimate a pass goes once under 0.09 (an assumed 0.1, less a tenth);
  // each next one only a tenth under the one before; the last, at or under the floor, once it
  // improves at all.
  EXPECT_LE(sent[0], 0.09);
  for (size_t i = 1; i + 1 < sent.size(); ++i) EXPECT_LE(sent[i], 0.9 * sent[i - 1]);
  EXPECT_LT(sent.back(), sent[sent.size() - 2]);
  EXPECT_LE(sent.back(), o.floor);
  EXPECT_EQ(passes, 16);                                        // 0.2 / sqrt(16) = 0.05
  EXPECT_EQ(sent_at, (std::vector<int>{5, 7, 9, 12, 15, 16}));  // the others not worth a frame
}

TEST(RefineTest, EstimatedFramesAreSentOnlyWhenBetterByATenth) {
  // Two reference passes of the same spp and standard error se: 0.27 gives se after the first,
  // se / sqrt(2) = 0.191 after the second (better than 0.2, not by a tenth); 0.3 gives 0.212.
  for (double se : {0.27, 0.3}) {
    Refinement r(sphere(), "thickness", "single", {}, {.floor = 0.01, .max_passes = 2});
    RenderResult full = result(0.1, 0.2);
    EXPECT_TRUE(r.take(*r.next(), full).send);  // the full frame always
    RenderResult high = result(0.1, 0.19);
    EXPECT_FALSE(r.take(*r.next(), high).send);  // 0.19 > 0.9 x 0.2
    EXPECT_EQ(r.last_sent(), 0.2);
    auto step = r.next();
    RenderResult first = result(1.0, std::nullopt, step->spp, se * std::sqrt(step->spp));
    EXPECT_FALSE(r.take(*step, first).send);  // worse than what is shown
    step = r.next();
    RenderResult second = result(1.0, std::nullopt, step->spp, se * std::sqrt(step->spp));
    auto out = r.take(*step, second);  // the passes run out
    EXPECT_NEAR(*out.estimate, se / std::sqrt(2.0), 1e-6);
    EXPECT_EQ(out.state, State::Done);
    EXPECT_EQ(out.send, se < 0.28) << "the last goes when it improves at all";
    EXPECT_FALSE(r.next());
  }
}

TEST(RefineTest, WhatNeedsNoRefiningEndsAfterTheFullFrame) {
  // Surface: one quality and no reference term.
  Refinement surface(sphere(), "surface", "", {}, {});
  RenderResult full = result(0.1);
  auto out = surface.take(*surface.next(), full);
  EXPECT_TRUE(out.send);
  EXPECT_EQ(out.state, State::Done);
  // The reference's marcher: exact up to its step, refined by the finer step of "high" only.
  Refinement marcher(sphere(), "reference", "single", {}, {});
  EXPECT_TRUE(marcher.take(*marcher.next(), full).send);
  auto step = marcher.next();
  ASSERT_TRUE(step);
  EXPECT_EQ(step->quality, "high");
  EXPECT_EQ(marcher.take(*step, full).state, State::Done);
  // Steps the server's time limit would refuse, or past the step limit, are left out.
  Refinement limited(sphere(), "thickness", "", {}, {.max_render_s = 1e-9});
  EXPECT_EQ(limited.take(*limited.next(), full).state, State::Done);
  Refinement brief(sphere(), "thickness", "", {}, {.step_max_s = 1e-9});  // each step short
  EXPECT_EQ(brief.take(*brief.next(), full).state, State::Done);
  // An estimate already at the floor.
  Refinement good(sphere(), "thickness", "", {}, {.floor = 0.05});
  RenderResult exact = result(0.1, 0.01);
  EXPECT_EQ(good.take(*good.next(), exact).state, State::Converged);
}

// A composite: after the full frame of the single term, the multiple term from psf at half the
// size, added to it (resampled) and sent; the higher quality's frame keeps it; the reference
// passes are then of all terms, not the single term alone.
TEST(RefineTest, ACompositeAddsTheMultipleTermToTheStillFrames) {
  Composite c{"psf", {{"step", 2}}, 0.5};
  RefineOptions o{.floor = 0.01, .max_passes = 4, .composite = c};
  Refinement r(sphere(), "thickness", "single", {}, o);
  auto step = r.next();
  ASSERT_EQ(step->stage, Stage::Full);
  RenderResult full = result(0.1);  // 4 x 4 of 1
  EXPECT_TRUE(r.take(*step, full).send);
  step = r.next();
  ASSERT_TRUE(step);
  EXPECT_EQ(step->stage, Stage::Multiple);
  EXPECT_EQ(step->pipeline, "psf");
  EXPECT_EQ(step->terms, "multiple");
  EXPECT_EQ(step->settings, c.settings);
  EXPECT_EQ(step->scale, 0.5);
  RenderResult multiple;  // 2 x 2, rows of 0.5 and 1.5
  multiple.image = Image(2, 2);
  multiple.image.rgb = {0.5f, 0.5f, 0.5f, 0.5f, 0.5f, 0.5f, 1.5f, 1.5f, 1.5f, 1.5f, 1.5f, 1.5f};
  multiple.error_estimate = 0.3;  // psf's own: not the composite's
  auto out = r.take(*step, multiple);
  EXPECT_TRUE(out.send);
  ASSERT_TRUE(out.estimate);  // the calibrated error of thickness + psf's draft, not psf's own
  EXPECT_DOUBLE_EQ(*out.estimate, *composite_error(sphere(), "thickness", {}, c));
  EXPECT_NE(*out.estimate, 0.3);
  ASSERT_EQ(multiple.image.width, 4);
  ASSERT_EQ(multiple.image.height, 4);
  // Rows 0..3 sample the small image's rows at -0.25, 0.25, 0.75, 1.25: 0.5, 0.75, 1.25, 1.5.
  const float rows[] = {0.5f, 0.75f, 1.25f, 1.5f};
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) EXPECT_FLOAT_EQ(multiple.image.at(x, y)[1], 1 + rows[y]);
  EXPECT_EQ(r.describe(*step, out.state)["stage"], "multiple");
  EXPECT_EQ(r.describe(*step, out.state)["pipeline"], "psf");
  step = r.next();
  ASSERT_EQ(step->stage, Stage::Quality);
  RenderResult high = result(0.2);
  auto shown = r.take(*step, high);
  EXPECT_FLOAT_EQ(high.image.at(0, 3)[0], 2.5f);  // its single term plus the multiple term
  // Sent without an estimate, it keeps the composite's as the mark the passes must beat by a
  // tenth: the page never shows a rising error.
  EXPECT_TRUE(shown.send);
  EXPECT_FALSE(shown.estimate);
  ASSERT_TRUE(r.last_sent());
  EXPECT_DOUBLE_EQ(*r.last_sent(), *out.estimate);
  step = r.next();
  ASSERT_TRUE(step);
  EXPECT_EQ(step->stage, Stage::Reference);
  EXPECT_EQ(step->terms, "all");
  EXPECT_EQ(step->settings.count("mc"), 0u);
  // A multiple term the limits would refuse is left out: the refinement is as without one.
  Refinement brief(sphere(), "thickness", "single", {}, {.max_render_s = 1e-9, .composite = c});
  RenderResult again = result(0.1);
  EXPECT_EQ(brief.take(*brief.next(), again).state, State::Done);
}

// A composite whose two parts are calibrated presets carries the table's error for their sum
// (also the web client's default, thickness with psf's draft); one that is not carries none.
TEST(RefineTest, ACompositeFrameCarriesItsCalibratedError) {
  Composite c{"psf", {}, 0.5};  // psf's normal quality
  auto expected = CalibrationTable::shipped().predict_error(classify(sphere(), Terms::All),
                                                            "thickness:normal+psf:normal");
  ASSERT_TRUE(expected);
  ASSERT_EQ(composite_error(sphere(), "thickness", {}, c), expected->value);
  Refinement r(sphere(), "thickness", "single", {},
               {.floor = 0.01, .max_passes = 4, .composite = c});
  RenderResult full = result(0.1);
  r.take(*r.next(), full);
  auto step = r.next();
  ASSERT_EQ(step->stage, Stage::Multiple);
  RenderResult multiple;
  multiple.image = Image(2, 2);
  multiple.error_estimate = 0.3;
  auto out = r.take(*step, multiple);
  ASSERT_TRUE(out.estimate);
  EXPECT_DOUBLE_EQ(*out.estimate, expected->value);
  auto draft = CalibrationTable::shipped().predict_error(classify(sphere(), Terms::All),
                                                         "thickness:normal+psf:draft");
  ASSERT_TRUE(draft);
  EXPECT_EQ(composite_error(sphere(), "thickness", {}, {"psf", {{"step", 2}}, 0.5}), draft->value);
  EXPECT_FALSE(composite_error(sphere(), "thickness", {}, {"psf", {{"step", 3}}, 0.5}));
  EXPECT_FALSE(composite_error(sphere(), "thickness", {{"steps", 7}}, c));  // not a preset
}

TEST(RefineTest, TheReferencesOwnMonteCarloSkipsItsPresetsAndKeepsItsSettings) {
  Refinement r(sphere(), "reference", "all", {{"max_depth", 8}, {"seed", 5}}, {});
  RenderResult full = result(1.0, 0.3, 64, 1.0);
  r.take(*r.next(), full);
  auto step = r.next();
  ASSERT_TRUE(step);
  EXPECT_EQ(step->stage, Stage::Reference);
  EXPECT_EQ(step->settings.at("max_depth"), 8);
  EXPECT_EQ(step->settings.at("seed"), 6);
  EXPECT_EQ(step->settings.count("mc"), 0u);
}

}  // namespace
}  // namespace scatter::server
