// Energy conservation over all orders of scattering (docs/STRESS.md): a sphere of albedo up to
// 1 - 1e-6 under a directional light of irradiance E scatters at most the power that falls on
// it, E times the area its medium presents to the light. The power it scatters is measured from
// images: a distant camera at angle theta from the light sees the radiant intensity
// I(theta) = sum over pixels of L x (pixel footprint), and, the scene being symmetric about the
// light's axis, P = 2 pi integral I(mu) dmu over mu = cos theta in [-1, 1] (Gauss-Legendre).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "../unit/test_util.hpp"
#include "pipelines/registry.hpp"
#include "scene/voxelizer.hpp"
#include "stress_bounds.hpp"

namespace scatter::stress {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDistance = 20;  // camera distance, in sphere radii: the far field within 0.3%
constexpr int kSide = 24;         // pixels per image side

// 8-point Gauss-Legendre on [-1, 1].
constexpr double kNodes[] = {-0.9602898564975363, -0.7966664774136267, -0.5255324099163290,
                             -0.1834346424956498, 0.1834346424956498,  0.5255324099163290,
                             0.7966664774136267,  0.9602898564975363};
constexpr double kWeights[] = {0.1012285362903763, 0.2223810344533745, 0.3137066833578221,
                               0.3626837833783620, 0.3626837833783620, 0.3137066833578221,
                               0.2223810344533745, 0.1012285362903763};

nlohmann::json sphere(double tau_voxel, double albedo, double g) {
  const int voxels = 8;
  const double st = tau_voxel * voxels / 2;
  return {
      {"mesh", {{"shape", "sphere"}, {"radius", 1}}},
      {"medium", {{"sigma_s", albedo * st}, {"sigma_a", (1 - albedo) * st}, {"g", g}}},
      // Light travels along -z: mu = 1 looks back at the lit side.
      {"lights", nlohmann::json::array(
                     {{{"type", "directional"}, {"direction", {0, 0, -1}}, {"irradiance", 2}}})},
      {"image", {{"width", kSide}, {"height", kSide}}},
      {"surface", {{"diffuse", 0}, {"specular", 0}}},  // no surface term on top
      {"voxels", voxels}};
}

// The area the medium presents to a light along z: the columns of voxels that hold extinction
// (the voxelized sphere covers more than pi r^2; the exact one less), and at least pi r^2.
double lit_area(const Scene& scene) {
  VoxelGrid g = voxelize(scene, {.resolution = scene.voxels});
  int columns = 0;
  for (int j = 0; j < g.ny; ++j)
    for (int i = 0; i < g.nx; ++i) {
      bool any = false;
      for (int k = 0; k < g.nz && !any; ++k) {
        size_t v = 3 * g.index(i, j, k);
        any = g.sigma_s[v] + g.sigma_a[v] > 0;
      }
      columns += any;
    }
  return std::max(kPi, columns * g.voxel * g.voxel);
}

// The power `pipeline` says the sphere scatters (all orders, channel 0).
double scattered_power(Pipeline& pipeline, Scene scene, Terms terms, const Settings& settings) {
  const double fov = 2 * std::atan(1.15 / kDistance);
  const double footprint = std::pow(2 * kDistance * std::tan(fov / 2) / kSide, 2);
  double power = 0;
  for (int k = 0; k < 8; ++k) {
    double mu = kNodes[k], s = std::sqrt(1 - mu * mu);
    scene.camera = {{kDistance * s, 0, kDistance * mu}, {0, 0, 0}, {0, 1, 0}, fov * 180 / kPi};
    Image img = pipeline.render(scene, {terms, settings, nullptr}).image;
    EXPECT_EQ(bad_value(img), "") << "mu " << mu;
    double intensity = 0;
    for (size_t i = 0; i < img.rgb.size(); i += 3) intensity += img.rgb[i] * footprint;
    power += 2 * kPi * kWeights[k] * intensity;
  }
  return power;
}

struct EnergyCase {
  double tau_voxel, albedo, g;
};

class Energy : public ::testing::TestWithParam<std::string> {};

INSTANTIATE_TEST_SUITE_P(AllOrders, Energy, ::testing::Values("reference", "psf", "lbl"),
                         [](const auto& p) { return p.param; });

// Allowance for the measurement itself: 8 views, 24 x 24 pixels over the sphere's disc, and the
// camera's finite distance.
constexpr double kQuadrature = 0.1;

TEST_P(Energy, ScatteredPowerAtMostIncident) {
  auto dir = test::scratch_dir("stress_energy_" + GetParam());
  auto pipeline = make_pipeline(GetParam(), test::shared_gpu());
  Settings settings;
  if (GetParam() == "reference") settings = {{"spp", 12}};
  for (EnergyCase c :
       {EnergyCase{0.1, 1 - 1e-6, 0}, EnergyCase{1, 1 - 1e-6, 0}, EnergyCase{10, 1 - 1e-6, 0},
        EnergyCase{1, 1 - 1e-6, 0.5}, EnergyCase{1, 0.5, 0}}) {
    Scene scene = parse_scene(sphere(c.tau_voxel, c.albedo, c.g), dir);
    double incident = 2 * lit_area(scene);
    double p = scattered_power(*pipeline, scene, Terms::All, settings);
    std::printf("%-10s tau %-5g albedo %-9g g %-4g: scattered %.4g of incident %.4g (%.3f)\n",
                GetParam().c_str(), c.tau_voxel, c.albedo, c.g, p, incident, p / incident);
    EXPECT_LE(p, incident * (1 + kQuadrature))
        << "tau " << c.tau_voxel << " albedo " << c.albedo << " g " << c.g;
  }
}

}  // namespace
}  // namespace scatter::stress
