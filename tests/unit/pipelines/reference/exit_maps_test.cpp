// Exit maps (pipelines/reference/exit_maps.hpp): a shadow ray's exit from inside a convex mesh
// found in its light's map is the BVH's closest hit, and the path tracer renders the same image
// with the maps as without.
#include "pipelines/reference/exit_maps.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "../../test_util.hpp"
#include "pipelines/metrics.hpp"
#include "reference_render.hpp"

namespace scatter {
namespace {

Light sun(const Vec3& direction) {
  Light l;
  l.type = Light::Type::Directional;
  l.direction = normalize(direction);
  l.intensity = 1;
  return l;
}

Light lamp(const Vec3& position) {
  Light l;
  l.position = position;
  return l;
}

// Random points inside the mesh (those with exactly one crossing ahead: a convex mesh), towards
// each of the lights (suns, the scene's point light, a point light close by): the map's exit is
// the BVH's closest hit wherever the map finds one, and it finds one for all but a few points
// (rounding where a ray meets an edge). A point light inside the mesh has no map.
TEST(ExitMaps, FindTheBvhsExitFromInsideAConvexMesh) {
  for (const std::string name : {"sphere", "layers"}) {
    SCOPED_TRACE(name);
    Scene s = load_scene(test::source_path("scenes/" + name + ".json"));
    const FlatBvh bvh = build_bvh(*s.mesh);
    const std::vector<Light> lights = {sun({-1, -1, -1}),     s.lights.front(),
                                       sun({0.2, -1, 0.05}),  sun({0, 0, 1}),
                                       lamp({0.3, 1.6, 0.2}), lamp({0, 0, 0})};
    const ExitMaps maps = exit_maps(bvh, lights);
    ASSERT_EQ(maps.header.size(), lights.size() * kExitMapFloats);
    EXPECT_EQ(maps.lights(), 5);
    EXPECT_EQ(exit_map_hit(maps, bvh, 5, {0.1, 0.1, 0.1}), -1);  // the light inside: no map
    const Aabb box = s.mesh->bounds();
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(0, 1);
    int tested = 0, found = 0;
    for (int i = 0; i < 4000; ++i) {
      const Vec3 p = box.lo + box.size() * Vec3{u(rng), u(rng), u(rng)};
      for (int l : {0, 1, 2, 3, 4}) {
        const Vec3 w = lights[l].type == Light::Type::Directional
                           ? -lights[l].direction
                           : normalize(lights[l].position - p);
        // Inside: a crossing ahead and one behind.
        const double ahead = bvh_closest_hit(bvh, p, w, 0, 1e30);
        if (ahead < 0 || bvh_closest_hit(bvh, p, -w, 0, 1e30) < 0) continue;
        ++tested;
        const double t = exit_map_hit(maps, bvh, l, p);
        if (t < 0) continue;
        ++found;
        // (the map's axes are float32, so its ray's direction is the light's to about 1e-7)
        ASSERT_NEAR(t, ahead, 1e-6 * (1 + ahead)) << "light " << l;
      }
    }
    EXPECT_GT(tested, 5000);
    EXPECT_GT(found, tested - tested / 1000 - 1);
  }
}

// The path tracer with the maps and without them (exit_maps=0: the mesh queries) renders the
// same image from the same seed, index matched and as a dielectric, under a sun and the scene's
// point light.
TEST(ExitMaps, LeaveTheReferencesImageAsItWas) {
  for (double ior : {1.0, 1.4}) {
    SCOPED_TRACE(ior);
    Scene s = test::small_scene("sphere", 24, 24);
    s.lights.push_back(sun({-1, -1, -1}));
    s.medium.ior = ior;
    RenderResult with = test::reference_render(s, Terms::All, {{"spp", 8}, {"seed", 3}});
    RenderResult without =
        test::reference_render(s, Terms::All, {{"spp", 8}, {"seed", 3}, {"exit_maps", 0}});
    std::vector<uint8_t> all(size_t(s.width) * s.height, 1);
    EXPECT_LT(relative_rmse(with.image, without.image, all), 1e-4);
    EXPECT_GT(*with.error_estimate, 0.01);  // and the image is not empty
    EXPECT_NE(plan_stage(with.plan, "boundary").reason.find("exit_maps"), std::string::npos);
    EXPECT_EQ(plan_stage(without.plan, "boundary").reason.find("exit_maps"), std::string::npos);
  }
}

}  // namespace
}  // namespace scatter
