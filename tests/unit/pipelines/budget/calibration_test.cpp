// The budget planner's scene classes and the calibration table's predictions, on a hand-made
// table (the choice: planner_test.cpp; auto on the GPU: auto_budget_test.cpp).
#include "pipelines/budget/calibration.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "budget_scenes.hpp"
#include "budget_table.hpp"
#include "pipelines/budget/scene_class.hpp"

namespace scatter {
namespace {

using test::entry;
using test::sphere_scene;
using test::table;

TEST(SceneClass, ReadsTheMediumAndTheObjectsOpticalSize) {
  Scene s = sphere_scene(0.95, 6, 0.3);
  SceneClass c = classify(s, Terms::All);
  EXPECT_TRUE(c.homogeneous);
  EXPECT_TRUE(c.index_matched);
  EXPECT_NEAR(c.albedo, 0.95, 1e-9);
  EXPECT_NEAR(c.tau, 6, 0.1);  // sigma_t 3 x diameter 2 (the mesh's bounds)
  EXPECT_DOUBLE_EQ(c.g, 0.3);
  EXPECT_FALSE(c.light_inside);
  s.lights[0].position = {0.1, 0, 0};
  EXPECT_TRUE(classify(s, Terms::All).light_inside);
}

// The lights' facing: the cosine between the directions from the object's centre to a light and
// to the camera, averaged with the irradiance at the centre as weights.
TEST(SceneClass, SaysFromWhereTheLightsShine) {
  Scene s = sphere_scene(0.9, 4, 0);  // light at (3, 3, 3), camera at (0, 0, 4)
  EXPECT_NEAR(classify(s, Terms::All).facing, 1 / std::sqrt(3.0), 1e-9);
  s.lights[0].position = {0, 0, -5};
  EXPECT_NEAR(classify(s, Terms::All).facing, -1, 1e-9);
  Light front = s.lights[0];
  front.position = {0, 0, 5};
  front.intensity = s.lights[0].intensity / 3;
  s.lights.push_back(front);  // a third of the irradiance from the front
  EXPECT_NEAR(classify(s, Terms::All).facing, -0.5, 1e-9);
  Light inside = front;
  inside.position = {0.1, 0, 0};
  inside.intensity = 1e6;
  s.lights.push_back(inside);  // left out
  EXPECT_NEAR(classify(s, Terms::All).facing, -0.5, 1e-9);
  Light spot = s.lights[0];  // behind, but turned away from the object: no weight
  spot.type = Light::Type::Spot;
  spot.direction = {0, 0, -1};
  s.lights = {front, spot};
  EXPECT_NEAR(classify(s, Terms::All).facing, 1, 1e-9);
  s.lights[1].direction = {0, 0, 1};  // turned to it
  EXPECT_LT(classify(s, Terms::All).facing, 0);
  Scene within = s;
  within.camera.position = {0.2, 0, 0};  // inside the bounds: no side is lit or dark to it
  EXPECT_EQ(classify(within, Terms::All).facing, 1);
  Light sun;
  sun.type = Light::Type::Directional;
  sun.direction = {0, 0, -1};  // travels away from the camera: lights the side it sees
  s.lights = {sun};
  EXPECT_NEAR(classify(s, Terms::All).facing, 1, 1e-9);
  EXPECT_EQ(describe(classify(s, Terms::All)).find("lit from"), std::string::npos);
  s.lights[0].direction = {1, 0, 0};
  EXPECT_NE(describe(classify(s, Terms::All)).find("lit from the side (facing 0)"),
            std::string::npos)
      << describe(classify(s, Terms::All));
}

TEST(Way, ParsesOneOrTwoParts) {
  Way w = Way::parse("thickness:normal+lbl:draft", Terms::All);
  ASSERT_EQ(w.parts.size(), 2u);
  EXPECT_EQ(w.parts[0].terms, Terms::Single);
  EXPECT_EQ(w.parts[1].terms, Terms::Multiple);
  EXPECT_EQ(w.id(), "thickness:normal+lbl:draft");
  EXPECT_EQ(w.settings(1).at("rays"), 1);  // lbl's draft preset
  EXPECT_THROW(Way::parse("thickness:normal+lbl:draft", Terms::Single), std::invalid_argument);
  EXPECT_THROW(Way::parse("lbl", Terms::All), std::invalid_argument);
}

TEST(CalibrationTable, PredictsTheWorseNeighbourAndDoublesOutsideItsRange) {
  CalibrationTable t = table();
  SceneClass c = classify(sphere_scene(0.9, 4, 0), Terms::All);
  auto p = t.predict_error(c, "lbl:normal");
  ASSERT_TRUE(p);
  EXPECT_DOUBLE_EQ(p->value, 0.08);  // the worse of tau 2 and tau 8
  EXPECT_TRUE(p->inside);
  SceneClass far = classify(sphere_scene(0.9, 64, 0), Terms::All);
  p = t.predict_error(far, "lbl:normal");
  ASSERT_TRUE(p);
  EXPECT_FALSE(p->inside);
  EXPECT_DOUBLE_EQ(p->value, 0.16);
  EXPECT_NE(p->note.find("tau 64 outside the calibrated range"), std::string::npos) << p->note;
  SceneClass dielectric = c;
  dielectric.index_matched = false;
  EXPECT_FALSE(t.predict_error(dielectric, "lbl:normal"));  // no scene of its kind
  EXPECT_DOUBLE_EQ(t.predict_noise(c)->value, 1.6);
}

// The path tracer's noise past the calibrated g grows with the phase function's spread, whose
// closed form is checked against the integral; within a spread ratio of 1.5 the flat factor holds.
TEST(CalibrationTable, TheNoisePastTheCalibratedGGrowsWithThePhaseSpread) {
  for (double g : {0.0, -0.5, 0.7, 0.9}) {
    double sum = 0;  // 4 pi * integral of p^2 over the sphere, p Henyey-Greenstein
    const int n = 200000;
    for (int i = 0; i < n; ++i) {
      double mu = -1 + 2 * (i + 0.5) / n;
      double p = (1 - g * g) / (4 * M_PI * std::pow(1 + g * g - 2 * g * mu, 1.5));
      sum += p * p * 2 * M_PI * 2.0 / n;
    }
    EXPECT_NEAR(phase_spread(g), std::sqrt(4 * M_PI * sum), 1e-4 * phase_spread(g)) << g;
  }
  CalibrationTable t = table();  // g 0 only; noise 0.8 at tau 2, 1.6 at tau 8
  SceneClass c = classify(sphere_scene(0.9, 4, 0), Terms::All);
  c.g = -0.9;
  auto p = t.predict_noise(c);
  ASSERT_TRUE(p);
  EXPECT_FALSE(p->inside);
  EXPECT_NEAR(p->value, 1.6 * std::pow(phase_spread(-0.9), 1.5), 1e-9) << p->note;
  EXPECT_NE(p->note.find("g -0.9 outside the calibrated range"), std::string::npos) << p->note;
  c.g = 0.3;  // spread 1.15 (1.23 to the power 1.5): the flat 1.5
  EXPECT_NEAR(t.predict_noise(c)->value, 1.6 * 1.5, 1e-9);
  c.g = -0.9;
  c.tau = 64;  // outside in tau too: both factors
  EXPECT_NEAR(t.predict_noise(c)->value, 1.6 * std::pow(phase_spread(-0.9), 1.5) * 1.5, 1e-9);
  c.tau = 4;
  // Calibrated at g -0.7 as well: the ratio to the spread there (g in features of g / 0.7).
  CalibrationEntry back = t.entries[3];
  back.cls.g = -0.7;
  back.noise = 2.0;
  t.entries.push_back(back);
  EXPECT_NEAR(t.predict_noise(c)->value,
              2.0 * std::pow(phase_spread(-0.9) / phase_spread(-0.7), 1.5), 1e-9);
  // An approximate way's error is not scaled by it (psf's all terms fell from 19 to 14 % between
  // g 0.7 and 0.9 on a 24 x 24 sphere): doubled.
  c.g = -0.9;
  EXPECT_DOUBLE_EQ(t.predict_error(c, "lbl:normal")->value, 0.16);
}

// A scene lit from further round than the grid takes the ratio of the twins' errors lit from
// there to their front entries' (the worst in its cell, its excess doubled past the twins' tau
// or g), linear in the facing from 1 at the front, never less further round, and doubled beyond
// the last facing calibrated; the twins never stand in for the front grid, and a way no twin of
// its kind measured is doubled.
TEST(CalibrationTable, ScalesAPredictionLitFromFurtherRoundByItsTwinsRatio) {
  CalibrationTable t = table();
  for (CalibrationEntry& e : t.entries) e.cls.facing = 0.8;
  SceneClass c = classify(sphere_scene(0.9, 4, 0), Terms::All);
  c.facing = -0.3;
  // No twins: a table from before the facing predicts as before.
  EXPECT_DOUBLE_EQ(t.predict_error(c, "lbl:normal")->value, 0.08);
  auto twin = [&](size_t i, double facing, double lbl, double noise) {
    CalibrationEntry e = t.entries.at(i);
    e.twin = e.scene;
    e.scene += facing > 0 ? "-side" : "-behind";
    e.cls.facing = facing;
    e.error = {{"lbl:normal", lbl}};
    e.noise = noise;
    t.entries.push_back(e);
  };
  twin(3, 0.05, 0.16, 3.2);  // thick (tau 8): lbl 0.08 -> 0.16, noise 1.6 -> 3.2
  twin(2, 0.05, 0.06, 0.8);  // thin (tau 2): 0.04 -> 0.06
  twin(3, -0.6, 0.12, 4.8);  // from behind: less than from the side, so the side's
  twin(2, -0.6, 0.05, 1.6);
  twin(3, 0.9, 1.0, 9.0);  // "lit" from the grid's side of the front: no twin
  const double side = (0.16 + 1e-3) / (0.08 + 1e-3);  // a tenth of a percent added to both
  c.facing = 0.8;
  auto p = t.predict_error(c, "lbl:normal");
  EXPECT_DOUBLE_EQ(p->value, 0.08);  // the front grid, not the twins' larger errors
  EXPECT_TRUE(p->inside);
  c.facing = 0.425;  // half way round to the side
  p = t.predict_error(c, "lbl:normal");
  EXPECT_NEAR(p->value, 0.08 * (1 + (side - 1) / 2), 1e-9);
  EXPECT_TRUE(p->inside);
  EXPECT_NE(p->note.find("lit from facing 0.425"), std::string::npos) << p->note;
  c.facing = -0.3;
  p = t.predict_error(c, "lbl:normal");
  EXPECT_NEAR(p->value, 0.08 * side, 1e-9);
  EXPECT_NE(p->note.find("thick-side"), std::string::npos) << p->note;  // where the ratio is from
  c.facing = -0.9;
  p = t.predict_error(c, "lbl:normal");
  EXPECT_NEAR(p->value, 0.08 * side * 2, 1e-9);
  EXPECT_FALSE(p->inside);
  EXPECT_NE(p->note.find("further round than calibrated"), std::string::npos) << p->note;
  // The twins' ratios are taken at the scene's class as the grid's errors are (the worst of its
  // cell): at tau 2, the thin pair's alone; past their tau, the nearest's excess doubled.
  c.tau = 2;
  c.facing = 0.05;
  EXPECT_NEAR(t.predict_error(c, "lbl:normal")->value, 0.04 * (0.061 / 0.041), 1e-9);
  c.tau = 64;  // outside the grid (x2) and the twins' tau
  p = t.predict_error(c, "lbl:normal");
  EXPECT_NEAR(p->value, 0.08 * 2 * (1 + (side - 1) * 2), 1e-9);
  EXPECT_NE(p->note.find("tau outside its twins'"), std::string::npos) << p->note;
  c.tau = 4;
  // The noise the same way: 2x at the side, 3x behind.
  EXPECT_NEAR(t.predict_noise(c)->value, 1.6 * 2, 1e-9);
  c.facing = -0.6;
  EXPECT_NEAR(t.predict_noise(c)->value, 1.6 * 3, 1e-9);
  // A way no twin measured, where its kind has twins: doubled.
  p = t.predict_error(c, "psf:normal");
  EXPECT_DOUBLE_EQ(p->value, 0.40 * 2);
  EXPECT_FALSE(p->inside);
  EXPECT_NE(p->note.find("no twin lit from further round measured it"), std::string::npos)
      << p->note;
}

TEST(CalibrationTable, RoundTripsThroughJson) {
  CalibrationTable t = table();
  t.entries[1].cls.facing = -0.4;
  t.entries[1].twin = "thin";
  CalibrationTable back = CalibrationTable::from_json(t.to_json());
  ASSERT_EQ(back.entries.size(), t.entries.size());
  EXPECT_EQ(back.entries[1].cls.facing, -0.4);
  EXPECT_EQ(back.entries[1].twin, "thin");
  EXPECT_EQ(back.entries[0].twin, "");
  EXPECT_EQ(back.entries[2].error, t.entries[2].error);
  EXPECT_EQ(back.entries[3].noise, 1.6);
  nlohmann::json wrong = t.to_json();
  wrong["format"] = 99;
  EXPECT_THROW(CalibrationTable::from_json(wrong), std::invalid_argument);
}

TEST(CalibrationTable, TheShippedOneCoversEveryTermsAndParses) {
  const CalibrationTable& t = CalibrationTable::shipped();
  EXPECT_GE(t.version, 1);
  for (Terms terms : {Terms::Single, Terms::Multiple, Terms::All})
    EXPECT_FALSE(t.ways(terms).empty()) << to_string(terms);
  for (const CalibrationEntry& e : t.entries)
    for (const auto& [way, err] : e.error) {
      EXPECT_NO_THROW(Way::parse(way, e.cls.terms).settings(0)) << way;
      EXPECT_GE(err, 0) << e.scene << " " << way;
    }
}

}  // namespace
}  // namespace scatter
