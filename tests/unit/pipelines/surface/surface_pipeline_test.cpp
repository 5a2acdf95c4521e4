#include "pipelines/surface/surface_pipeline.hpp"

#include <gtest/gtest.h>

#include <numbers>

#include "../../test_util.hpp"
#include "protocol/json_reader.hpp"

namespace scatter {
namespace {

constexpr double kPi = std::numbers::pi;

// The camera ray through the centre of pixel (i, j), row 0 at the top (the scene convention).
Vec3 pixel_direction(const Scene& s, int i, int j) {
  const Camera& c = s.camera;
  Vec3 f = normalize(c.target - c.position);
  Vec3 r = normalize(cross(f, c.up));
  Vec3 u = cross(r, f);
  double t = std::tan(c.fov_deg * kPi / 360);
  double x = (2 * (i + 0.5) / s.width - 1) * t * s.width / s.height;
  double y = (1 - 2 * (j + 0.5) / s.height) * t;
  return normalize(f + r * x + u * y);
}

// Distance along a unit ray to the unit sphere at the origin, or -1.
double hit_unit_sphere(const Vec3& o, const Vec3& d) {
  double b = dot(o, d), c = dot(o, o) - 1, disc = b * b - c;
  return disc < 0 ? -1 : -b - std::sqrt(disc);
}

Scene lambert_sphere(int size) {
  nlohmann::json j = test::minimal_scene();
  j["image"] = {{"width", size}, {"height", size}};
  j["surface"] = {{"diffuse", 0.5}, {"specular", 0.0}};
  j["lights"] = {{{"type", "directional"}, {"direction", {-1, -1, -2}}, {"irradiance", 2.0}}};
  j["background"] = {0.1, 0.2, 0.3};
  return parse_scene(j, ".");
}

// Every pixel against the analytic Lambertian radiance kd / pi * E * max(n.l, 0) of the exact
// sphere, away from the silhouette where the tessellation and the sphere differ.
TEST(SurfacePipeline, LambertSphereMatchesAnalyticRadiance) {
  Scene s = lambert_sphere(96);
  SurfacePipeline p(test::shared_gpu());
  RenderResult r = p.render(s, {Terms::Surface});
  ASSERT_EQ(r.image.width, 96);
  Vec3 l = normalize(Vec3{1, 1, 2});
  int compared = 0;
  double worst = 0;
  for (int j = 0; j < s.height; ++j)
    for (int i = 0; i < s.width; ++i) {
      Vec3 d = pixel_direction(s, i, j);
      double t = hit_unit_sphere(s.camera.position, d);
      Vec3 got = r.image.at(i, j);
      if (t < 0) {
        // Rays that miss by a clear margin show the background.
        Vec3 o = s.camera.position;
        if (dot(o, o) - dot(o, d) * dot(o, d) > 1.05) {
          EXPECT_NEAR(got.x, 0.1, 1e-6);
          EXPECT_NEAR(got.z, 0.3, 1e-6);
        }
        continue;
      }
      Vec3 n = normalize(s.camera.position + d * t);
      if (dot(n, -d) < 0.3) continue;  // near the silhouette
      double expected = 0.5 / kPi * 2.0 * std::max(dot(n, l), 0.0);
      worst = std::max(worst, std::abs(got.x - expected));
      EXPECT_NEAR(got.y, got.x, 1e-6);
      ++compared;
    }
  EXPECT_GT(compared, 2000);
  // 0.5 % of the brightest radiance (0.318): tessellation normals and float precision.
  EXPECT_LT(worst, 0.005 * 0.5 / kPi * 2.0);
}

// Point light on the view axis with a specular lobe: at the sphere's nearest point l = v = h = n.
TEST(SurfacePipeline, PointLightAndSpecularAtTheCentre) {
  nlohmann::json j = test::minimal_scene();
  j["image"] = {{"width", 33}, {"height", 33}};  // odd: one pixel sits on the axis
  j["surface"] = {{"diffuse", 0.4}, {"specular", 0.2}, {"shininess", 32}};
  j["lights"] = {
      {{"type", "point"}, {"position", {0, 0, 3}}, {"intensity", 8.0}, {"color", {1, 0.5, 0}}}};
  Scene s = parse_scene(j, ".");
  SurfacePipeline p(test::shared_gpu());
  Vec3 got = p.render(s, {Terms::Surface}).image.at(16, 16);
  double e = 8.0 / 4.0;  // intensity / r^2 with r = 2
  double brdf = 0.4 / kPi + 0.2 * (32 + 8) / (8 * kPi);
  EXPECT_NEAR(got.x, brdf * e, 2e-3 * brdf * e);
  EXPECT_NEAR(got.y, 0.5 * brdf * e, 2e-3 * brdf * e);
  EXPECT_NEAR(got.z, 0.0, 1e-7);
}

TEST(SurfacePipeline, SpotLightConeCutsOff) {
  nlohmann::json j = test::minimal_scene();
  j["image"] = {{"width", 64}, {"height", 64}};
  j["lights"] = {{{"type", "spot"},
                  {"position", {0, 0, 3}},
                  {"direction", {0, 0, -1}},
                  {"intensity", 8.0},
                  {"inner_deg", 5},
                  {"outer_deg", 8}}};
  Scene s = parse_scene(j, ".");
  SurfacePipeline p(test::shared_gpu());
  Image im = p.render(s, {Terms::Surface}).image;
  EXPECT_GT(im.at(32, 32).x, 0.1);  // inside the cone
  EXPECT_EQ(im.at(32, 12).x, 0.0);  // on the sphere, well outside the cone
}

double total(const Image& im) {
  double sum = 0;
  for (float v : im.rgb) sum += v;
  return sum;
}

// A convex object cannot shadow itself: the shadow maps change nothing (no acne from the bias).
TEST(SurfacePipeline, ShadowsLeaveAConvexObjectAsItWas) {
  Scene s = lambert_sphere(64);
  SurfacePipeline p(test::shared_gpu());
  double plain = total(p.render(s, {Terms::Surface}).image);
  double shadowed = total(p.render(s, {Terms::Surface, {{"shadows", 1}}}).image);
  EXPECT_GT(plain, 0);
  EXPECT_NEAR(shadowed, plain, 0.005 * plain);
}

// A torus lit 17 degrees above its plane: the ring's near side shadows the inner wall on the
// far side, which faces the light; the shadowed image is darker there and nowhere brighter.
TEST(SurfacePipeline, ShadowsDarkenWhatTheObjectHidesFromTheLight) {
  nlohmann::json j = test::minimal_scene();
  j["mesh"] = {
      {"shape", "torus"}, {"major_radius", 1.0}, {"minor_radius", 0.35}, {"axis", {0, 1, 0}}};
  j["lights"] = {{{"type", "directional"}, {"direction", {0.95, -0.3, 0}}, {"irradiance", 2.0}}};
  j["camera"] = {
      {"position", {0, 4, 0.01}}, {"target", {0, 0, 0}}, {"up", {0, 0, -1}}, {"fov_deg", 45}};
  j["image"] = {{"width", 64}, {"height", 64}};
  Scene s = parse_scene(j, ".");
  SurfacePipeline p(test::shared_gpu());
  Image plain = p.render(s, {Terms::Surface}).image;
  Image shadowed = p.render(s, {Terms::Surface, {{"shadows", 1}}}).image;
  int darker = 0;
  for (size_t i = 0; i < plain.rgb.size(); ++i) {
    ASSERT_LE(shadowed.rgb[i], plain.rgb[i] + 1e-6f);
    if (shadowed.rgb[i] < 0.5f * plain.rgb[i]) ++darker;
  }
  EXPECT_GT(darker, 3 * 20);  // at least 20 pixels (3 channels each) in shadow
  EXPECT_LT(total(shadowed),
            0.995 * total(plain));  // measured 0.987: the wall is a small part of the view
}

TEST(SurfacePipeline, PlanAndTermsAreChecked) {
  Scene s = lambert_sphere(16);
  SurfacePipeline p(test::shared_gpu());
  Plan plan = p.plan(s, {Terms::Surface});
  EXPECT_EQ(plan.pipeline, "surface");
  ASSERT_EQ(plan.stages.size(), 4u);
  EXPECT_FALSE(plan.stages[1].run);  // shadow maps: off by default
  RenderResult r = p.render(s, {Terms::Surface});
  ASSERT_EQ(r.timings.size(), 3u);
  for (const auto& t : r.timings) EXPECT_GE(t.ms, 0.0);
  EXPECT_THROW(p.render(s, {Terms::Multiple}), ValidationError);
}

}  // namespace
}  // namespace scatter
