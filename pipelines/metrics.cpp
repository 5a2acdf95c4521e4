#include "pipelines/metrics.hpp"

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

namespace scatter {
namespace {

// Whether the ray o + t d (t >= 0) crosses an occupied voxel: slab test against the grid's box,
// then a walk through the voxels (Amanatides-Woo).
bool hits_occupied(const VoxelGrid& g, const Vec3& o, const Vec3& d) {
  int n[3] = {g.nx, g.ny, g.nz};
  double t0 = 0, t1 = 1e300;
  for (int a = 0; a < 3; ++a) {
    double lo = g.origin[a], hi = g.origin[a] + n[a] * g.voxel;
    if (d[a] == 0) {
      if (o[a] < lo || o[a] > hi) return false;
      continue;
    }
    double ta = (lo - o[a]) / d[a], tb = (hi - o[a]) / d[a];
    t0 = std::max(t0, std::min(ta, tb));
    t1 = std::min(t1, std::max(ta, tb));
  }
  if (t1 <= t0) return false;
  Vec3 p = o + d * t0;
  int cell[3], step[3];
  double tmax[3], tdelta[3];
  for (int a = 0; a < 3; ++a) {
    cell[a] = std::clamp(static_cast<int>(std::floor((p[a] - g.origin[a]) / g.voxel)), 0, n[a] - 1);
    step[a] = d[a] >= 0 ? 1 : -1;
    double next = g.origin[a] + (cell[a] + (d[a] >= 0 ? 1 : 0)) * g.voxel;
    tdelta[a] = d[a] != 0 ? g.voxel / std::abs(d[a]) : 1e300;
    tmax[a] = d[a] != 0 ? (next - o[a]) / d[a] : 1e300;
  }
  for (;;) {
    if (g.occupancy[g.index(cell[0], cell[1], cell[2])] > 0) return true;
    int a = tmax[0] < tmax[1] ? (tmax[0] < tmax[2] ? 0 : 2) : (tmax[1] < tmax[2] ? 1 : 2);
    if (tmax[a] > t1) return false;
    cell[a] += step[a];
    if (cell[a] < 0 || cell[a] >= n[a]) return false;
    tmax[a] += tdelta[a];
  }
}

void check_sizes(const Image& a, const Image& b, const std::vector<uint8_t>& mask) {
  if (a.width != b.width || a.height != b.height || mask.size() != size_t(a.width) * a.height)
    throw std::invalid_argument("images of different sizes cannot be compared");
}

}  // namespace

std::vector<uint8_t> coverage_mask(const Scene& scene, const VoxelGrid& grid) {
  CameraFrame frame = camera_frame(scene.camera, scene.width, scene.height);
  std::vector<uint8_t> mask(size_t(scene.width) * scene.height);
  for (int y = 0; y < scene.height; ++y)
    for (int x = 0; x < scene.width; ++x)
      mask[size_t(y) * scene.width + x] =
          hits_occupied(grid, scene.camera.position, frame.ray(x, y, scene.width, scene.height));
  return mask;
}

double relative_norm(const Image& e, const Image& ref, const std::vector<uint8_t>& mask) {
  check_sizes(e, ref, mask);
  double num = 0, den = 0;
  for (size_t p = 0; p < mask.size(); ++p)
    if (mask[p])
      for (int c = 0; c < 3; ++c) {
        num += double(e.rgb[3 * p + c]) * e.rgb[3 * p + c];
        den += double(ref.rgb[3 * p + c]) * ref.rgb[3 * p + c];
      }
  if (den <= 0) throw std::invalid_argument("the reference image is black where the medium is");
  return std::sqrt(num / den);
}

double relative_norm(const Image& e, const Image& ref) {
  if (e.rgb.size() != ref.rgb.size()) throw std::invalid_argument("the images' sizes differ");
  double num = 0, den = 0;
  for (size_t i = 0; i < e.rgb.size(); ++i) {
    num += double(e.rgb[i]) * e.rgb[i];
    den += double(ref.rgb[i]) * ref.rgb[i];
  }
  if (den <= 0) return num > 0 ? std::numeric_limits<double>::infinity() : 0;  // nothing to see
  return std::sqrt(num / den);
}

double error_scatter(const Image& std_error) {
  double sum = 0, sum_sq = 0;
  for (size_t p = 0; 3 * p + 2 < std_error.rgb.size(); ++p) {
    double s = 0;
    for (int c = 0; c < 3; ++c) s += double(std_error.rgb[3 * p + c]) * std_error.rgb[3 * p + c];
    sum += s;
    sum_sq += s * s;
  }
  return sum > 0 ? std::sqrt(2 * sum_sq) / sum : 0;
}

double relative_rmse(const Image& a, const Image& ref, const std::vector<uint8_t>& mask) {
  check_sizes(a, ref, mask);
  Image diff(a.width, a.height);
  for (size_t i = 0; i < a.rgb.size(); ++i) diff.rgb[i] = a.rgb[i] - ref.rgb[i];
  return relative_norm(diff, ref, mask);
}

}  // namespace scatter
