// The scene a request renders: the object's boundary, its medium, lights, camera and image.
// Parsed from JSON (docs/scene-format.md) with every field validated; see parse_scene().
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "scene/density.hpp"
#include "scene/mesh.hpp"
#include "scene/shapes.hpp"

namespace scatter {

struct Medium {
  Vec3 sigma_s{1, 1, 1};  // per scene unit, scaled by the density
  Vec3 sigma_a{0.1, 0.1, 0.1};
  double g = 0;    // Henyey-Greenstein asymmetry
  double ior = 1;  // refractive index of the medium (1: index matched)
  std::shared_ptr<const DensityField> density;
};

struct Light {
  enum class Type { Point, Directional, Spot };
  Type type = Type::Point;
  Vec3 position{3, 3, 3};
  Vec3 direction{0, -1, 0};  // the way the light travels (directional, spot)
  Vec3 color{1, 1, 1};
  double intensity = 10;  // point, spot: radiant intensity; directional: irradiance
  double inner_deg = 20;  // spot: full intensity inside this half-angle
  double outer_deg = 30;  // spot: zero outside this half-angle
};

// The share of the light's intensity that leaves it in the unit direction `d`: a spot's cone,
// smooth (smoothstep of the cosine) from its outer half-angle to its inner one, as
// kernels/common/lights.cl lights; 1 for the other lights.
double spot_cone(const Light& l, const Vec3& d);

struct Camera {
  Vec3 position{0, 0, 4};
  Vec3 target{0, 0, 0};
  Vec3 up{0, 1, 0};
  double fov_deg = 40;
};

// The pinhole camera's frame for a width x height image: the ray through pixel (i, j)'s centre
// (row 0 at the top) is normalize(forward + right * sx + up * sy) with
// sx = 2 (i + 0.5) / width - 1 and sy = 1 - 2 (j + 0.5) / height; right and up carry tan(fov / 2)
// (and the aspect ratio).
struct CameraFrame {
  Vec3 forward, right, up;
  Vec3 ray(int i, int j, int width, int height) const {
    return normalize(forward + right * (2 * (i + 0.5) / width - 1) +
                     up * (1 - 2 * (j + 0.5) / height));
  }
};
CameraFrame camera_frame(const Camera& camera, int width, int height);

// Blinn-Phong parameters for the surface term (normalised so the BRDF conserves energy).
struct SurfaceMaterial {
  Vec3 diffuse{0.8, 0.8, 0.8};
  Vec3 specular{0.04, 0.04, 0.04};
  double shininess = 64;
};

struct SceneLimits {
  int max_image = 8192;  // pixels per side
  int max_voxels = 512;  // voxels along the longest side
  int max_lights = 16;
};

struct Scene {
  // What is rasterised; watertight. Shared: the frames of a session, and requests for the same
  // scene, hold one mesh.
  std::shared_ptr<const Mesh> mesh = std::make_shared<const Mesh>();
  // mesh_digest(*mesh), computed once by parse_scene and carried with the mesh; empty for a
  // scene built in code (asset_key then hashes the mesh itself).
  std::string mesh_id;
  std::optional<Shape> shape;  // the exact solid when the mesh came from a procedural shape
  Medium medium;
  std::vector<Light> lights;
  Camera camera;
  int width = 512, height = 512;
  int voxels = 64;
  Vec3 background{0, 0, 0};
  SurfaceMaterial surface;
};

// Validates `json` and builds the scene; mesh and grid files are read relative to `base_dir`.
// Throws ValidationError naming the first bad field, std::runtime_error for unreadable files.
Scene parse_scene(const nlohmann::json& json, const std::filesystem::path& base_dir,
                  const SceneLimits& limits = {});
// Validates an array of light objects (as in a scene's "lights"); `path` names it in errors.
std::vector<Light> parse_lights(const nlohmann::json& lights, const std::string& path,
                                const SceneLimits& limits = {});
// Reads and parses a scene file.
Scene load_scene(const std::filesystem::path& path, const SceneLimits& limits = {});

}  // namespace scatter
