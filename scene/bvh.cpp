#include "scene/bvh.hpp"

#include <algorithm>
#include <numeric>

namespace scatter {
namespace {

struct Builder {
  const Mesh& mesh;
  std::vector<Vec3> centroids;
  std::vector<uint32_t> order;
  FlatBvh out;

  Aabb triangle_bounds(uint32_t t) const {
    Aabb b;
    for (int k = 0; k < 3; ++k) b.add(mesh.positions[mesh.indices[3 * t + k]]);
    return b;
  }

  void emit_bounds(size_t node, const Aabb& b) {
    for (int a = 0; a < 3; ++a) {
      out.bounds[8 * node + a] = static_cast<float>(b.lo[a]);
      out.bounds[8 * node + 4 + a] = static_cast<float>(b.hi[a]);
    }
  }

  // Builds the subtree over order[first, first + count) and returns its node index.
  size_t build(size_t first, size_t count) {
    size_t node = out.links.size() / 2;
    out.links.resize(out.links.size() + 2);
    out.bounds.resize(out.bounds.size() + 8, 0.f);
    Aabb b, cb;
    for (size_t i = first; i < first + count; ++i) {
      Aabb tb = triangle_bounds(order[i]);
      b.add(tb.lo);
      b.add(tb.hi);
      cb.add(centroids[order[i]]);
    }
    emit_bounds(node, b);
    Vec3 extent = cb.size();
    int axis = extent.x > extent.y ? (extent.x > extent.z ? 0 : 2) : (extent.y > extent.z ? 1 : 2);
    if (count <= 4 || extent[axis] <= 0) {
      out.links[2 * node] = static_cast<int32_t>(out.triangles.size() / 12);
      out.links[2 * node + 1] = static_cast<int32_t>(count);
      for (size_t i = first; i < first + count; ++i)
        for (int k = 0; k < 3; ++k) {
          const Vec3& v = mesh.positions[mesh.indices[3 * order[i] + k]];
          out.triangles.insert(out.triangles.end(), {float(v.x), float(v.y), float(v.z), 0.f});
        }
      return node;
    }
    size_t half = count / 2;
    std::nth_element(
        order.begin() + first, order.begin() + first + half, order.begin() + first + count,
        [&](uint32_t x, uint32_t y) { return centroids[x][axis] < centroids[y][axis]; });
    build(first, half);
    size_t second = build(first + half, count - half);
    out.links[2 * node] = static_cast<int32_t>(second);
    out.links[2 * node + 1] = 0;
    return node;
  }
};

bool box_hit(const float* b, const Vec3& o, const Vec3& d, double t_min, double t_max) {
  for (int a = 0; a < 3; ++a) {
    double inv = 1.0 / d[a];
    double t0 = (b[a] - o[a]) * inv, t1 = (b[4 + a] - o[a]) * inv;
    if (t0 > t1) std::swap(t0, t1);
    t_min = std::max(t_min, t0);
    t_max = std::min(t_max, t1);
  }
  return t_min <= t_max;
}

}  // namespace

double triangle_ray_hit(const float* t, const Vec3& o, const Vec3& d) {
  Vec3 v0{t[0], t[1], t[2]}, v1{t[4], t[5], t[6]}, v2{t[8], t[9], t[10]};
  Vec3 e1 = v1 - v0, e2 = v2 - v0, p = cross(d, e2);
  double det = dot(e1, p);
  if (std::abs(det) < 1e-20) return -1;
  Vec3 s = o - v0;
  double u = dot(s, p) / det;
  if (u < 0 || u > 1) return -1;
  Vec3 q = cross(s, e1);
  double v = dot(d, q) / det;
  if (v < 0 || u + v > 1) return -1;
  return dot(e2, q) / det;
}

FlatBvh build_bvh(const Mesh& mesh) {
  Builder b{mesh, {}, {}, {}};
  size_t n = mesh.triangle_count();
  b.centroids.resize(n);
  for (size_t t = 0; t < n; ++t)
    b.centroids[t] =
        (mesh.positions[mesh.indices[3 * t]] + mesh.positions[mesh.indices[3 * t + 1]] +
         mesh.positions[mesh.indices[3 * t + 2]]) /
        3.0;
  b.order.resize(n);
  std::iota(b.order.begin(), b.order.end(), 0u);
  if (n > 0) b.build(0, n);
  return std::move(b.out);
}

double bvh_closest_hit(const FlatBvh& bvh, const Vec3& o, const Vec3& d, double t_min,
                       double t_max) {
  if (bvh.links.empty()) return -1;
  double best = t_max;
  bool found = false;
  std::vector<int32_t> stack = {0};
  while (!stack.empty()) {
    int32_t node = stack.back();
    stack.pop_back();
    if (!box_hit(&bvh.bounds[8 * node], o, d, t_min, best)) continue;
    int32_t a = bvh.links[2 * node], count = bvh.links[2 * node + 1];
    if (count > 0) {
      for (int32_t i = 0; i < count; ++i) {
        double t = triangle_ray_hit(&bvh.triangles[12 * (a + i)], o, d);
        if (t > t_min && t < best) {
          best = t;
          found = true;
        }
      }
    } else {
      stack.push_back(a);
      stack.push_back(node + 1);
    }
  }
  return found ? best : -1;
}

}  // namespace scatter
