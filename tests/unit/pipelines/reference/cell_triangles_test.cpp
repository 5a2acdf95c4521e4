#include "pipelines/reference/cell_triangles.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "../../test_util.hpp"
#include "pipelines/common/cl_library.hpp"
#include "pipelines/common/cl_scene.hpp"
#include "pipelines/reference/inside_grid.hpp"
#include "scene/scene.hpp"

namespace scatter {
namespace {

TEST(TriangleBoxOverlap, SeparatesOnlyWhatIsApart) {
  const Vec3 lo{0, 0, 0}, hi{1, 1, 1};
  // Inside, crossing a face, far away.
  EXPECT_TRUE(triangle_box_overlap({0.2, 0.2, 0.5}, {0.8, 0.2, 0.5}, {0.5, 0.8, 0.5}, lo, hi));
  EXPECT_TRUE(triangle_box_overlap({0.5, 0.5, 0.5}, {3, 0.5, 0.5}, {0.5, 3, 0.5}, lo, hi));
  EXPECT_FALSE(triangle_box_overlap({2, 2, 2}, {3, 2, 2}, {2, 3, 2}, lo, hi));
  // A large triangle through the box with no vertex in it.
  EXPECT_TRUE(triangle_box_overlap({-5, -5, 0.5}, {5, -5, 0.5}, {0, 5, 0.5}, lo, hi));
  // Its bounding box holds the box's corner (1, 1, 1), but the plane x + y + z = 3.2 passes it by.
  EXPECT_FALSE(triangle_box_overlap({3.2, 0, 0}, {0, 3.2, 0}, {0, 0, 3.2}, lo, hi));
  EXPECT_TRUE(triangle_box_overlap({2.9, 0, 0}, {0, 2.9, 0}, {0, 0, 2.9}, lo, hi));
  // Touching a face counts.
  EXPECT_TRUE(triangle_box_overlap({1, 0.2, 0.2}, {2, 0.2, 0.2}, {1, 0.8, 0.2}, lo, hi));
  // An edge passing the box's edge at (1, 1) by, x + y = 2.1 (an edge-cross-product axis
  // separates): the bounding boxes overlap; at x + y = 1.9 the triangle cuts the box.
  EXPECT_FALSE(triangle_box_overlap({2.3, -0.2, 0.5}, {-0.2, 2.3, 0.5}, {2.3, 2.3, 0.6}, lo, hi));
  EXPECT_TRUE(triangle_box_overlap({2.1, -0.2, 0.5}, {-0.2, 2.1, 0.5}, {2.3, 2.3, 0.6}, lo, hi));
}

// A shipped scene's grid at `voxels`, its BVH and the voxels' triangle lists.
struct Lists {
  VoxelGrid grid;
  FlatBvh bvh;
  CellTriangles cells;
};

Lists lists_for(const std::string& name, int voxels) {
  Scene s = load_scene(test::source_path("scenes/" + name + ".json"));
  Lists l;
  l.grid = voxelize(s, {.resolution = voxels});
  l.bvh = build_bvh(*s.mesh);
  l.cells = cell_triangles(l.grid, l.bvh);
  return l;
}

Vec3 vertex(const FlatBvh& bvh, size_t t, int k) {
  const float* p = bvh.triangles.data() + 12 * t + 4 * k;
  return {p[0], p[1], p[2]};
}

bool listed(const CellTriangles& cells, size_t v, int32_t t) {
  auto b = cells.triangles.begin() + cells.first[v],
       e = cells.triangles.begin() + cells.first[v + 1];
  return std::find(b, e, t) != e;
}

// Every voxel a triangle overlaps lists it: points spread over each triangle (its vertices,
// edges and inside) all lie in voxels that list it, and each voxel's list holds exactly the
// triangles that the separating-axis test finds overlapping its box grown by the padding.
TEST(CellTriangles, EveryVoxelListsTheTrianglesOverlappingIt) {
  for (const std::string name : {"sphere", "bunny"}) {
    SCOPED_TRACE(name);
    const auto [grid, bvh, cells] = lists_for(name, 24);
    const size_t count = bvh.triangles.size() / 12;
    ASSERT_EQ(cells.first.size(), grid.count() + 1);
    ASSERT_EQ(size_t(cells.first.back()), cells.triangles.size());
    const int steps = 6;
    for (size_t t = 0; t < count; t += name == "bunny" ? 7 : 1) {
      const Vec3 a = vertex(bvh, t, 0), b = vertex(bvh, t, 1), c = vertex(bvh, t, 2);
      for (int i = 0; i <= steps; ++i)
        for (int j = 0; i + j <= steps; ++j) {
          const Vec3 p = a + (b - a) * (double(i) / steps) + (c - a) * (double(j) / steps);
          const Vec3 q = (p - grid.origin) * (1 / grid.voxel);
          const int x = int(std::floor(q.x)), y = int(std::floor(q.y)), z = int(std::floor(q.z));
          ASSERT_TRUE(x >= 0 && y >= 0 && z >= 0 && x < grid.nx && y < grid.ny && z < grid.nz);
          ASSERT_TRUE(listed(cells, grid.index(x, y, z), int32_t(t))) << "triangle " << t;
        }
    }
    // The lists against a brute-force test of every triangle near a sample of voxels.
    const double pad = 1e-2 * grid.voxel;
    for (size_t v = 0; v < grid.count(); v += 13) {
      const int x = int(v % grid.nx), y = int(v / grid.nx % grid.ny),
                z = int(v / grid.nx / grid.ny);
      const Vec3 lo =
          grid.origin + Vec3{double(x), double(y), double(z)} * grid.voxel - Vec3{pad, pad, pad};
      const Vec3 hi = lo + Vec3{1, 1, 1} * (grid.voxel + 2 * pad);
      int expected = 0;
      for (size_t t = 0; t < count; ++t) {
        bool overlaps =
            triangle_box_overlap(vertex(bvh, t, 0), vertex(bvh, t, 1), vertex(bvh, t, 2), lo, hi);
        expected += overlaps;
        if (overlaps) ASSERT_TRUE(listed(cells, v, int32_t(t))) << "voxel " << v;
      }
      ASSERT_EQ(cells.first[v + 1] - cells.first[v], expected) << "voxel " << v;
    }
  }
}

// The lists are chosen where they were measured faster (docs/BENCHMARKS.md, ref22): the
// finely tessellated sphere, not the 12-triangle cube nor the bunny's long lists.
TEST(CellTriangles, ListsAreUsedOnTheFineSphereOnly) {
  Lists sphere = lists_for("sphere", 64), cube = lists_for("layers", 64),
        bunny = lists_for("bunny", 64);
  EXPECT_TRUE(uses_cell_lists(sphere.cells, sphere.bvh));
  EXPECT_FALSE(uses_cell_lists(cube.cells, cube.bvh));
  EXPECT_FALSE(uses_cell_lists(bunny.cells, bunny.bvh));
}

// The kernels' closest hits through the voxels' triangle lists are the BVH's: the same distance
// (the same triangle test, so equal up to float rounding where two triangles meet) and the same
// side of the surface, for rays from inside the medium (collision vertices, tmin 0), from
// points just past a crossing and from outside the grid, on a convex and a non-convex mesh.
TEST(CellTriangles, KernelHitsMatchTheBvh) {
  gpu::ClContext& cl = test::shared_gpu().cl();
  for (const std::string name : {"sphere", "bunny"}) {
    SCOPED_TRACE(name);
    const auto [grid, bvh, cells] = lists_for(name, 48);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(0, 1);
    std::vector<float> rays;
    auto random_dir = [&] {
      double z = 2 * u(rng) - 1, phi = 2 * M_PI * u(rng), r = std::sqrt(1 - z * z);
      return Vec3{r * std::cos(phi), r * std::sin(phi), z};
    };
    const Vec3 extent = Vec3{double(grid.nx), double(grid.ny), double(grid.nz)} * grid.voxel;
    for (int i = 0; i < 6000; ++i) {
      Vec3 d = random_dir(), o;
      float t0 = 0;
      if (i % 3 == 2) {  // from outside the grid, towards its centre
        Vec3 centre = grid.origin + extent * 0.5;
        o = centre - d * (2 * extent.x + 1) + random_dir() * (0.3 * extent.x);
        d = normalize(centre - o);
      } else {  // from a point inside the mesh (a voxel whose centre is inside)
        size_t v;
        do v = size_t(u(rng) * grid.count());
        while (!grid.inside[v]);
        const int x = int(v % grid.nx), y = int(v / grid.nx % grid.ny),
                  z = int(v / grid.nx / grid.ny);
        o = grid.origin + Vec3{x + u(rng), y + u(rng), z + u(rng)} * grid.voxel;
        if (i % 3 == 1) t0 = float(1e-3 * grid.voxel);
      }
      rays.insert(rays.end(), {float(o.x), float(o.y), float(o.z), t0, float(d.x), float(d.y),
                               float(d.z), 0.f});
    }
    const size_t n = rays.size() / 8;
    cl::Buffer ray_buf = upload(cl, rays), bounds = upload(cl, bvh.bounds),
               tris = upload(cl, bvh.triangles);
    auto ints = [&](const std::vector<int32_t>& v) {
      return cl::Buffer(cl.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                        v.size() * sizeof(int32_t), const_cast<int32_t*>(v.data()));
    };
    cl::Buffer links = ints(bvh.links), first = ints(cells.first), list = ints(cells.triangles);
    cl::Buffer skip(cl.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, cells.skip.size(),
                    const_cast<uint8_t*>(cells.skip.data()));
    cl::Kernel k(cl.program(with_cl_library(
                     {"kernels/reference/boundary.cl", "kernels/reference/mesh_hits.cl"})),
                 "mesh_hits");
    std::vector<std::vector<float>> hits(2, std::vector<float>(4 * n));
    for (int use_cells = 0; use_cells < 2; ++use_cells) {
      cl::Buffer out(cl.context(), CL_MEM_WRITE_ONLY, 4 * n * sizeof(float));
      cl_float3 origin = {{float(grid.origin.x), float(grid.origin.y), float(grid.origin.z)}};
      gpu::set_args(k, origin, float(grid.voxel), grid.nx, grid.ny, grid.nz, bounds, links, tris,
                    use_cells, first, list, skip, ray_buf, out);
      cl.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(n));
      cl.queue().enqueueReadBuffer(out, CL_TRUE, 0, 4 * n * sizeof(float), hits[use_cells].data());
    }
    int hit_count = 0;
    for (size_t i = 0; i < n; ++i) {
      const float* a = &hits[0][4 * i];
      const float* b = &hits[1][4 * i];
      ASSERT_EQ(a[0] < 0, b[0] < 0) << "ray " << i;
      if (a[0] < 0) continue;
      ++hit_count;
      ASSERT_NEAR(a[0], b[0], 1e-5f * std::max(1.0f, a[0])) << "ray " << i;
      const Vec3 d{rays[8 * i + 4], rays[8 * i + 5], rays[8 * i + 6]};
      // The same side: entering or leaving.
      ASSERT_EQ(dot(d, Vec3{a[1], a[2], a[3]}) > 0, dot(d, Vec3{b[1], b[2], b[3]}) > 0)
          << "ray " << i;
    }
    EXPECT_GT(hit_count, int(n) / 2);
  }
}

}  // namespace
}  // namespace scatter
