// float32 kernels against a float64 CPU computation of the same thing, over the extremes of the
// stress suite (docs/STRESS.md): the single-scattered radiance of a homogeneous box lit by a
// directional light, index matched, which has a closed form per view ray. The reference's
// marcher (OpenCL) and thickness (OpenGL) compute it in float32.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "../unit/test_util.hpp"
#include "pipelines/registry.hpp"
#include "stress_bounds.hpp"
#include "stress_scenes.hpp"

namespace scatter::stress {
namespace {

// Exit distance from x (inside the box [-h, h]^3) along w, through face axis k: linear in x.
double face_distance(const Vec3& x, const Vec3& w, double h, int k) {
  return ((w[k] > 0 ? h : -h) - x[k]) / w[k];
}

// The single-scattered radiance along o + t d through the homogeneous box [-h, h]^3 lit by a
// directional light from -w (w points to the light), in double: along the view segment the
// light's path length l(t) is the smallest of three linear functions, so the integrand
// exp(-sigma_t ((t - t0) + l(t))) is exp of a piecewise-linear function, integrated exactly
// piece by piece between the points where the exit face changes.
double box_single(Vec3 o, Vec3 d, Vec3 w, double h, double ss, double st, double e, double g) {
  double t0 = -INFINITY, t1 = INFINITY;
  for (int k = 0; k < 3; ++k) {
    if (d[k] == 0) {
      if (std::abs(o[k]) > h) return 0;
      continue;
    }
    double a = (-h - o[k]) / d[k], b = (h - o[k]) / d[k];
    t0 = std::max(t0, std::min(a, b));
    t1 = std::min(t1, std::max(a, b));
  }
  t0 = std::max(t0, 0.0);
  if (!(t1 > t0)) return 0;
  std::vector<double> cuts = {t0, t1};
  for (int i = 0; i < 3; ++i)
    for (int j = i + 1; j < 3; ++j) {
      if (w[i] == 0 || w[j] == 0) continue;
      // l_i(t) = l_j(t): both linear in t.
      auto l = [&](int k, double t) { return face_distance(o + d * t, w, h, k); };
      double c0 = l(i, 0) - l(j, 0), c1 = l(i, 1) - l(j, 1) - c0;
      if (c1 != 0 && -c0 / c1 > t0 && -c0 / c1 < t1) cuts.push_back(-c0 / c1);
    }
  std::sort(cuts.begin(), cuts.end());
  double sum = 0;
  for (size_t k = 0; k + 1 < cuts.size(); ++k) {
    double a = cuts[k], b = cuts[k + 1];
    if (b <= a) continue;
    // The face the light leaves through on this piece: l_k is linear on it.
    int face = -1;
    double nearest = INFINITY;
    for (int i = 0; i < 3; ++i) {
      double l = w[i] != 0 ? face_distance(o + d * ((a + b) / 2), w, h, i) : INFINITY;
      if (l < nearest) nearest = l, face = i;
    }
    auto exponent = [&](double t) {
      double l = face < 0 ? 0 : face_distance(o + d * t, w, h, face);
      return st * ((t - t0) + std::max(l, 0.0));
    };
    double fa = exponent(a), x = exponent(b) - fa;  // the exponent's rise over the piece
    double mean = std::abs(x) < 1e-12 ? 1 - x / 2 : -std::expm1(-x) / x;
    sum += std::exp(-fa) * (b - a) * mean;
  }
  return ss * e * hg(dot(w, d), g) * sum;
}

struct Case {
  double tau_voxel, scale, g, albedo;
  std::string light, camera;
};

std::string label(const Case& c) {
  std::ostringstream s;
  s << "tau=" << c.tau_voxel << " scale=" << c.scale << " g=" << c.g << " albedo=" << c.albedo
    << " light=" << c.light << " camera=" << c.camera;
  return s.str();
}

std::vector<Case> subset() {
  std::vector<Case> out;
  for (double tau : {1e-6, 1e-3, 0.1, 1.0, 10.0, 1e3})
    for (double scale : {1e-3, 1.0, 1e3}) out.push_back({tau, scale, 0.3, 0.8, "front", "axis"});
  for (double g : {-0.99, 0.0, 0.99})
    for (double tau : {1e-6, 1.0, 1e3}) out.push_back({tau, 1, g, 1 - 1e-6, "behind", "axis"});
  for (double tau : {1e-4, 0.5, 30.0}) {
    out.push_back({tau, 1, 0.5, 0.5, "front", "oblique"});
    out.push_back({tau, 1e2, -0.5, 0.5, "grazing", "oblique"});
  }
  // From inside the box: every view ray starts in the medium (the first surface is its exit).
  for (double tau : {1e-3, 1.0, 10.0}) {
    out.push_back({tau, 1, 0.3, 0.8, "front", "inside"});
    out.push_back({tau, 1e3, 0.9, 0.8, "behind", "inside"});
  }
  return out;
}

// The float64 image of the stress scene, and per pixel how much the value moves when the ray
// turns by 1e-5 rad (a float32 ray's direction is good to ~1e-7): a ray that grazes an edge of
// the box gains or loses a whole face for a turn that small, and float32 may decide either way.
struct CpuImage {
  Image value, spread;
};

CpuImage cpu_image(const Scene& scene, double h) {
  const Light& l = scene.lights.at(0);
  const Medium& m = scene.medium;
  CpuImage out{Image(scene.width, scene.height), Image(scene.width, scene.height)};
  CameraFrame f = camera_frame(scene.camera, scene.width, scene.height);
  const Vec3 turns[] = {{},
                        normalize(f.right) * 1e-5,
                        normalize(f.right) * -1e-5,
                        normalize(f.up) * 1e-5,
                        normalize(f.up) * -1e-5};
  for (int y = 0; y < scene.height; ++y)
    for (int x = 0; x < scene.width; ++x)
      for (int ch = 0; ch < 3; ++ch) {
        double lo = INFINITY, hi = -INFINITY, centre = 0;
        for (const Vec3& turn : turns) {
          Vec3 d = normalize(f.ray(x, y, scene.width, scene.height) + turn);
          double v = box_single(scene.camera.position, d, -l.direction, h, m.sigma_s[ch],
                                m.sigma_s[ch] + m.sigma_a[ch], l.intensity * l.color[ch], m.g);
          if (length(turn) == 0) centre = v;
          lo = std::min(lo, v);
          hi = std::max(hi, v);
        }
        size_t i = (size_t(y) * scene.width + x) * 3 + ch;
        out.value.rgb[i] = float(centre);
        out.spread.rgb[i] = float(hi - lo);
      }
  return out;
}

// |a - b| <= rtol b + atol max(b) + spread per pixel of `region` (x and y in [lo, hi]).
std::string compare(const Image& a, const CpuImage& b, double rtol, double atol, int lo, int hi) {
  double peak = *std::max_element(b.value.rgb.begin(), b.value.rgb.end());
  for (size_t i = 0; i < a.rgb.size(); ++i) {
    int x = int(i / 3) % a.width, y = int(i / 3) / a.width;
    if (x < lo || x > hi || y < lo || y > hi) continue;
    double ref = b.value.rgb[i], err = std::abs(double(a.rgb[i]) - ref);
    if (err <= rtol * ref + atol * peak + b.spread.rgb[i]) continue;
    std::ostringstream s;
    s << "pixel " << x << ", " << y << " channel " << i % 3 << ": " << a.rgb[i]
      << " against float64 " << ref << " (peak " << peak << ")";
    return s.str();
  }
  return "";
}

class Precision : public ::testing::TestWithParam<std::string> {};

INSTANTIATE_TEST_SUITE_P(Float32AgainstFloat64, Precision,
                         ::testing::Values("reference", "thickness"),
                         [](const auto& p) { return p.param; });

// The reference marches at step 0.01 voxels, where its discretisation is below 1e-4: each
// sub-step is exact for a light depth linear across it, and where the light's exit face changes
// within one the depth has a kink (at the default step 0.25 up to 0.3% off; at 0.05, 25% on a
// ray that runs 0.009 units between two faces by an edge, its light depth a tent over one
// sub-step). Thickness's shadow map and pieces per view segment add their own.
double rtol(const std::string& pipeline) {
  return pipeline == "reference" ? 2e-3 : 2e-2;
}

// The pixels compared: all for the reference. Thickness reads the light's path length from the
// nearest shadow-map texel's surface, its distance at the texel's centre carried to the point by
// the surface's slope: exact on a face, but where the box's edge (seen from the light) crosses a
// texel, the texel's face may not be the point's. Those pixels measure the map's resolution, not
// float32 (docs/STRESS.md, failures found and fixed: the oblique camera at sigma_t x voxel 30 has
// one, 0.71 of float64), so it is held to the axis camera's inner pixels, whose rays stay clear of
// the edges.
bool compared(const std::string& pipeline, const std::string& camera) {
  return pipeline == "reference" || camera == "axis" || camera == "inside";
}

TEST_P(Precision, HomogeneousBoxSingleTerm) {
  auto dir = test::scratch_dir("stress_precision_" + GetParam());
  auto pipeline = make_pipeline(GetParam(), test::shared_gpu());
  for (const Case& c : subset()) {
    Params p;
    p.tau_voxel = c.tau_voxel;
    p.scale = c.scale;
    p.g = c.g;
    p.albedo = c.albedo;
    p.light = c.light;
    p.camera = c.camera;
    p = accepted(p);
    Scene scene = parse_scene(scene_json(p, dir), dir);
    SCOPED_TRACE(label(c));
    if (!compared(GetParam(), c.camera)) continue;
    Settings s;
    if (GetParam() == "reference") s = {{"step", 0.01}};
    Image img = pipeline->render(scene, {Terms::Single, s, nullptr}).image;
    CpuImage cpu = cpu_image(scene, p.scale);
    if (std::getenv("SCATTER_STRESS_VERBOSE")) {
      std::printf("%s: centre %.7g against float64 %.7g; (1, 1) %.7g against %.7g\n",
                  label(c).c_str(), img.at(8, 8).x, cpu.value.at(8, 8).x, img.at(1, 1).x,
                  cpu.value.at(1, 1).x);
      for (int y = 0; y < 16 && std::getenv("SCATTER_STRESS_ROWS"); ++y) {
        for (int x = 0; x < 16; ++x)
          std::printf(" %5.2f", img.at(x, y).x / std::max(1e-30, double(cpu.value.at(x, y).x)));
        std::printf("\n");
      }
    }
    const bool all = GetParam() == "reference";
    std::string bad = compare(img, cpu, rtol(GetParam()), 1e-3, all ? 0 : 3, all ? 15 : 12);
    EXPECT_EQ(bad, "");
  }
}

}  // namespace
}  // namespace scatter::stress
