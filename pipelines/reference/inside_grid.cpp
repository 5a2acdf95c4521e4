#include "pipelines/reference/inside_grid.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace scatter {

void restrict_to_mesh(VoxelGrid& grid) {
  const size_t n = grid.count();
  for (size_t v = 0; v < n; ++v) {
    float occ = grid.occupancy[v];
    if (occ <= 0) continue;
    for (int c = 0; c < 3; ++c) {
      grid.sigma_s[3 * v + c] /= occ;
      grid.sigma_a[3 * v + c] /= occ;
    }
  }
  // Empty voxels next to occupied ones: their neighbours' mean (read from a copy, one pass).
  const std::vector<float> ss = grid.sigma_s, sa = grid.sigma_a;
  for (int k = 0; k < grid.nz; ++k)
    for (int j = 0; j < grid.ny; ++j)
      for (int i = 0; i < grid.nx; ++i) {
        size_t v = grid.index(i, j, k);
        if (grid.occupancy[v] > 0) continue;
        double s[3] = {0, 0, 0}, a[3] = {0, 0, 0};
        int count = 0;
        for (int dk = -1; dk <= 1; ++dk)
          for (int dj = -1; dj <= 1; ++dj)
            for (int di = -1; di <= 1; ++di) {
              int x = i + di, y = j + dj, z = k + dk;
              if (x < 0 || y < 0 || z < 0 || x >= grid.nx || y >= grid.ny || z >= grid.nz) continue;
              size_t u = grid.index(x, y, z);
              if (grid.occupancy[u] <= 0) continue;
              for (int c = 0; c < 3; ++c) {
                s[c] += ss[3 * u + c];
                a[c] += sa[3 * u + c];
              }
              ++count;
            }
        if (count == 0) continue;
        for (int c = 0; c < 3; ++c) {
          grid.sigma_s[3 * v + c] = static_cast<float>(s[c] / count);
          grid.sigma_a[3 * v + c] = static_cast<float>(a[c] / count);
        }
      }
}

}  // namespace scatter

namespace scatter {

std::vector<uint8_t> interior_depth(const VoxelGrid& grid) {
  const int cap = 256;
  std::vector<int> d(grid.count());
  for (size_t v = 0; v < d.size(); ++v) d[v] = grid.occupancy[v] >= 1.0f ? cap : 0;
  chebyshev_distance(grid, d);
  std::vector<uint8_t> out(d.size());
  // Less one more: a sliver of surface the supersampling missed may sit in a voxel counted full.
  for (size_t v = 0; v < d.size(); ++v) out[v] = uint8_t(std::clamp(d[v] - 2, 0, 255));
  return out;
}

void chebyshev_distance(const VoxelGrid& grid, std::vector<int>& d) {
  // Two raster passes over the 26-neighbourhood give the exact Chebyshev distance.
  auto pass = [&](int sign) {
    int k0 = sign > 0 ? 0 : grid.nz - 1, j0 = sign > 0 ? 0 : grid.ny - 1,
        i0 = sign > 0 ? 0 : grid.nx - 1;
    for (int k = k0; k >= 0 && k < grid.nz; k += sign)
      for (int j = j0; j >= 0 && j < grid.ny; j += sign)
        for (int i = i0; i >= 0 && i < grid.nx; i += sign) {
          int& here = d[grid.index(i, j, k)];
          for (int dk = -1; dk <= 1; ++dk)
            for (int dj = -1; dj <= 1; ++dj)
              for (int di = -1; di <= 1; ++di) {
                // Only the neighbours this pass has already visited.
                int order = (dk * 3 + dj) * 3 + di;
                if (order * sign >= 0) continue;
                int x = i + di, y = j + dj, z = k + dk;
                if (x < 0 || y < 0 || z < 0 || x >= grid.nx || y >= grid.ny || z >= grid.nz) {
                  here = std::min(here, 1);  // past the grid: outside
                  continue;
                }
                here = std::min(here, d[grid.index(x, y, z)] + 1);
              }
        }
  };
  pass(1);
  pass(-1);
}

}  // namespace scatter

namespace scatter {
namespace {

// Whether a segment inside the mesh may cross voxel (i, j, k): the voxel or a neighbour holds
// part of the mesh's inside.
bool reachable(const VoxelGrid& grid, int i, int j, int k) {
  for (int dk = -1; dk <= 1; ++dk)
    for (int dj = -1; dj <= 1; ++dj)
      for (int di = -1; di <= 1; ++di) {
        int x = i + di, y = j + dj, z = k + dk;
        if (x < 0 || y < 0 || z < 0 || x >= grid.nx || y >= grid.ny || z >= grid.nz) continue;
        if (grid.occupancy[grid.index(x, y, z)] > 0) return true;
      }
  return false;
}

// Equal to float32's rounding: restrict_to_mesh's mean over a voxel's part inside (sigma times
// occupancy, over occupancy) is the medium's own sigma to within an ulp or two.
bool close(float a, float b) {
  return std::abs(a - b) <= 1e-6f * std::max(std::abs(a), std::abs(b));
}

}  // namespace

std::vector<int32_t> uniform_bricks(const VoxelGrid& grid, int brick, bool mesh_bounds) {
  const int bx = (grid.nx + brick - 1) / brick, by = (grid.ny + brick - 1) / brick,
            bz = (grid.nz + brick - 1) / brick;
  std::vector<int32_t> out(size_t(bx) * by * bz, -1);
  for (int b = 0; b < int(out.size()); ++b) {
    const int i0 = (b % bx) * brick, j0 = (b / bx % by) * brick, k0 = b / (bx * by) * brick;
    int64_t rep = -1;
    bool same = true;  // (and rep stays -1 where no voxel is reachable)
    for (int k = k0; same && k < std::min(k0 + brick, grid.nz); ++k)
      for (int j = j0; same && j < std::min(j0 + brick, grid.ny); ++j)
        for (int i = i0; same && i < std::min(i0 + brick, grid.nx); ++i) {
          if (mesh_bounds && !reachable(grid, i, j, k)) continue;
          size_t v = grid.index(i, j, k);
          if (rep < 0) {
            rep = int64_t(v);
            continue;
          }
          for (int c = 0; c < 3 && same; ++c)
            same = close(grid.sigma_s[3 * v + c], grid.sigma_s[3 * rep + c]) &&
                   close(grid.sigma_a[3 * v + c], grid.sigma_a[3 * rep + c]);
        }
    if (same) out[size_t(b)] = rep >= 0 ? int32_t(rep) : -2;
  }
  return out;
}

int32_t homogeneous_voxel(const VoxelGrid& grid, const std::vector<int32_t>& uniform) {
  int32_t rep = -1;
  for (int32_t u : uniform) {
    if (u == -2) continue;
    if (u < 0) return -1;
    if (rep < 0) {
      rep = u;
      continue;
    }
    for (int c = 0; c < 3; ++c)
      if (!close(grid.sigma_s[3 * size_t(u) + c], grid.sigma_s[3 * size_t(rep) + c]) ||
          !close(grid.sigma_a[3 * size_t(u) + c], grid.sigma_a[3 * size_t(rep) + c]))
        return -1;
  }
  return rep;
}

}  // namespace scatter
