#include "pipelines/reference/inside_grid.hpp"

#include <algorithm>
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
  std::vector<uint8_t> out(d.size());
  // Less one more: a sliver of surface the supersampling missed may sit in a voxel counted full.
  for (size_t v = 0; v < d.size(); ++v) out[v] = uint8_t(std::clamp(d[v] - 2, 0, 255));
  return out;
}

}  // namespace scatter
