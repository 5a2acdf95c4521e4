#include "pipelines/reference/inside_grid.hpp"

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
              if (x < 0 || y < 0 || z < 0 || x >= grid.nx || y >= grid.ny || z >= grid.nz)
                continue;
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
