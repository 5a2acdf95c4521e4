#include "stress_scenes.hpp"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>

#include "core/errors.hpp"
#include "pipelines/pipeline.hpp"
#include "scene/scene.hpp"

namespace scatter::stress {
namespace {

constexpr double kMaxSigma = 1e6;  // parse_medium's bound on sigma_s and sigma_a

std::string num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// The object's bounding box's longest side, in units of `scale`.
double longest_side(const Params& p) {
  return p.shape == "torus" ? 2 * (0.6 + 0.25) : 2.0;
}

nlohmann::json mesh_json(const Params& p) {
  const double s = p.scale;
  if (p.shape == "sphere") return {{"shape", "sphere"}, {"radius", s}};
  if (p.shape == "torus")
    return {{"shape", "torus"},
            {"major_radius", 0.6 * s},
            {"minor_radius", 0.25 * s},
            {"axis", {0.3, 1, 0.2}}};
  // slab: one voxel thick along z (voxels count along the longest side, 2 s).
  double z = p.shape == "slab" ? 2.0 / p.voxels : 2.0;
  return {{"shape", "box"}, {"size", {2 * s, 2 * s, z * s}}};
}

// A hollow sphere of radius `scale` whose density is 1 in its outermost voxel layer only,
// written once per scale and resolution as a grid file under `dir`.
std::string shell_grid(const Params& p, const std::filesystem::path& dir) {
  const int n = p.voxels;
  std::string stem = "shell_" + num(p.scale) + "_" + std::to_string(n);
  std::filesystem::path header = dir / (stem + ".json");
  if (std::filesystem::exists(header)) return header.string();
  std::vector<float> data(size_t(n) * n * n);
  const double h = 2.0 / n;  // voxel size in units of the scale
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        double x = -1 + (i + 0.5) * h, y = -1 + (j + 0.5) * h, z = -1 + (k + 0.5) * h;
        double r = std::sqrt(x * x + y * y + z * z);
        data[(size_t(k) * n + j) * n + i] = r <= 1 && r > 1 - h ? 1.f : 0.f;
      }
  std::ofstream(dir / (stem + ".raw"), std::ios::binary)
      .write(reinterpret_cast<const char*>(data.data()), std::streamsize(data.size() * 4));
  const double s = p.scale;
  nlohmann::json j = {{"dims", {n, n, n}},
                      {"format", "float32"},
                      {"data", stem + ".raw"},
                      {"bounds", {{"min", {-s, -s, -s}}, {"max", {s, s, s}}}}};
  std::ofstream(header) << j.dump();
  return header.string();
}

nlohmann::json density_json(const Params& p, const std::filesystem::path& dir) {
  const double s = p.scale;
  if (p.density == "layers")
    return {{"type", "layers"},
            {"axis", {0, 1, 0}},
            {"thickness", 0.25 * s},
            {"values", {1, 0, 1e-3, 0.5}}};
  if (p.density == "noise")
    return {{"type", "noise"}, {"scale", 3 / s}, {"min", 0}, {"max", 1}, {"seed", 7}};
  if (p.density == "blocker")
    return {{"type", "blocker"},
            {"shape", {{"shape", "sphere"}, {"radius", 0.5 * s}}},
            {"sigma_a", kMaxSigma}};
  if (p.density == "shell") return {{"type", "grid"}, {"file", shell_grid(p, dir)}};
  return {{"type", "constant"}};
}

// The light classes; positions and directions scale with the object.
nlohmann::json light_json(const Params& p) {
  const double s = p.scale;
  const nlohmann::json c = {p.color, p.color, p.color};
  auto directional = [&](nlohmann::json d) {
    return nlohmann::json{
        {"type", "directional"}, {"direction", d}, {"color", c}, {"irradiance", p.power}};
  };
  auto point = [&](double x, double y, double z) {
    return nlohmann::json{{"type", "point"},
                          {"position", {x * s, y * s, z * s}},
                          {"color", c},
                          {"intensity", p.power}};
  };
  const std::string& l = p.light;
  if (l == "behind")
    return nlohmann::json::array({directional({0, 0, 1})});  // travels into the camera
  if (l == "grazing")
    return nlohmann::json::array({directional({1, 0, 0})});  // along the faces z = +-1
  if (l == "grazing_top")
    return nlohmann::json::array({directional({1, -1e-4, 0})});                     // skims y = 1
  if (l == "point_inside") return nlohmann::json::array({point(0.1, -0.2, 0.05)});  // in the medium
  if (l == "point_surface")
    return nlohmann::json::array({point(0, 0, 1)});  // on the box's front face
  if (l == "point_near")
    return nlohmann::json::array({point(0.2, 0.1, 1 + 1e-4)});  // just outside the front face
  if (l == "point_far") return nlohmann::json::array({point(3, 4, 6)});
  if (l == "spot_inside")
    return nlohmann::json::array({{{"type", "spot"},
                                   {"position", {0, 0, 0}},
                                   {"direction", {0, 0, 1}},
                                   {"color", c},
                                   {"intensity", p.power},
                                   {"inner_deg", 0},
                                   {"outer_deg", 1e-3}}});
  if (l == "many") {  // the most lights a scene may hold, from all around
    nlohmann::json all = nlohmann::json::array();
    for (int k = 0; k < 16; ++k) {
      double a = 2.399963 * k, z = 1 - (2 * k + 1) / 16.0, r = std::sqrt(1 - z * z);
      all.push_back(directional({r * std::cos(a), r * std::sin(a), z}));
    }
    return all;
  }
  if (l == "none") return nlohmann::json::array();
  return nlohmann::json::array({directional({0.3, -0.4, -1})});  // front: from the camera's side
}

nlohmann::json camera_json(const Params& p) {
  const double s = p.scale;
  if (p.camera == "oblique")
    return {{"position", {2.1 * s, 1.7 * s, 2.9 * s}}, {"target", {0, 0, 0}}, {"fov_deg", 45}};
  if (p.camera == "inside")
    return {{"position", {0.1 * s, 0.2 * s, 0.3 * s}}, {"target", {0, 0, -s}}, {"fov_deg", 90}};
  return {{"position", {0, 0, 4 * s}}, {"target", {0, 0, 0}}, {"fov_deg", 40}};
}

StressCase make_case(const std::string& klass, const std::string& label, Params p,
                     const std::filesystem::path& dir) {
  StressCase c{klass + "/" + label, klass, p, {}, {}, {}};
  c.scene = scene_json(p, dir);
  try {
    parse_scene(c.scene, dir);
  } catch (const ValidationError& e) {
    c.rejected = std::string(e.what());
    c.params = accepted(p);
    c.scene = scene_json(c.params, dir);
  }
  return c;
}

// Values of each class; the long mode adds the ones in between.
struct Axes {
  std::vector<double> tau, albedo, g, ior, scale, power;
  std::vector<std::string> shapes, densities, lights, cameras;
};

Axes axes(Mode mode) {
  Axes a;
  a.tau = {1e-6, 1e-4, 1e-2, 1, 10, 100, 1e3};
  a.albedo = {0, 1e-6, 0.5, 1 - 1e-6, 1};
  a.g = {-0.99, -0.5, 0, 0.5, 0.99};
  a.ior = {1, 1.0001, 1.33, 2, 2.5};
  a.scale = {1e-3, 1e-2, 1, 1e2, 1e3};
  a.power = {0, 1e-12, 1e-6, 1, 1e6, 1e9};
  a.shapes = {"box", "sphere", "torus", "slab"};
  a.densities = {"const", "layers", "noise", "blocker", "shell"};
  a.lights = {"front",         "behind",     "grazing",   "grazing_top", "point_inside",
              "point_surface", "point_near", "point_far", "spot_inside", "many"};
  a.cameras = {"axis", "oblique", "inside"};
  if (mode == Mode::Long) {
    a.tau.insert(a.tau.end(), {1e-5, 1e-3, 0.1, 3, 30, 300});
    a.g.insert(a.g.end(), {-0.9, 0.9, -0.999, 0.999});
    a.ior.insert(a.ior.end(), {1.5, 4});
    a.scale.insert(a.scale.end(), {1e-1, 10});
    a.power.insert(a.power.end(), {1e-30, 1e3});
  }
  return a;
}

template <class T>
const T& pick(const std::vector<T>& v, std::mt19937& rng) {
  return v[std::uniform_int_distribution<size_t>(0, v.size() - 1)(rng)];
}

}  // namespace

Params accepted(Params p) {
  const double dx = longest_side(p) * p.scale / p.voxels;
  p.tau_voxel = std::min(p.tau_voxel, kMaxSigma * dx);
  return p;
}

Mode mode_from_env() {
  const char* v = std::getenv("SCATTER_STRESS");
  return v && std::string(v) == "long" ? Mode::Long : Mode::Quick;
}

nlohmann::json scene_json(const Params& p, const std::filesystem::path& data_dir) {
  const double dx = longest_side(p) * p.scale / p.voxels;
  const double st = p.tau_voxel / dx;
  return {{"mesh", mesh_json(p)},
          {"medium",
           {{"sigma_s", p.albedo * st},
            {"sigma_a", (1 - p.albedo) * st},
            {"g", p.g},
            {"ior", p.ior},
            {"density", density_json(p, data_dir)}}},
          {"lights", light_json(p)},
          {"camera", camera_json(p)},
          {"image", {{"width", p.image}, {"height", p.image}}},
          {"voxels", p.voxels}};
}

std::vector<StressCase> stress_cases(Mode mode, const std::filesystem::path& data_dir) {
  const Axes a = axes(mode);
  Params base;
  if (mode == Mode::Long) {
    base.voxels = 16;
    base.image = 24;
  }
  std::vector<StressCase> out;
  auto one = [&](const std::string& klass, const std::string& label, auto set) {
    Params p = base;
    set(p);
    out.push_back(make_case(klass, label, p, data_dir));
  };
  for (double v : a.tau) one("optical", "tau=" + num(v), [&](Params& p) { p.tau_voxel = v; });
  for (double v : a.tau)  // the thick ones against the grazing light too
    one("optical", "grazing_tau=" + num(v), [&](Params& p) {
      p.tau_voxel = v;
      p.light = "grazing";
    });
  for (double v : a.albedo) {
    one("albedo", "albedo=" + num(v), [&](Params& p) { p.albedo = v; });
    one("albedo", "thick_albedo=" + num(v), [&](Params& p) {
      p.albedo = v;
      p.tau_voxel = 10;
    });
  }
  for (double v : a.g) {
    one("phase", "g=" + num(v), [&](Params& p) { p.g = v; });
    one("phase", "behind_g=" + num(v), [&](Params& p) {  // the forward peak in the camera
      p.g = v;
      p.light = "behind";
    });
  }
  for (double v : a.ior) {
    one("ior", "ior=" + num(v), [&](Params& p) { p.ior = v; });
    one("ior", "sphere_ior=" + num(v), [&](Params& p) {
      p.ior = v;
      p.shape = "sphere";
    });
  }
  for (double v : a.scale) {
    one("scale", "scale=" + num(v), [&](Params& p) { p.scale = v; });
    one("scale", "point_scale=" + num(v), [&](Params& p) {
      p.scale = v;
      p.light = "point_far";
    });
    one("scale", "ior_scale=" + num(v), [&](Params& p) {
      p.scale = v;
      p.ior = 1.5;
    });
  }
  for (double v : {1e-6, 1.0, 1e3}) {
    one("shell", "slab_tau=" + num(v), [&](Params& p) {
      p.shape = "slab";
      p.tau_voxel = v;
    });
    one("shell", "sphere_shell_tau=" + num(v), [&](Params& p) {
      p.shape = "sphere";
      p.density = "shell";
      p.tau_voxel = v;
    });
  }
  one("shell", "slab_edge_on", [&](Params& p) {
    p.shape = "slab";
    p.camera = "oblique";
    p.light = "grazing";
  });
  for (const std::string& l : a.lights) one("light", l, [&](Params& p) { p.light = l; });
  one("light", "point_inside_ior", [&](Params& p) {
    p.light = "point_inside";
    p.ior = 2.5;
  });
  for (const std::string& c : a.cameras)
    one("camera", "camera_" + c, [&](Params& p) { p.camera = c; });
  for (double v : a.power) {
    one("intensity", "directional=" + num(v), [&](Params& p) { p.power = v; });
    one("intensity", "point_inside=" + num(v * 1e3), [&](Params& p) {
      p.power = v * 1e3;  // up to 1e12, the parser's bound for point lights
      p.light = "point_inside";
    });
  }
  one("intensity", "color=1e6_irradiance=1e9", [&](Params& p) {
    p.color = 1e6;
    p.power = 1e9;
  });
  one("intensity", "color=1e6_point_inside=1e12", [&](Params& p) {
    p.color = 1e6;
    p.power = 1e12;
    p.light = "point_inside";
  });
  one("intensity", "color=1e-12", [&](Params& p) { p.color = 1e-12; });

  // Every class scene goes to every pipeline; each mixture to one, in turn.
  const std::vector<std::string> all = pipeline_names();
  for (StressCase& c : out) c.pipelines = all;
  std::mt19937 rng(20261202);
  const int mixtures = (mode == Mode::Long ? 2000 : 560) - int(out.size());
  for (int k = 0; k < mixtures; ++k) {
    Params p = base;
    p.tau_voxel = pick(a.tau, rng);
    p.albedo = pick(a.albedo, rng);
    p.g = pick(a.g, rng);
    p.ior = k % 3 == 0 ? pick(a.ior, rng) : 1.0;  // a third dielectric
    p.scale = pick(a.scale, rng);
    p.shape = pick(a.shapes, rng);
    p.density = pick(a.densities, rng);
    p.light = pick(a.lights, rng);
    p.camera = k % 7 == 0 ? "inside" : pick(a.cameras, rng);
    p.power = pick(a.power, rng) * (p.light.rfind("point", 0) == 0 ? 1e3 : 1);
    if (p.density == "shell") p.shape = "sphere";
    StressCase c = make_case("mixed", std::to_string(k), p, data_dir);
    c.pipelines = {all[size_t(k) % all.size()]};
    out.push_back(std::move(c));
  }
  return out;
}

}  // namespace scatter::stress
