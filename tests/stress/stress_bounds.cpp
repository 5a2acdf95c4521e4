#include "stress_bounds.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "scene/voxelizer.hpp"

namespace scatter::stress {
namespace {

constexpr double kPi = std::numbers::pi;

// Distance from p to the box [lo, hi] (0 inside).
double box_distance(const Vec3& p, const Vec3& lo, const Vec3& hi) {
  Vec3 d = vmax(vmax(lo - p, p - hi), Vec3{});
  return length(d);
}

// The distance from `p` to the nearest medium any pipeline sees: the mesh's bounding box (the
// exact solid) and every voxel with extinction (the voxelized one, whose boundary voxels reach
// beyond the mesh).
double medium_distance(const Scene& scene, const Vec3& p) {
  Aabb b = scene.mesh->bounds();
  double d = box_distance(p, b.lo, b.hi);
  VoxelGrid g = voxelize(scene, {.resolution = scene.voxels});
  for (int k = 0; k < g.nz; ++k)
    for (int j = 0; j < g.ny; ++j)
      for (int i = 0; i < g.nx; ++i) {
        size_t v = 3 * g.index(i, j, k);
        if (g.sigma_s[v] + g.sigma_a[v] + g.sigma_s[v + 1] + g.sigma_a[v + 1] + g.sigma_s[v + 2] +
                g.sigma_a[v + 2] <=
            0)
          continue;
        Vec3 lo = g.origin + Vec3{double(i), double(j), double(k)} * g.voxel;
        d = std::min(d, box_distance(p, lo, lo + Vec3{1, 1, 1} * g.voxel));
      }
  return d;
}

double max_channel(const Vec3& v) {
  return std::max({v.x, v.y, v.z});
}

// The largest single-scattering albedo sigma_s / sigma_t over the channels (the density scales
// both alike; a blocker's inside is a pure absorber, albedo 0).
double max_albedo(const Medium& m) {
  double a = 0;
  for (int c = 0; c < 3; ++c) {
    double st = m.sigma_s[c] + m.sigma_a[c];
    if (st > 0) a = std::max(a, m.sigma_s[c] / st);
  }
  return a;
}

// The largest irradiance light `l` gives anywhere in the medium, per unit of phase; infinite
// when the light touches the medium.
double max_irradiance(const Scene& scene, const Light& l) {
  double e = l.intensity * max_channel(l.color);
  if (l.type == Light::Type::Directional || e == 0) return e;
  double d = medium_distance(scene, l.position);
  return d > 0 ? e / (d * d) : INFINITY;
}

}  // namespace

std::string bad_value(const Image& image) {
  for (size_t i = 0; i < image.rgb.size(); ++i) {
    float v = image.rgb[i];
    if (std::isfinite(v) && v >= 0) continue;
    size_t px = i / 3;
    std::ostringstream s;
    s << "pixel (" << px % image.width << ", " << px / image.width << ") channel " << i % 3
      << " is " << v;
    return s.str();
  }
  return "";
}

double hg(double mu, double g) {
  return (1 - g * g) / (4 * kPi * std::pow(1 + g * g - 2 * g * mu, 1.5));
}

double hg_max(double g) {
  return hg(g >= 0 ? 1 : -1, g);
}

// Single scattering with no boundary (ior 1), along the view ray x(t) = o + t d:
//   L = integral sigma_s(t) p(theta) E(t) T_light(t) T_view(t) dt
//     <= albedo_max p E_max integral sigma_t(t) T_view(t) dt = albedo_max p E_max (1 - T_view)
//     <= albedo_max p E_max,
// with sigma_s <= albedo_max sigma_t pointwise and T_light <= 1. A directional light's angle is
// one per pixel, p = p(dot(-light direction, d)); a point or spot light's E(t) <= I / r_min^2
// with r_min its distance to the medium, and p <= its maximum.
std::optional<Image> single_bound(const Scene& scene, bool isotropic_view) {
  if (scene.medium.ior != 1) return std::nullopt;
  const double albedo = max_albedo(scene.medium), g = scene.medium.g;
  auto phase = [&](double mu) { return isotropic_view ? 1 / (4 * kPi) : hg(mu, g); };
  const double phase_max = isotropic_view ? 1 / (4 * kPi) : hg_max(g);
  Image bound(scene.width, scene.height);
  CameraFrame f = camera_frame(scene.camera, scene.width, scene.height);
  for (const Light& l : scene.lights) {
    double e = max_irradiance(scene, l);
    if (!std::isfinite(e)) return std::nullopt;
    for (int y = 0; y < scene.height; ++y)
      for (int x = 0; x < scene.width; ++x) {
        Vec3 d = f.ray(x, y, scene.width, scene.height);
        double p = l.type == Light::Type::Directional ? phase(dot(-l.direction, d)) : phase_max;
        for (int c = 0; c < 3; ++c)
          bound.rgb[(size_t(y) * scene.width + x) * 3 + c] += float(albedo * p * e);
      }
  }
  return bound;
}

// Blinn-Phong as pipelines/surface shades it (shaders/surface): per light
//   (kd / pi + ks (n + 8) / (8 pi) cos^n theta_h) E cos theta_i <= (kd / pi + ks (n + 8) / (8 pi))
//   E.
std::optional<Image> surface_bound(const Scene& scene) {
  const SurfaceMaterial& s = scene.surface;
  const double brdf =
      max_channel(s.diffuse) / kPi + max_channel(s.specular) * (s.shininess + 8) / (8 * kPi);
  double sum = 0;
  for (const Light& l : scene.lights) {
    double e = l.intensity * max_channel(l.color);
    if (l.type != Light::Type::Directional && e > 0) {
      Aabb b = scene.mesh->bounds();
      double d = box_distance(l.position, b.lo, b.hi);
      if (d <= 0) return std::nullopt;
      e /= d * d;
    }
    sum += brdf * e;
  }
  Image bound(scene.width, scene.height);
  std::fill(bound.rgb.begin(), bound.rgb.end(), float(sum));
  return bound;
}

std::string above_bound(const Image& image, const Image& bound) {
  double worst = 1;
  size_t at = 0;
  for (size_t i = 0; i < image.rgb.size(); ++i) {
    // float32 rounding of the image and of the bound's own sum.
    double b = double(bound.rgb[i]) * (1 + 1e-5) + 1e-37;
    if (image.rgb[i] > b && image.rgb[i] / b > worst) {
      worst = image.rgb[i] / b;
      at = i;
    }
  }
  if (worst <= 1) return "";
  std::ostringstream s;
  size_t px = at / 3;
  s << "pixel (" << px % image.width << ", " << px / image.width << ") channel " << at % 3 << ": "
    << image.rgb[at] << " > bound " << bound.rgb[at] << " (x" << worst << ")";
  return s.str();
}

}  // namespace scatter::stress
