// Optical depths of given rays through the mesh-bounded voxel medium (optical_depth3_bounded,
// kernels/common/dda.cl): pipelines/common/grid_ops.hpp's bounded_optical_depths, which tests
// hold to closed forms. One work item per ray: origin, direction (unit) and length, 7 floats.
__kernel void bounded_depths(float3 origin, float voxel, int nx, int ny, int nz,
                             __global const float* sigma_t, __global const float* bound,
                             __global const float* rays, int count, __global float* out) {
  int i = get_global_id(0);
  if (i >= count) return;
  Grid grid = make_grid(origin, voxel, nx, ny, nz, 1, 0, 0, 0);
  float3 o = (float3)(rays[7 * i], rays[7 * i + 1], rays[7 * i + 2]);
  float3 d = (float3)(rays[7 * i + 3], rays[7 * i + 4], rays[7 * i + 5]);
  vstore3(optical_depth3_bounded(&grid, sigma_t, bound, o, d, 0.0f, rays[7 * i + 6]), i, out);
}
