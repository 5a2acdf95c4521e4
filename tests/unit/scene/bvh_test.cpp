#include "scene/bvh.hpp"

#include <gtest/gtest.h>

#include <random>

#include "scene/shapes.hpp"

namespace scatter {
namespace {

// Closest hit over all triangles, the slow way.
double brute_force(const Mesh& m, const Vec3& o, const Vec3& d) {
  double best = -1;
  for (size_t t = 0; t < m.indices.size(); t += 3) {
    Vec3 v0 = m.positions[m.indices[t]], e1 = m.positions[m.indices[t + 1]] - v0,
         e2 = m.positions[m.indices[t + 2]] - v0;
    Vec3 p = cross(d, e2);
    double det = dot(e1, p);
    if (std::abs(det) < 1e-20) continue;
    Vec3 s = o - v0;
    double u = dot(s, p) / det, v = dot(d, cross(s, e1)) / det;
    if (u < 0 || v < 0 || u + v > 1) continue;
    double t_hit = dot(e2, cross(s, e1)) / det;
    if (t_hit > 1e-9 && (best < 0 || t_hit < best)) best = t_hit;
  }
  return best;
}

TEST(Bvh, ClosestHitsMatchBruteForce) {
  Shape torus;
  torus.kind = Shape::Kind::Torus;
  torus.axis = normalize(Vec3{0.2, 1, 0.4});
  Mesh m = torus.tessellate(48);
  FlatBvh bvh = build_bvh(m);
  EXPECT_GT(bvh.node_count(), m.triangle_count() / 4);
  EXPECT_EQ(bvh.triangles.size(), 12 * m.triangle_count());  // every triangle in one leaf
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  int hits = 0;
  for (int i = 0; i < 2000; ++i) {
    Vec3 o{2 * u(rng), 2 * u(rng), 2 * u(rng)};
    Vec3 d = normalize(Vec3{0.8 * u(rng), 0.8 * u(rng), 0.8 * u(rng)} - o);  // towards the torus
    double expected = brute_force(m, o, d);
    double got = bvh_closest_hit(bvh, o, d, 1e-9, 1e30);
    if (expected < 0) {
      EXPECT_LT(got, 0);
    } else {
      EXPECT_NEAR(got, expected, 1e-5);  // the BVH holds float vertices
      ++hits;
    }
  }
  EXPECT_GT(hits, 300);
}

}  // namespace
}  // namespace scatter
