#include "pipelines/reference/exit_maps.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace scatter {
namespace {

Vec3 vertex(const FlatBvh& bvh, size_t tri, int k) {
  const float* p = &bvh.triangles[12 * tri + 4 * k];
  return {p[0], p[1], p[2]};
}

// Two unit axes orthogonal to w and to each other.
void plane_axes(const Vec3& w, Vec3& e1, Vec3& e2) {
  Vec3 h = std::abs(w.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
  e1 = normalize(cross(h, w));
  e2 = cross(w, e1);
}

}  // namespace

ExitMaps exit_maps(const FlatBvh& bvh, const std::vector<Light>& lights) {
  ExitMaps maps;
  const size_t tris = bvh.triangles.size() / 12;
  for (const Light& light : lights) {
    std::vector<float> h(kExitMapFloats, 0.f);
    h[11] = static_cast<float>(maps.first.size());
    if (light.type != Light::Type::Directional || tris == 0) {
      maps.header.insert(maps.header.end(), h.begin(), h.end());
      continue;
    }
    const Vec3 w = normalize(-light.direction);  // towards the light
    Vec3 e1, e2;
    plane_axes(w, e1, e2);
    // The light-facing triangles (outward normal towards the light) and their projections.
    std::vector<size_t> facing;
    std::vector<std::array<double, 4>> boxes;  // u0, u1, v0, v1
    double u_lo = 1e300, u_hi = -1e300, v_lo = 1e300, v_hi = -1e300, area = 0;
    for (size_t t = 0; t < tris; ++t) {
      Vec3 a = vertex(bvh, t, 0), b = vertex(bvh, t, 1), c = vertex(bvh, t, 2);
      Vec3 n = cross(b - a, c - a);
      if (dot(n, w) <= 0) continue;
      std::array<double, 4> box{1e300, -1e300, 1e300, -1e300};
      for (const Vec3& p : {a, b, c}) {
        box[0] = std::min(box[0], dot(p, e1)), box[1] = std::max(box[1], dot(p, e1));
        box[2] = std::min(box[2], dot(p, e2)), box[3] = std::max(box[3], dot(p, e2));
      }
      u_lo = std::min(u_lo, box[0]), u_hi = std::max(u_hi, box[1]);
      v_lo = std::min(v_lo, box[2]), v_hi = std::max(v_hi, box[3]);
      area += 0.5 * dot(n, w);
      facing.push_back(t);
      boxes.push_back(box);
    }
    if (facing.empty() || area <= 0) {
      maps.header.insert(maps.header.end(), h.begin(), h.end());
      continue;
    }
    // A cell half a triangle's projected size (a triangle's box then spans about 2.4 cells a
    // side: 3.6 triangles a cell, half of them tested before the hit); the box grown by a
    // millionth of its size so the corner cells' float32 projections stay inside.
    const double pad = 1e-6 * std::max(u_hi - u_lo, v_hi - v_lo);
    u_lo -= pad, u_hi += pad, v_lo -= pad, v_hi += pad;
    double cell = 0.5 * std::sqrt(area / double(facing.size()));
    cell = std::max({cell, (u_hi - u_lo) / 1024, (v_hi - v_lo) / 1024});
    const int nu = std::max(1, int(std::ceil((u_hi - u_lo) / cell)));
    const int nv = std::max(1, int(std::ceil((v_hi - v_lo) / cell)));
    std::vector<std::vector<int32_t>> lists(size_t(nu) * nv);
    // Each triangle in every cell its projection's box overlaps, grown by a hundredth of a cell
    // (the kernel's float32 projection).
    const double grow = 0.01 * cell;
    for (size_t k = 0; k < facing.size(); ++k) {
      const auto& b = boxes[k];
      int i0 = std::clamp(int(std::floor((b[0] - grow - u_lo) / cell)), 0, nu - 1);
      int i1 = std::clamp(int(std::floor((b[1] + grow - u_lo) / cell)), 0, nu - 1);
      int j0 = std::clamp(int(std::floor((b[2] - grow - v_lo) / cell)), 0, nv - 1);
      int j1 = std::clamp(int(std::floor((b[3] + grow - v_lo) / cell)), 0, nv - 1);
      for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i) lists[size_t(j) * nu + i].push_back(int32_t(facing[k]));
    }
    h = {float(e1.x),     float(e1.y), float(e1.z), float(e2.x),
         float(e2.y),     float(e2.z), float(u_lo), float(v_lo),
         float(1 / cell), float(nu),   float(nv),   float(maps.first.size())};
    for (const auto& l : lists) {
      maps.first.push_back(int32_t(maps.triangles.size()));
      maps.triangles.insert(maps.triangles.end(), l.begin(), l.end());
    }
    maps.header.insert(maps.header.end(), h.begin(), h.end());
  }
  maps.first.push_back(int32_t(maps.triangles.size()));
  return maps;
}

double exit_map_hit(const ExitMaps& maps, const FlatBvh& bvh, int light, const Vec3& o) {
  const float* h = &maps.header[size_t(kExitMapFloats) * light];
  const int nu = int(h[9]), nv = int(h[10]);
  if (nu == 0) return -1;
  const Vec3 e1{h[0], h[1], h[2]}, e2{h[3], h[4], h[5]};
  const Vec3 w = cross(e1, e2);
  int i = int(std::floor((dot(o, e1) - h[6]) * h[8]));
  int j = int(std::floor((dot(o, e2) - h[7]) * h[8]));
  if (i < 0 || j < 0 || i >= nu || j >= nv) return -1;
  const size_t cell = size_t(h[11]) + size_t(j) * nu + i;
  for (int k = maps.first[cell]; k < maps.first[cell + 1]; ++k) {
    double t = triangle_ray_hit(&bvh.triangles[12 * size_t(maps.triangles[k])], o, w);
    if (t > 0) return t;
  }
  return -1;
}

}  // namespace scatter
