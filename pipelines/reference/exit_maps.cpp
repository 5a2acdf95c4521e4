#include "pipelines/reference/exit_maps.hpp"

#include <algorithm>
#include <array>
#include <bit>
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

// How a light's map projects a point: onto the plane normal to a directional light, or from a
// point (or spot) light onto the plane one unit along its axis w (a perspective: a triangle
// stays a triangle while every point lies in front, dot(p - L, w) > 0).
struct Projection {
  bool point = false;
  Vec3 e1, e2, w, light;
  std::array<double, 2> operator()(const Vec3& p) const {
    if (!point) return {dot(p, e1), dot(p, e2)};
    const Vec3 q = p - light;
    const double z = dot(q, w);
    return {dot(q, e1) / z, dot(q, e2) / z};
  }
};

}  // namespace

ExitMaps exit_maps(const FlatBvh& bvh, const std::vector<Light>& lights) {
  ExitMaps maps;
  const size_t tris = bvh.triangles.size() / 12;
  Aabb bounds;
  for (size_t t = 0; t < tris; ++t)
    for (int k = 0; k < 3; ++k) bounds.add(vertex(bvh, t, k));
  for (const Light& light : lights) {
    std::vector<float> h(kExitMapFloats, 0.f);
    h[11] = std::bit_cast<float>(int32_t(maps.first.size()));
    auto no_map = [&] { maps.header.insert(maps.header.end(), h.begin(), h.end()); };
    if (tris == 0) {
      no_map();
      continue;
    }
    Projection proj;
    proj.point = light.type != Light::Type::Directional;
    proj.light = light.position;
    // towards a directional light; from a point (spot) light to the mesh
    proj.w = proj.point ? bounds.center() - light.position : -light.direction;
    if (length(proj.w) <= 0) {
      no_map();
      continue;
    }
    proj.w = normalize(proj.w);
    plane_axes(proj.w, proj.e1, proj.e2);
    // A point light's map needs the whole mesh in front of the light (then the light is
    // outside it, and the perspective keeps triangles whole).
    bool in_front = true;
    const double margin = 1e-6 * length(bounds.size());
    if (proj.point)
      for (size_t t = 0; t < tris && in_front; ++t)
        for (int k = 0; k < 3; ++k)
          in_front = in_front && dot(vertex(bvh, t, k) - light.position, proj.w) > margin;
    if (!in_front) {
      no_map();
      continue;
    }
    // The light-facing triangles (outward normal towards the light) and their projections.
    std::vector<size_t> facing;
    std::vector<std::array<double, 4>> boxes;  // u0, u1, v0, v1
    double u_lo = 1e300, u_hi = -1e300, v_lo = 1e300, v_hi = -1e300, area = 0;
    for (size_t t = 0; t < tris; ++t) {
      Vec3 a = vertex(bvh, t, 0), b = vertex(bvh, t, 1), c = vertex(bvh, t, 2);
      Vec3 n = cross(b - a, c - a);
      if (dot(n, proj.point ? light.position - a : proj.w) <= 0) continue;
      std::array<double, 4> box{1e300, -1e300, 1e300, -1e300};
      const std::array<std::array<double, 2>, 3> q = {proj(a), proj(b), proj(c)};
      for (const auto& uv : q) {
        box[0] = std::min(box[0], uv[0]), box[1] = std::max(box[1], uv[0]);
        box[2] = std::min(box[2], uv[1]), box[3] = std::max(box[3], uv[1]);
      }
      u_lo = std::min(u_lo, box[0]), u_hi = std::max(u_hi, box[1]);
      v_lo = std::min(v_lo, box[2]), v_hi = std::max(v_hi, box[3]);
      area += 0.5 * std::abs((q[1][0] - q[0][0]) * (q[2][1] - q[0][1]) -
                             (q[1][1] - q[0][1]) * (q[2][0] - q[0][0]));
      facing.push_back(t);
      boxes.push_back(box);
    }
    if (facing.empty() || area <= 0) {
      no_map();
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
    const Vec3 &e1 = proj.e1, &e2 = proj.e2, &l = light.position;
    h = {
        float(e1.x),     float(e1.y), float(e1.z), float(e2.x),
        float(e2.y),     float(e2.z), float(u_lo), float(v_lo),
        float(1 / cell), float(nu),   float(nv),   std::bit_cast<float>(int32_t(maps.first.size())),
        float(l.x),      float(l.y),  float(l.z),  float(proj.point)};
    for (const auto& list : lists) {
      maps.first.push_back(int32_t(maps.triangles.size()));
      maps.triangles.insert(maps.triangles.end(), list.begin(), list.end());
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
  Projection proj;
  proj.e1 = {h[0], h[1], h[2]}, proj.e2 = {h[3], h[4], h[5]};
  proj.w = cross(proj.e1, proj.e2);
  proj.point = h[15] > 0;
  proj.light = {h[12], h[13], h[14]};
  if (proj.point && dot(o - proj.light, proj.w) <= 0) return -1;
  const auto uv = proj(o);
  const int i = int(std::floor((uv[0] - h[6]) * h[8]));
  const int j = int(std::floor((uv[1] - h[7]) * h[8]));
  if (i < 0 || j < 0 || i >= nu || j >= nv) return -1;
  const Vec3 d = proj.point ? normalize(proj.light - o) : proj.w;
  const size_t cell = size_t(std::bit_cast<int32_t>(h[11])) + size_t(j) * nu + i;
  for (int k = maps.first[cell]; k < maps.first[cell + 1]; ++k) {
    double t = triangle_ray_hit(&bvh.triangles[12 * size_t(maps.triangles[k])], o, d);
    if (t > 0) return t;
  }
  return -1;
}

}  // namespace scatter
