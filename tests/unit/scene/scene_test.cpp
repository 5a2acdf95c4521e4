#include "scene/scene.hpp"

#include <gtest/gtest.h>

#include "../test_util.hpp"

namespace scatter {
namespace {

std::string error_for(const nlohmann::json& scene) {
  try {
    parse_scene(scene, ".");
  } catch (const std::exception& e) {
    return e.what();
  }
  return "no error";
}

TEST(Scene, MinimalSceneHasDefaults) {
  Scene s = parse_scene(test::minimal_scene(), ".");
  EXPECT_EQ(s.width, 64);
  EXPECT_EQ(s.voxels, 64);
  EXPECT_EQ(s.medium.g, 0.0);
  EXPECT_EQ(s.medium.ior, 1.0);
  ASSERT_TRUE(s.medium.density);
  EXPECT_TRUE(s.medium.density->homogeneous());
  ASSERT_EQ(s.lights.size(), 1u);
  EXPECT_EQ(s.lights[0].type, Light::Type::Directional);
  EXPECT_TRUE(check_watertight(*s.mesh).watertight());
}

TEST(Scene, ShippedScenesParse) {
  for (const char* name : {"sphere", "cube-torus", "layers", "bunny"}) {
    SCOPED_TRACE(name);
    Scene s = load_scene(test::source_path(std::string("scenes/") + name + ".json"));
    EXPECT_EQ(s.width, 512);
    EXPECT_FALSE(s.lights.empty());
    EXPECT_GT(s.mesh->volume(), 0);
  }
}

// Each bad field gives an error that names it and says what is wrong.
TEST(Scene, EachBadFieldGivesItsMessage) {
  struct Case {
    const char* pointer;
    nlohmann::json value;
    const char* expected;
  };
  const Case cases[] = {
      {"/mesh/shape", "cone", "scene.mesh.shape: must be one of sphere, box, torus; got \"cone\""},
      {"/mesh/radius", -1, "scene.mesh.radius: must be in [1e-06, 1e+06], got -1"},
      {"/mesh/colour", 1, "scene.mesh.colour: is not a known field"},
      {"/medium/sigma_s", nlohmann::json::array({1, -2, 1}),
       "scene.medium.sigma_s[1]: must be in [0, 1e+06], got -2"},
      {"/medium/sigma_a", "lots",
       "scene.medium.sigma_a: must be an array of 3 numbers, got \"lots\""},
      {"/medium/g", 1.0, "scene.medium.g: must be in [-0.999, 0.999], got 1"},
      {"/medium/ior", 0.5, "scene.medium.ior: must be in [1, 4], got 0.5"},
      {"/medium/density",
       {{"type", "fog"}},
       "scene.medium.density.type: must be one of constant, layers, noise, grid, blocker; got "
       "\"fog\""},
      {"/medium/density",
       {{"type", "layers"}, {"values", nlohmann::json::array()}},
       "scene.medium.density.values: must have 1 to 64 elements, got 0"},
      {"/medium/density",
       {{"type", "noise"}, {"min", 2}, {"max", 1}},
       "scene.medium.density.max: must not be below min"},
      {"/lights/0/type", "area",
       "scene.lights[0].type: must be one of point, directional, spot; got \"area\""},
      {"/lights/0/direction", nlohmann::json::array({0, 0, 0}),
       "scene.lights[0].direction: must not be zero"},
      {"/lights/0/irradiance", -3, "scene.lights[0].irradiance: must be in [0, 1e+09], got -3"},
      {"/camera/fov_deg", 180, "scene.camera.fov_deg: must be in [1, 170], got 180"},
      {"/camera/target", nlohmann::json::array({0, 0, 4}),
       "scene.camera.target: must differ from position"},
      {"/camera/up", nlohmann::json::array({0, 0, 1}),
       "scene.camera.up: must not be parallel to the viewing direction"},
      {"/image/width", 100000, "scene.image.width: must be in [1, 8192], got 100000"},
      {"/image/height", 0, "scene.image.height: must be in [1, 8192], got 0"},
      {"/voxels", 4096, "scene.voxels: must be in [4, 512], got 4096"},
      {"/voxels", 64.5, "scene.voxels: must be an integer, got 64.5"},
      {"/lighting", 1, "scene.lighting: is not a known field"},
  };
  for (const Case& c : cases) {
    nlohmann::json scene = test::minimal_scene();
    scene[nlohmann::json::json_pointer(c.pointer)] = c.value;
    EXPECT_EQ(error_for(scene), c.expected) << c.pointer;
  }
}

TEST(Scene, MissingSectionsAndMeshProblems) {
  nlohmann::json s = test::minimal_scene();
  s.erase("medium");
  EXPECT_EQ(error_for(s), "scene.medium: is required");

  s = test::minimal_scene();
  s["mesh"] = {{"file", "nowhere.obj"}};
  EXPECT_NE(error_for(s).find("nowhere.obj does not exist"), std::string::npos) << error_for(s);

  s["mesh"] = {{"file", "a.obj"}, {"shape", "sphere"}};
  EXPECT_EQ(error_for(s), "scene.mesh.file: give exactly one of \"file\" or \"shape\"");

  auto dir = test::scratch_dir("scene_errors");
  // A cube with its top face missing: four boundary edges.
  test::write_file(dir / "open.obj",
                   "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
                   "f 1 3 2\nf 1 4 3\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\n"
                   "f 4 1 5\nf 4 5 8\n");
  s["mesh"] = {{"file", "open.obj"}};
  try {
    parse_scene(s, dir);
    FAIL() << "an open mesh was accepted";
  } catch (const ValidationError& e) {
    EXPECT_EQ(std::string(e.what()),
              "scene.mesh.file: mesh open.obj is not watertight (4 boundary edges, 0 non-manifold "
              "edges, 0 inconsistently oriented edges); it cannot bound a volume");
  }
}

TEST(Scene, MeshesThatBoundNoVolumeOrHoldBadNumbersAreRejected) {
  auto dir = test::scratch_dir("scene_bad_meshes");
  nlohmann::json s = test::minimal_scene();
  // Two triangles back to back: closed in the edge sense, but flat.
  test::write_file(dir / "flat.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 3 2\n");
  s["mesh"] = {{"file", "flat.obj"}};
  try {
    parse_scene(s, dir);
    FAIL();
  } catch (const ValidationError& e) {
    EXPECT_EQ(std::string(e.what()), "scene.mesh.file: mesh flat.obj encloses no volume");
  }
  test::write_file(dir / "nan.obj",
                   "v nan 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n");
  s["mesh"] = {{"file", "nan.obj"}};
  try {
    parse_scene(s, dir);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("not finite"), std::string::npos) << e.what();
  }
}

TEST(Scene, FitCentresAndScalesTheMesh) {
  nlohmann::json s = test::minimal_scene();
  s["mesh"] = {{"file", "/usr/share/glmark2/models/bunny.obj"}, {"fit", 2.0}};
  Scene scene = parse_scene(s, ".");
  Aabb b = scene.mesh->bounds();
  EXPECT_NEAR(std::max({b.size().x, b.size().y, b.size().z}), 2.0, 1e-9);
  EXPECT_NEAR(length(b.center()), 0.0, 1e-9);
}

}  // namespace
}  // namespace scatter
