#include "scene/voxelizer.hpp"

#include <cmath>
#include <exception>
#include <stdexcept>
#include <thread>

#include "scene/solid.hpp"

namespace scatter {
namespace {

enum Class : char { kOutside = 0, kMedium = 1, kBlocked = 2 };

// Runs body(j) for j in [0, n) on `threads` threads; the first exception is rethrown here.
template <class F>
void parallel_rows(int n, int threads, F body) {
  std::vector<std::thread> pool;
  std::vector<std::exception_ptr> errors(threads);
  for (int t = 0; t < threads; ++t)
    pool.emplace_back([&, t] {
      try {
        for (int j = t; j < n; j += threads) body(j);
      } catch (...) {
        errors[t] = std::current_exception();
      }
    });
  for (auto& th : pool) th.join();
  for (auto& e : errors)
    if (e) std::rethrow_exception(e);
}

struct VoxelSums {
  double medium = 0;   // fraction of the voxel in the medium
  double blocked = 0;  // fraction inside a blocker
  double density = 0;  // mean density over the medium part
};

}  // namespace

double VoxelGrid::volume() const {
  double s = 0;
  for (float o : occupancy) s += o;
  return s * voxel * voxel * voxel;
}

VoxelGrid voxelize(const Scene& scene, const VoxelizeOptions& options) {
  auto solid = make_solid(scene);
  const DensityField& field = *scene.medium.density;
  Aabb b = solid->bounds();
  Vec3 size = b.size();
  VoxelGrid g;
  g.voxel = std::max({size.x, size.y, size.z}) / options.resolution;
  if (!(g.voxel > 0) || !std::isfinite(g.voxel) || options.resolution < 1 ||
      options.resolution > 4096 || options.margin < 0 || options.margin > 64)
    throw std::invalid_argument(
        "cannot voxelize: the solid has no extent or the resolution is invalid");
  g.nx = static_cast<int>(std::ceil(size.x / g.voxel)) + 2 * options.margin;
  g.ny = static_cast<int>(std::ceil(size.y / g.voxel)) + 2 * options.margin;
  g.nz = static_cast<int>(std::ceil(size.z / g.voxel)) + 2 * options.margin;
  g.origin = b.center() - Vec3{double(g.nx), double(g.ny), double(g.nz)} * (g.voxel / 2);
  const size_t n = g.count();
  g.sigma_s.assign(3 * n, 0.f);
  g.sigma_a.assign(3 * n, 0.f);
  g.occupancy.assign(n, 0.f);
  g.inside.assign(n, 0);
  int threads =
      options.threads > 0 ? options.threads : std::max(1u, std::thread::hardware_concurrency());

  // Pass 1: classify every voxel centre, one column per (i, j).
  std::vector<char> cls(n, kOutside);
  parallel_rows(g.ny, threads, [&](int j) {
    std::vector<double> zs(g.nz);
    std::vector<char> in;
    for (int k = 0; k < g.nz; ++k) zs[k] = g.center(0, 0, k).z;
    for (int i = 0; i < g.nx; ++i) {
      Vec3 c = g.center(i, j, 0);
      solid->classify_column(c.x, c.y, zs, in);
      for (int k = 0; k < g.nz; ++k)
        if (in[k]) cls[g.index(i, j, k)] = field.blocked(g.center(i, j, k)) ? kBlocked : kMedium;
    }
  });

  // A voxel whose 26 neighbours all share its class is taken as uniform; others are supersampled.
  auto boundary = [&](int i, int j, int k) {
    char c = cls[g.index(i, j, k)];
    for (int dk = -1; dk <= 1; ++dk)
      for (int dj = -1; dj <= 1; ++dj)
        for (int di = -1; di <= 1; ++di) {
          int a = i + di, bb = j + dj, cc = k + dk;
          if (a < 0 || bb < 0 || cc < 0 || a >= g.nx || bb >= g.ny || cc >= g.nz) continue;
          if (cls[g.index(a, bb, cc)] != c) return true;
        }
    return false;
  };

  const int ss = std::max(1, options.supersample);
  const Vec3 sigma_s = scene.medium.sigma_s, sigma_a = scene.medium.sigma_a;
  const double blocker_a = field.blocker_sigma_a();
  parallel_rows(g.ny, threads, [&](int j) {
    std::vector<double> zs;
    std::vector<char> in;
    std::vector<VoxelSums> sums(g.nz);
    std::vector<char> is_boundary(g.nz);
    for (int i = 0; i < g.nx; ++i) {
      bool any = false;
      for (int k = 0; k < g.nz; ++k) {
        is_boundary[k] = boundary(i, j, k);
        any = any || is_boundary[k];
        sums[k] = {};
        char c = cls[g.index(i, j, k)];
        if (!is_boundary[k] && c != kOutside) {
          sums[k].medium = c == kMedium;
          sums[k].blocked = c == kBlocked;
          sums[k].density = c == kMedium ? field.density(g.center(i, j, k)) : 0;
        }
      }
      if (any) {
        // Sub-columns through the voxel column; each is intersected once for all its z samples.
        zs.clear();
        for (int k = 0; k < g.nz; ++k)
          if (is_boundary[k])
            for (int s = 0; s < ss; ++s) zs.push_back(g.origin.z + (k + (s + 0.5) / ss) * g.voxel);
        for (int sy = 0; sy < ss; ++sy)
          for (int sx = 0; sx < ss; ++sx) {
            double x = g.origin.x + (i + (sx + 0.5) / ss) * g.voxel;
            double y = g.origin.y + (j + (sy + 0.5) / ss) * g.voxel;
            solid->classify_column(x, y, zs, in);
            size_t q = 0;
            for (int k = 0; k < g.nz; ++k) {
              if (!is_boundary[k]) continue;
              for (int s = 0; s < ss; ++s, ++q) {
                if (!in[q]) continue;
                Vec3 p{x, y, zs[q]};
                if (field.blocked(p)) {
                  sums[k].blocked += 1;
                } else {
                  sums[k].medium += 1;
                  sums[k].density += field.density(p);
                }
              }
            }
          }
        const double per = 1.0 / (ss * ss * ss);
        for (int k = 0; k < g.nz; ++k)
          if (is_boundary[k]) {
            if (sums[k].medium > 0) sums[k].density /= sums[k].medium;
            sums[k].medium *= per;
            sums[k].blocked *= per;
          }
      }
      for (int k = 0; k < g.nz; ++k) {
        size_t v = g.index(i, j, k);
        const VoxelSums& s = sums[k];
        g.occupancy[v] = static_cast<float>(s.medium + s.blocked);
        g.inside[v] = cls[v] != kOutside;
        double dm = s.density * s.medium;
        for (int c = 0; c < 3; ++c) {
          g.sigma_s[3 * v + c] = static_cast<float>(sigma_s[c] * dm);
          g.sigma_a[3 * v + c] = static_cast<float>(sigma_a[c] * dm + blocker_a * s.blocked);
        }
      }
    }
  });
  return g;
}

}  // namespace scatter
