// asset_key (pipelines/asset_key.hpp): the identity computed once when a scene is parsed, and
// what it does and does not depend on.
#include "pipelines/asset_key.hpp"

#include <gtest/gtest.h>

#include "../test_util.hpp"
#include "pipelines/single/single_pipeline.hpp"

namespace scatter {
namespace {

Scene parse(const nlohmann::json& j) {
  return parse_scene(j, test::source_path("scenes"));
}

nlohmann::json noise_sphere() {
  nlohmann::json j = test::minimal_scene();
  j["medium"]["density"] = {{"type", "noise"}, {"scale", 3}, {"seed", 1}};
  return j;
}

TEST(AssetKey, IdsAreComputedOnceWhenParsedAndFollowTheContent) {
  Scene a = parse(noise_sphere()), b = parse(noise_sphere());
  EXPECT_EQ(a.mesh_id, mesh_digest(*a.mesh));
  EXPECT_EQ(a.mesh_id.size(), 64u);
  EXPECT_FALSE(a.medium.density->id().empty());
  EXPECT_NE(a.medium.density.get(), b.medium.density.get());  // two objects, one identity
  EXPECT_EQ(a.medium.density->id(), b.medium.density->id());
  EXPECT_EQ(asset_key(a).hex(), asset_key(b).hex());

  nlohmann::json seed = noise_sphere();
  seed["medium"]["density"]["seed"] = 2;
  EXPECT_NE(parse(seed).medium.density->id(), a.medium.density->id());
  EXPECT_NE(asset_key(parse(seed)).hex(), asset_key(a).hex());

  nlohmann::json bigger = noise_sphere();
  bigger["mesh"]["radius"] = 1.5;
  EXPECT_NE(parse(bigger).mesh_id, a.mesh_id);

  // What the asset does not hold: camera, lights, image size.
  nlohmann::json moved = noise_sphere();
  moved["camera"]["position"] = {1, 2, 4};
  moved["image"] = {{"width", 64}, {"height", 32}};
  EXPECT_EQ(asset_key(parse(moved)).hex(), asset_key(a).hex());

  Scene fewer = a;
  fewer.voxels = 32;
  EXPECT_NE(asset_key(fewer).hex(), asset_key(a).hex());
  Scene denser = a;
  denser.medium.sigma_s = {2, 2, 2};
  EXPECT_NE(asset_key(denser).hex(), asset_key(a).hex());
}

// A scene built in code has no ids: the mesh is hashed then, and the density keyed by its object.
TEST(AssetKey, ScenesBuiltInCodeFallBackToTheirContent) {
  Scene a = parse(noise_sphere());
  Scene code = a;
  code.mesh_id.clear();
  EXPECT_EQ(asset_key(code).hex(),
            asset_key(a).hex());  // the same mesh bytes, the same density object
}

// The single product's key is what bake() files the product under.
TEST(AssetKey, SingleProductKeyIsTheBakesKey) {
  Scene s = parse(test::minimal_scene());
  s.voxels = 16;
  Settings settings = {{"samples", 500}, {"directions", 16}, {"sh_order", 2}};
  SinglePipeline p(test::shared_gpu(), nullptr);
  BakeResult r = p.bake(s, {Terms::Single, settings, nullptr});
  EXPECT_EQ(r.key, SinglePipeline::product_key(s, SingleSettings::read(settings)));
  settings["samples"] = 600;
  EXPECT_NE(r.key, SinglePipeline::product_key(s, SingleSettings::read(settings)));
}

}  // namespace
}  // namespace scatter
