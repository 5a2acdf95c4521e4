#include "protocol/session_messages.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include "../test_util.hpp"

namespace scatter {
namespace {

// Each light type, as the scene message sends it, reads back (parse_lights) to the same light:
// the web client sends these lights back unchanged after editing one of them.
TEST(SessionMessages, LightsRoundTripThroughTheSceneFormat) {
  nlohmann::json lights = nlohmann::json::parse(R"([
    {"type": "point", "position": [1, 2, 3], "color": [1, 0.5, 0.25], "intensity": 40},
    {"type": "directional", "direction": [0, 0, -1], "color": [1, 1, 1], "irradiance": 2},
    {"type": "spot", "position": [0, 3, 0], "direction": [0, -1, 0], "color": [0.2, 0.4, 0.6],
     "intensity": 7, "inner_deg": 10, "outer_deg": 25}])");
  std::vector<Light> parsed = parse_lights(lights, "lights");
  nlohmann::json sent = nlohmann::json::array();
  for (const Light& l : parsed) sent.push_back(light_json(l));
  EXPECT_EQ(sent, lights);
  std::vector<Light> again = parse_lights(sent, "lights");
  ASSERT_EQ(again.size(), 3u);
  EXPECT_EQ(again[2].outer_deg, 25);
  EXPECT_EQ(again[1].intensity, 2);
}

TEST(SessionMessages, TheSceneMessageCarriesTheSceneAndTheShippedNames) {
  nlohmann::json hello = {{"scene_name", "sphere"}};
  Scene scene = load_scene(test::source_path("scenes/sphere.json"));
  nlohmann::json m = scene_message(hello, scene, test::source_path("scenes"), 3);
  EXPECT_EQ(m["type"], "scene");
  EXPECT_EQ(m["request"], 3);
  EXPECT_EQ(m["source"]["mesh"]["shape"], "sphere");  // the file's JSON, for the client to edit
  EXPECT_EQ(m["camera"], camera_json(scene.camera));
  EXPECT_EQ(m["lights"].size(), scene.lights.size());
  EXPECT_NEAR(m["bounds"]["min"][1].get<double>(), -1.0, 0.01);
  std::vector<std::string> names = m["scenes"];
  EXPECT_TRUE(std::is_sorted(names.begin(), names.end()));
  EXPECT_NE(std::find(names.begin(), names.end(), "jade"), names.end());
  // A name that is no file gives no source rather than an error (the hello was validated).
  EXPECT_TRUE(
      scene_message({{"scene_name", "gone"}}, scene, test::source_path("scenes"), 0)["source"]
          .is_null());
}

}  // namespace
}  // namespace scatter
