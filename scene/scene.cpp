#include "scene/scene.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>

namespace scatter {
namespace {

constexpr Range kCoord{-1e6, 1e6};
constexpr Range kColor{0, 1e6};

void parse_mesh(JsonObject obj, const std::filesystem::path& base_dir, Scene& scene) {
  if (obj.has("file") == obj.has("shape"))
    throw ValidationError(obj.path("file"), "give exactly one of \"file\" or \"shape\"");
  if (obj.has("shape")) {
    Shape shape = Shape::parse(obj);
    int detail = obj.integer("detail", 96, {8, 1024});
    scene.mesh = std::make_shared<const Mesh>(shape.tessellate(detail));
    scene.shape = shape;
  } else {
    std::filesystem::path file = obj.string("file", std::nullopt);
    double scale = obj.number("scale", 1.0, {1e-9, 1e9});
    Vec3 translate = obj.vec3("translate", Vec3{}, kCoord);
    std::optional<double> fit;
    if (obj.has("fit")) fit = obj.number("fit", std::nullopt, {1e-9, 1e9});
    Mesh mesh = load_mesh(file.is_absolute() ? file : base_dir / file);
    WatertightReport report = check_watertight(mesh);
    if (!report.watertight())
      throw ValidationError(obj.path("file"), "mesh " + file.string() + " is not watertight (" +
                                                  report.summary() + "); it cannot bound a volume");
    // A closed mesh can still enclose nothing (a point, a flat double-sided sheet).
    Aabb b = mesh.bounds();
    Vec3 s = b.size();
    double longest = std::max({s.x, s.y, s.z});
    if (!(std::abs(mesh.volume()) > 1e-9 * s.x * s.y * s.z) || longest <= 0)
      throw ValidationError(obj.path("file"), "mesh " + file.string() + " encloses no volume");
    if (fit) {
      // Centre on the origin and scale so the longest side of the bounding box is `fit`.
      mesh.transform(1.0, -b.center());
      scale *= *fit / longest;
    }
    mesh.transform(scale, translate);
    mesh.orient_outwards();
    mesh.compute_normals();
    scene.mesh = std::make_shared<const Mesh>(std::move(mesh));
  }
  obj.finish();
}

Medium parse_medium(JsonObject obj, const std::filesystem::path& base_dir) {
  Medium m;
  m.sigma_s = obj.rgb("sigma_s", m.sigma_s, {0, 1e6});
  m.sigma_a = obj.rgb("sigma_a", m.sigma_a, {0, 1e6});
  m.g = obj.number("g", 0.0, {-0.999, 0.999});
  m.ior = obj.number("ior", 1.0, {1.0, 4.0});
  if (auto d = obj.optional_object("density")) {
    m.density = parse_density(*d, base_dir);
    d->finish();
  } else {
    nlohmann::json constant = {{"type", "constant"}};
    JsonObject c(constant, obj.path("density"));
    m.density = parse_density(c, base_dir);
  }
  obj.finish();
  return m;
}

Light parse_light(JsonObject obj) {
  Light l;
  std::string type = obj.choice("type", {"point", "directional", "spot"}, std::nullopt);
  l.color = obj.rgb("color", l.color, kColor);
  if (type == "directional") {
    l.type = Light::Type::Directional;
    l.intensity = obj.number("irradiance", 1.0, {0, 1e9});
  } else {
    l.type = type == "point" ? Light::Type::Point : Light::Type::Spot;
    l.position = obj.vec3("position", std::nullopt, kCoord);
    l.intensity = obj.number("intensity", 10.0, {0, 1e12});
  }
  if (type != "point") {
    Vec3 d = obj.vec3("direction", std::nullopt, kCoord);
    if (length(d) < 1e-12) throw ValidationError(obj.path("direction"), "must not be zero");
    l.direction = normalize(d);
  }
  if (type == "spot") {
    l.inner_deg = obj.number("inner_deg", 20.0, {0, 90});
    l.outer_deg = obj.number("outer_deg", 30.0, {1e-3, 90});
    if (l.inner_deg > l.outer_deg)
      throw ValidationError(obj.path("inner_deg"), "must not exceed outer_deg");
  }
  obj.finish();
  return l;
}

Camera parse_camera(JsonObject obj) {
  Camera c;
  c.position = obj.vec3("position", c.position, kCoord);
  c.target = obj.vec3("target", c.target, kCoord);
  c.up = obj.vec3("up", c.up, kCoord);
  c.fov_deg = obj.number("fov_deg", c.fov_deg, {1, 170});
  if (length(c.target - c.position) < 1e-9)
    throw ValidationError(obj.path("target"), "must differ from position");
  if (length(cross(normalize(c.target - c.position), c.up)) < 1e-6)
    throw ValidationError(obj.path("up"), "must not be parallel to the viewing direction");
  obj.finish();
  return c;
}

SurfaceMaterial parse_surface(JsonObject obj) {
  SurfaceMaterial s;
  s.diffuse = obj.rgb("diffuse", s.diffuse, {0, 1});
  s.specular = obj.rgb("specular", s.specular, {0, 1});
  s.shininess = obj.number("shininess", s.shininess, {1, 1e4});
  obj.finish();
  return s;
}

}  // namespace

Scene parse_scene(const nlohmann::json& json, const std::filesystem::path& base_dir,
                  const SceneLimits& limits) {
  JsonObject root(json, "scene");
  Scene scene;
  parse_mesh(root.object("mesh"), base_dir, scene);
  scene.mesh_id = mesh_digest(*scene.mesh);
  scene.medium = parse_medium(root.object("medium"), base_dir);
  scene.lights = parse_lights(root.array("lights", 0, static_cast<size_t>(limits.max_lights)),
                              root.path("lights"), limits);
  if (auto cam = root.optional_object("camera")) scene.camera = parse_camera(*cam);
  if (auto img = root.optional_object("image")) {
    Range side{1, double(limits.max_image)};
    scene.width = img->integer("width", 512, side);
    scene.height = img->integer("height", 512, side);
    img->finish();
  }
  scene.voxels = root.integer("voxels", 64, {4, double(limits.max_voxels)});
  scene.background = root.rgb("background", Vec3{}, kColor);
  if (auto s = root.optional_object("surface")) scene.surface = parse_surface(*s);
  root.finish();
  return scene;
}

std::vector<Light> parse_lights(const nlohmann::json& lights, const std::string& path,
                                const SceneLimits& limits) {
  if (!lights.is_array() || lights.size() > static_cast<size_t>(limits.max_lights))
    throw ValidationError(
        path, "must be an array of at most " + std::to_string(limits.max_lights) + " lights");
  std::vector<Light> out;
  for (size_t i = 0; i < lights.size(); ++i)
    out.push_back(parse_light(JsonObject(lights[i], path + "[" + std::to_string(i) + "]")));
  return out;
}

double spot_cone(const Light& l, const Vec3& d) {
  if (l.type != Light::Type::Spot) return 1;
  const double lo = std::cos(l.outer_deg * std::numbers::pi / 180);
  const double hi = std::cos(l.inner_deg * std::numbers::pi / 180);
  const double x = dot(d, normalize(l.direction));
  if (hi <= lo) return x >= lo ? 1 : 0;
  const double t = std::clamp((x - lo) / (hi - lo), 0.0, 1.0);
  return t * t * (3 - 2 * t);
}

CameraFrame camera_frame(const Camera& c, int width, int height) {
  Vec3 f = normalize(c.target - c.position);
  Vec3 r = normalize(cross(f, c.up));
  Vec3 u = cross(r, f);
  double t = std::tan(c.fov_deg * std::numbers::pi / 360);
  return {f, r * (t * width / height), u * t};
}

Scene load_scene(const std::filesystem::path& path, const SceneLimits& limits) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open scene file " + path.string());
  std::string text((std::istreambuf_iterator<char>(in)), {});
  return parse_scene(parse_json(text, path.string()), path.parent_path(), limits);
}

}  // namespace scatter
