// The `psf` pipeline's light pyramid (Algorithm 1's BuildVolumePyramid): level 0 is the scattered
// source b * L0 at the voxel centres; each further level is the one below downsampled by two with
// the tent [1 3 3 1] / 8 per axis, then blurred by a separable Gaussian (zero outside the grid).
// The host chooses the Gaussians so that level k holds the source blurred by a known total width
// (pipelines/psf/psf_model.hpp). Volumes are float4 per voxel, x fastest.

__kernel void scatter_source(int count, __global const float* sigma_s, __global const float4* l0,
                             __global float4* out) {
  int i = get_global_id(0);
  if (i >= count) return;
  out[i] = (float4)(vload3(i, sigma_s) * l0[i].xyz, 0.0f);
}

// out has dims (ceil(nx/2), ceil(ny/2), ceil(nz/2)).
__kernel void downsample_tent(__global const float4* in, int nx, int ny, int nz, __global float4* out,
                              int ox, int oy, int oz) {
  int i = get_global_id(0), j = get_global_id(1), k = get_global_id(2);
  if (i >= ox || j >= oy || k >= oz) return;
  const float w[4] = {0.125f, 0.375f, 0.375f, 0.125f};
  float4 sum = (float4)(0.0f);
  for (int dk = 0; dk < 4; ++dk) {
    int z = 2 * k - 1 + dk;
    if (z < 0 || z >= nz) continue;
    for (int dj = 0; dj < 4; ++dj) {
      int y = 2 * j - 1 + dj;
      if (y < 0 || y >= ny) continue;
      for (int di = 0; di < 4; ++di) {
        int x = 2 * i - 1 + di;
        if (x < 0 || x >= nx) continue;
        sum += (w[di] * w[dj] * w[dk]) * in[(z * ny + y) * nx + x];
      }
    }
  }
  out[(k * oy + j) * ox + i] = sum;
}

// One axis (0 x, 1 y, 2 z) of a separable blur with a Gaussian per channel: taps[d] holds the
// channels' weights at distance d (taps[0] the centre), zero outside the grid.
__kernel void blur_axis(__global const float4* in, int nx, int ny, int nz, int axis,
                        __global const float4* taps, int radius, __global float4* out) {
  int i = get_global_id(0), j = get_global_id(1), k = get_global_id(2);
  if (i >= nx || j >= ny || k >= nz) return;
  int n = axis == 0 ? nx : (axis == 1 ? ny : nz);
  int at = axis == 0 ? i : (axis == 1 ? j : k);
  int stride = axis == 0 ? 1 : (axis == 1 ? nx : nx * ny);
  int base = (k * ny + j) * nx + i;
  float4 sum = taps[0] * in[base];
  for (int d = 1; d <= radius; ++d) {
    if (at - d >= 0) sum += taps[d] * in[base - d * stride];
    if (at + d < n) sum += taps[d] * in[base + d * stride];
  }
  out[base] = sum;
}
