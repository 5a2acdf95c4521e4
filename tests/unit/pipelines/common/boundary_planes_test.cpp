#include "pipelines/common/boundary_planes.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "../../test_util.hpp"
#include "pipelines/common/grid_ops.hpp"
#include "scene/scene.hpp"

namespace scatter {
namespace {

// The unit sphere of extinction 1 (per unit medium) on a coarse grid.
VoxelGrid unit_sphere_grid(int voxels) {
  nlohmann::json j = test::minimal_scene();
  j["medium"] = {{"sigma_s", {0.5, 0.5, 0.5}}, {"sigma_a", {0.5, 0.5, 0.5}}};
  j["voxels"] = voxels;
  return voxelize(parse_scene(j, "."), {.resolution = voxels, .margin = 1});
}

// Distance from p (inside) along the unit direction d to the unit sphere.
double sphere_exit(const Vec3& p, const Vec3& d) {
  double b = dot(p, d), c = dot(p, p) - 1;
  return -b + std::sqrt(b * b - c);
}

Vec3 random_direction(std::mt19937& rng) {
  std::normal_distribution<double> n;
  Vec3 d{n(rng), n(rng), n(rng)};
  return d / std::sqrt(dot(d, d));
}

// Each boundary voxel's plane stands for the sphere's surface there: its normal is the radial
// direction and it passes where the surface does, within a fraction of a voxel.
TEST(BoundaryPlanes, FollowTheSurface) {
  VoxelGrid g = unit_sphere_grid(16);
  BoundedExtinction b = bounded_extinction(g);
  ASSERT_GT(b.planes, 100);
  double worst_angle = 0, worst_offset = 0;
  int boundary = 0;
  for (int k = 0; k < g.nz; ++k)
    for (int j = 0; j < g.ny; ++j)
      for (int i = 0; i < g.nx; ++i) {
        const size_t v = g.index(i, j, k);
        const float* p = &b.plane[4 * v];
        const bool has = p[0] != 0 || p[1] != 0 || p[2] != 0;
        const float occ = g.occupancy[v];
        EXPECT_EQ(has, occ > 0 && occ < 1) << i << " " << j << " " << k;
        if (!has) {
          EXPECT_FLOAT_EQ(b.sigma_t[3 * v], g.sigma_s[3 * v] + g.sigma_a[3 * v]);
          continue;
        }
        ++boundary;
        const Vec3 c = g.center(i, j, k), n{p[0], p[1], p[2]};
        EXPECT_NEAR(dot(n, n), 1, 1e-5);
        worst_angle =
            std::max(worst_angle, std::acos(std::min(1.0, dot(n, c) / std::sqrt(dot(c, c)))));
        // The sphere's surface along the normal through the centre, against the plane's.
        worst_offset =
            std::max(worst_offset, std::abs((1 - std::sqrt(dot(c, c))) - p[3]) / g.voxel);
        EXPECT_FLOAT_EQ(b.sigma_t[3 * v], (g.sigma_s[3 * v] + g.sigma_a[3 * v]) / occ);
      }
  EXPECT_EQ(boundary, b.planes);
  std::printf("worst angle %.2f deg, worst offset %.3f voxel over %d voxels\n",
              worst_angle * 180 / M_PI, worst_offset, boundary);
  EXPECT_LT(worst_angle * 180 / M_PI, 15.0);
  EXPECT_LT(worst_offset, 0.15);
}

// A box whose faces sit inside voxels (axis-aligned normals, where a lattice quantile would be
// a staircase): each face voxel's plane is the face, its side holding the voxel's occupancy.
TEST(BoundaryPlanes, AxisAlignedFacesAreExact) {
  nlohmann::json j = test::minimal_scene();
  j["mesh"] = {{"shape", "box"}, {"size", {1.9, 1.3, 1.7}}};
  j["voxels"] = 16;
  VoxelGrid g = voxelize(parse_scene(j, "."), {.resolution = 16, .margin = 1});
  BoundedExtinction b = bounded_extinction(g);
  const Vec3 half{0.95, 0.65, 0.85};
  int faces = 0;
  for (int k = 0; k < g.nz; ++k)
    for (int jj = 0; jj < g.ny; ++jj)
      for (int i = 0; i < g.nx; ++i) {
        const size_t v = g.index(i, jj, k);
        const float* p = &b.plane[4 * v];
        if (p[0] == 0 && p[1] == 0 && p[2] == 0) continue;
        const Vec3 n{p[0], p[1], p[2]}, c = g.center(i, jj, k);
        // Face voxels whose stencil sees that face only (1.5 voxels from the others): the normal
        // is one axis.
        int axis = -1, count = 0;
        bool near_other = false;
        for (int a = 0; a < 3; ++a) {
          const double gap = half[a] - std::abs(c[a]);
          if (std::abs(gap) < 0.5 * g.voxel) {
            axis = a;
            ++count;
          } else if (gap < 1.5 * g.voxel) {
            near_other = true;
          }
        }
        if (count != 1 || near_other) continue;
        ++faces;
        EXPECT_NEAR(std::abs(n[axis]), 1, 1e-6) << i << " " << jj << " " << k;
        // The plane holds the voxel's occupancy (the voxelizer's, supersampled: the face itself
        // to a quarter voxel) on its side, at (occ - 1/2) voxels from the centre.
        EXPECT_NEAR(p[3], (g.occupancy[v] - 0.5) * g.voxel, 1e-3 * g.voxel)
            << i << " " << jj << " " << k;
        EXPECT_NEAR(p[3], half[axis] - std::abs(c[axis]), 0.25 * g.voxel);
      }
  EXPECT_GT(faces, 100);
}

// Optical depths from inside the sphere to its surface: with the planes, within a few percent
// of a mean free path for a dense medium; the voxels' means alone fall short along rays that
// leave through a boundary voxel's sliver.
TEST(BoundaryPlanes, OpticalDepthsToTheSurface) {
  VoxelGrid g = unit_sphere_grid(16);
  BoundedExtinction bounded = bounded_extinction(g);
  BoundedExtinction means = bounded;
  for (size_t v = 0; v < g.count(); ++v)
    for (int c = 0; c < 3; ++c)
      means.sigma_t[3 * v + c] = g.sigma_s[3 * v + c] + g.sigma_a[3 * v + c];
  std::fill(means.plane.begin(), means.plane.end(), 0.f);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<float> rays;
  std::vector<double> exact;
  for (int r = 0; r < 4000; ++r) {
    // Points a voxel or less under the surface, every direction.
    Vec3 p = random_direction(rng) * (1 - u(rng) * g.voxel);
    Vec3 d = random_direction(rng);
    rays.insert(rays.end(),
                {float(p.x), float(p.y), float(p.z), float(d.x), float(d.y), float(d.z), 10.f});
    exact.push_back(sphere_exit(p, d));
  }
  auto& cl = test::shared_gpu().cl();
  std::vector<float> with = bounded_optical_depths(cl, g, bounded, rays);
  std::vector<float> without = bounded_optical_depths(cl, g, means, rays);
  double err_with = 0, err_without = 0, worst_with = 0;
  for (size_t r = 0; r < exact.size(); ++r) {
    // Each channel's extinction is 1: the depth is the chord, in voxels.
    err_with += std::abs(with[3 * r] - exact[r]) / g.voxel;
    err_without += std::abs(without[3 * r] - exact[r]) / g.voxel;
    worst_with = std::max(worst_with, std::abs(with[3 * r] - exact[r]) / g.voxel);
    EXPECT_EQ(with[3 * r], with[3 * r + 2]);
  }
  err_with /= exact.size();
  err_without /= exact.size();
  std::printf("mean |error| %.4f voxel with the planes, %.4f without; worst %.3f\n", err_with,
              err_without, worst_with);
  // Measured: 0.036 with, 0.23 without, the worst 0.76 voxel (a ray leaving tangentially, along
  // the curved surface the planes cut as facets).
  EXPECT_LT(err_with, 0.06);
  EXPECT_LT(err_with, err_without / 4);
  EXPECT_LT(worst_with, 1.0);
}

}  // namespace
}  // namespace scatter
