#include "pipelines/budget/scene_class.hpp"

#include <algorithm>
#include <cmath>

namespace scatter {

double SceneClass::feature(int i) const {
  switch (i) {
    case 0:
      return std::log2(std::max(tau, 1e-6)) / 2;
    case 1:
      return -std::log10(std::max(1 - albedo, 1e-6));
    default:
      return g / kGStep;
  }
}

const char* SceneClass::feature_name(int i) {
  return i == 0 ? "tau" : (i == 1 ? "albedo" : "g");
}

SceneClass classify(const Scene& scene, Terms terms) {
  SceneClass c;
  c.terms = terms;
  const Medium& m = scene.medium;
  c.homogeneous = m.density->homogeneous();
  c.index_matched = m.ior == 1.0;
  c.g = m.g;
  double albedo = 0, sigma_t = 0;
  for (int k = 0; k < 3; ++k) {
    double t = m.sigma_s[k] + m.sigma_a[k];
    albedo += t > 0 ? m.sigma_s[k] / t : 0;
    sigma_t += t;
  }
  c.albedo = albedo / 3;
  Aabb b = scene.mesh->bounds();
  Vec3 size = b.size();
  // The mean density over a 5^3 lattice inside the bounds (blocked points left out): exact for a
  // constant field, the layers' or noise's mean for the others.
  double density = 0, lo = 1e300, hi = 0;
  int n = 0;
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j)
      for (int k = 0; k < 5; ++k) {
        Vec3 p = b.lo + size * Vec3{(i + 0.5) / 5, (j + 0.5) / 5, (k + 0.5) / 5};
        if (m.density->blocked(p)) continue;
        const double d = m.density->density(p);
        density += d;
        ++n;
        if (d > 0) lo = std::min(lo, d), hi = std::max(hi, d);
      }
  density = n ? density / n : 0;
  c.contrast = hi > 0 ? hi / lo : 1;
  double extent =
      std::cbrt(std::max(size.x, 1e-9) * std::max(size.y, 1e-9) * std::max(size.z, 1e-9));
  c.tau = sigma_t / 3 * density * extent;
  const Vec3 view = normalize(scene.camera.position - b.center());
  // A camera inside the bounds sees the medium from within: no side is lit or dark to it, and
  // the facing stays 1 (the calibration's front).
  const Vec3 eye = scene.camera.position;
  const bool camera_inside = eye.x >= b.lo.x && eye.x <= b.hi.x && eye.y >= b.lo.y &&
                             eye.y <= b.hi.y && eye.z >= b.lo.z && eye.z <= b.hi.z;
  double weight = 0, facing = 0;
  for (const Light& l : scene.lights) {
    const double power = l.intensity * (l.color.x + l.color.y + l.color.z) / 3;
    if (l.type == Light::Type::Directional) {
      weight += power;
      facing += power * dot(normalize(-l.direction), view);
      continue;
    }
    const Vec3 to = l.position - b.center();
    if (length(to) <= length(size) / 2 * 1.05) {
      c.light_inside = true;
      continue;
    }
    const double w = power / dot(to, to) * spot_cone(l, normalize(-to));  // a spot: its cone
    weight += w;
    facing += w * dot(normalize(to), view);
  }
  if (weight > 0 && !camera_inside) c.facing = facing / weight;
  return c;
}

std::string describe(const SceneClass& c) {
  return std::string(c.homogeneous ? "homogeneous" : "inhomogeneous") +
         (c.index_matched ? ", index matched" : ", dielectric") + ", albedo " +
         short_number(c.albedo) + ", tau " + short_number(c.tau) + ", g " + short_number(c.g) +
         (c.light_inside ? ", a light inside" : "") +
         (c.facing < 0.5 ? ", lit from " + std::string(c.facing < -0.3 ? "behind" : "the side") +
                               " (facing " + short_number(c.facing) + ")"
                         : "");
}

void to_json(nlohmann::json& j, const SceneClass& c) {
  j = {{"terms", to_string(c.terms)},
       {"homogeneous", c.homogeneous},
       {"index_matched", c.index_matched},
       {"albedo", c.albedo},
       {"tau", c.tau},
       {"g", c.g},
       {"light_inside", c.light_inside},
       {"facing", c.facing}};
}

void from_json(const nlohmann::json& j, SceneClass& c) {
  c.terms = parse_terms(j.at("terms").get<std::string>());
  c.homogeneous = j.at("homogeneous").get<bool>();
  c.index_matched = j.at("index_matched").get<bool>();
  c.albedo = j.at("albedo").get<double>();
  c.tau = j.at("tau").get<double>();
  c.g = j.at("g").get<double>();
  c.light_inside = j.value("light_inside", false);
  c.facing = j.value("facing", 1.0);
}

}  // namespace scatter
