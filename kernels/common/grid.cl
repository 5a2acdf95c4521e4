// Operations on voxel grids (x fastest, then y, then z; RGB coefficients interleaved).

// Majorant of the extinction per brick of b^3 voxels: the largest sigma_s + sigma_a of any
// channel over the brick and a one-voxel apron, so that it also bounds trilinear interpolation
// between voxel centres at the brick's faces. One work item per brick.
__kernel void brick_majorant(__global const float* sigma_s, __global const float* sigma_a,
                             int nx, int ny, int nz, int b, int bx, int by, int bz,
                             __global float* majorant) {
  int id = get_global_id(0);
  if (id >= bx * by * bz) return;
  int i0 = (id % bx) * b, j0 = ((id / bx) % by) * b, k0 = (id / (bx * by)) * b;
  float m = 0.0f;
  for (int k = max(k0 - 1, 0); k < min(k0 + b + 1, nz); ++k)
    for (int j = max(j0 - 1, 0); j < min(j0 + b + 1, ny); ++j)
      for (int i = max(i0 - 1, 0); i < min(i0 + b + 1, nx); ++i) {
        size_t v = 3 * (((size_t)k * ny + j) * nx + i);
        for (int c = 0; c < 3; ++c) m = fmax(m, sigma_s[v + c] + sigma_a[v + c]);
      }
  majorant[id] = m;
}
