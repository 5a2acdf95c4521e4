#include "pipelines/cost_support.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "scene/solid.hpp"

namespace scatter::cost {
namespace {

Aabb solid_bounds(const Scene& scene) {
  // make_solid's bounds without building the mesh solid's bins (scene/solid.cpp).
  return scene.shape ? scene.shape->bounds() : scene.mesh->bounds();
}

std::string fixed(double v, int digits) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

}  // namespace

std::string GridShape::text() const {
  if (nx == ny && ny == nz) return std::to_string(nx) + "^3";
  return std::to_string(nx) + "x" + std::to_string(ny) + "x" + std::to_string(nz);
}

GridShape grid_shape(const Scene& scene, int margin, int block) {
  GridShape g;
  Vec3 size = solid_bounds(scene).size();
  g.longest = std::max({size.x, size.y, size.z});
  const int res = std::max(scene.voxels, 1);
  if (!(g.longest > 0) || !std::isfinite(g.longest)) {
    g.nx = g.ny = g.nz = res + 2 * margin;  // voxelize() refuses it; count the worst
    return g;
  }
  g.voxel = g.longest / res;
  auto side = [&](double s) {
    int n = static_cast<int>(std::ceil(s / g.voxel)) + 2 * margin;
    return (n + block - 1) / block * block;
  };
  g.nx = side(size.x);
  g.ny = side(size.y);
  g.nz = side(size.z);
  return g;
}

// Measured (Release, 2 cores shared): sphere 130^3 0.48 s, 194^3 0.86 s, 258^3 1.1 s (~60-220 ns
// a voxel; boundary voxels are supersampled at 4^3 points); bunny (a mesh: crossings per column)
// 66^3 0.20 s (690 ns); under load from other builds sphere 258^3 took 6.3 s (370 ns). Taken
// at 300 and 1000 ns.
double voxelize_seconds(const Scene& scene, double voxels) {
  return voxels * (scene.shape ? 300e-9 : 1000e-9);
}

// Measured: 130^3 0.43 s, 194^3 0.82 s, 258^3 1.38 s (80-200 ns a voxel, the majorant kernel
// and three copies); plus ~0.3 s of kernel builds when PoCL's cache is cold.
double upload_seconds(double voxels) {
  return 0.3 + voxels * 200e-9;
}

void add_medium_upload(Ledger& l, const Scene& scene, const GridShape& g) {
  const double n = g.count();
  const std::string grid = g.text() + " voxels";
  l.host("scene.voxels", n * (kGridBytes + 12), grid + " x 41 B (grid, sigma_t)");
  l.device("scene.voxels", n * 48, grid + " x 48 B (sigma_s, sigma_t, majorant copies)");
  l.time("scene.voxels", voxelize_seconds(scene, n) + upload_seconds(n),
         grid + " voxelized and uploaded");
}

// Area of the convex hull of the bounding box's corners on the image plane (tangent units), or
// -1 when a corner lies behind the eye.
double box_hull_area(const Aabb& b, const Scene& scene) {
  CameraFrame f = camera_frame(scene.camera, scene.width, scene.height);
  Vec3 fwd = normalize(f.forward), right = normalize(f.right), up = normalize(f.up);
  std::vector<std::pair<double, double>> p;
  for (int c = 0; c < 8; ++c) {
    Vec3 corner{c & 1 ? b.hi.x : b.lo.x, c & 2 ? b.hi.y : b.lo.y, c & 4 ? b.hi.z : b.lo.z};
    Vec3 v = corner - scene.camera.position;
    double z = dot(v, fwd);
    if (!(z > 1e-9)) return -1;
    p.emplace_back(dot(v, right) / z, dot(v, up) / z);
  }
  // Monotone chain.
  std::sort(p.begin(), p.end());
  auto cross = [](auto o, auto a, auto c) {
    return (a.first - o.first) * (c.second - o.second) -
           (a.second - o.second) * (c.first - o.first);
  };
  std::vector<std::pair<double, double>> h(16);
  size_t k = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  for (size_t i = p.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  double area = 0;
  for (size_t i = 0; i + 1 < k; ++i)
    area += h[i].first * h[i + 1].second - h[i + 1].first * h[i].second;
  return std::abs(area) / 2;
}

double coverage(const Scene& scene) {
  Aabb b = solid_bounds(scene);
  const bool ball = scene.shape && scene.shape->kind == Shape::Kind::Sphere;
  double r = ball ? scene.shape->radius : length(b.size()) / 2;
  double d = length(scene.camera.position - b.center());
  if (!(d > r)) return 1.0;  // the eye inside the bounding sphere
  double t = std::tan(std::asin(r / d));
  double area = std::numbers::pi * t * t;  // the bounding sphere's disc
  double hull = ball ? -1 : box_hull_area(b, scene);
  if (hull >= 0) area = std::min(area, hull);
  double half = std::tan(scene.camera.fov_deg * std::numbers::pi / 360);
  double aspect = double(scene.width) / std::max(scene.height, 1);
  return std::clamp(area / (4 * half * half * aspect), 0.01, 1.0);
}

MediumBounds medium_bounds(const Scene& scene) {
  MediumBounds m;
  Aabb b = solid_bounds(scene);
  double dmax = 0, dmean = -1;
  const DensityField* field = scene.medium.density.get();
  if (!field) {
    dmax = 1;
  } else if (field->homogeneous()) {
    dmax = field->density(b.center());
  } else {
    double sum = 0;
    int count = 0;
    for (int k = 0; k < 5; ++k)
      for (int j = 0; j < 5; ++j)
        for (int i = 0; i < 5; ++i) {
          Vec3 f{(i + 0.5) / 5, (j + 0.5) / 5, (k + 0.5) / 5};
          Vec3 p = b.lo + Vec3{f.x * b.size().x, f.y * b.size().y, f.z * b.size().z};
          if (field->blocked(p)) continue;
          double d = field->density(p);
          dmax = std::max(dmax, d);
          sum += d;
          ++count;
        }
    dmean = count ? sum / count : dmax;
    dmax *= 1.5;  // between the lattice points
  }
  if (dmean < 0) dmean = dmax;
  for (int c = 0; c < 3; ++c) {
    double s = scene.medium.sigma_s[c], t = s + scene.medium.sigma_a[c];
    m.sigma_s = std::max(m.sigma_s, s * dmax);
    m.sigma_t = std::max(m.sigma_t, t * dmax);
    m.mean_sigma_t = std::max(m.mean_sigma_t, t * dmean);
    if (t > 0) m.albedo = std::max(m.albedo, s / t);
  }
  return m;
}

std::string bytes_text(double b) {
  if (b >= 1e9) return fixed(b / 1e9, b >= 1e10 ? 0 : 1) + " GB";
  if (b >= 1e6) return fixed(b / 1e6, 0) + " MB";
  return fixed(b / 1e3, 0) + " kB";
}

std::string seconds_text(double s) {
  if (s >= 100) return fixed(s, 0) + " s";
  if (s >= 1) return fixed(s, 1) + " s";
  return fixed(s * 1e3, 0) + " ms";
}

void Ledger::host(const std::string& field, double bytes, const std::string& what) {
  memory_.push_back({field, what, bytes, false});
}
void Ledger::device(const std::string& field, double bytes, const std::string& what) {
  memory_.push_back({field, what, bytes, true});
}
void Ledger::time(const std::string& field, double seconds, const std::string& what) {
  time_.push_back({field, what, seconds, false});
}

double Ledger::bytes() const {
  double s = 0;
  for (const Term& t : memory_) s += t.amount;
  return s;
}

void Ledger::peak_of(const Ledger& other) {
  if (other.bytes() > bytes()) memory_ = other.memory_;
  time_.insert(time_.end(), other.time_.begin(), other.time_.end());
}

CostEstimate Ledger::finish(const std::string& pipeline) const {
  CostEstimate e;
  const Term* mem = nullptr;
  const Term* slow = nullptr;
  for (const Term& t : memory_) {
    (t.device ? e.device_bytes : e.host_bytes) += t.amount;
    if (!mem || t.amount > mem->amount) mem = &t;
  }
  for (const Term& t : time_) {
    e.seconds += t.amount;
    if (!slow || t.amount > slow->amount) slow = &t;
  }
  e.summary = pipeline + ": " + bytes_text(e.bytes()) + ", " + seconds_text(e.seconds);
  if (mem) {
    e.memory_field = mem->field;
    e.summary +=
        "; most memory: " + mem->what + " = " + bytes_text(mem->amount) + " (" + mem->field + ")";
  }
  if (slow) {
    e.time_field = slow->field;
    e.summary += "; most time: " + slow->what + " ~ " + seconds_text(slow->amount) + " (" +
                 slow->field + ")";
  }
  return e;
}

}  // namespace scatter::cost
