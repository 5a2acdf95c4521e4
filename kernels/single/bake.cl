// The `single` pipeline's bake (papers/single-scattering-inhomogeneous.md, section 4), after
// kernels/common/ (Grid, DDA).
//
// sweep_slice: the direction-dependent optical depth of every voxel for a group of directions
// that share their major axis, one slice of voxels per launch. For a voxel x and direction w,
// tau(x, w) = tau(x + h w, w) + h (sigma(x) + sigma(x + h w)) / 2, where x + h w lies on the
// upstream slice (one voxel along the major axis) and is read bilinearly; outside the grid tau and
// sigma are zero. Each work item then adds exp(-tau) w dOmega to the first moment T(x) of its voxel
// (equation 4), so no direction's depths are kept.
//
// sample_depths: the exact optical depth (DDA through the voxels) of every channel from each
// sample along each direction to the grid's boundary, for the spherical-harmonic projection.

// Slice coordinates (u, v, k) to a voxel index; `axis` is the major axis (the slice normal).
int slice_voxel(int axis, int u, int v, int k, int nx, int ny) {
  int3 c = axis == 0 ? (int3)(k, u, v) : (axis == 1 ? (int3)(u, k, v) : (int3)(u, v, k));
  return (c.z * ny + c.y) * nx + c.x;
}

float slice_read(__global const float* s, int nu, int nv, int u, int v) {
  return (u < 0 || v < 0 || u >= nu || v >= nv) ? 0.0f : s[v * nu + u];
}

float bilinear(__global const float* s, int nu, int nv, float u, float v) {
  float fu = floor(u), fv = floor(v);
  int iu = (int)fu, iv = (int)fv;
  float a = u - fu, b = v - fv;
  return (1 - a) * (1 - b) * slice_read(s, nu, nv, iu, iv) + a * (1 - b) * slice_read(s, nu, nv, iu + 1, iv) +
         (1 - a) * b * slice_read(s, nu, nv, iu, iv + 1) + a * b * slice_read(s, nu, nv, iu + 1, iv + 1);
}

// sigma: mean extinction per voxel. dirs: per direction (du, dv, h, 0): the upstream point's
// offset within the slice in voxels and the step length in scene units; moments: w dOmega.
// tau_prev holds the upstream slice (upstream_k) per direction, tau_cur receives slice k.
__kernel void sweep_slice(__global const float* sigma, int nx, int ny, int nz, int axis, int k,
                          int upstream_k, __global const float4* dirs, __global const float4* moments,
                          int dir_count, __global const float* tau_prev, __global float* tau_cur,
                          __global float* moment) {
  int nu = axis == 0 ? ny : nx;
  int nv = axis == 2 ? ny : nz;
  int u = get_global_id(0), v = get_global_id(1);
  if (u >= nu || v >= nv) return;
  const int slice = nu * nv;
  const int n = axis == 0 ? nx : (axis == 1 ? ny : nz);
  const bool has_upstream = upstream_k >= 0 && upstream_k < n;
  int vox = slice_voxel(axis, u, v, k, nx, ny);
  float s_here = sigma[vox];
  float3 t = (float3)(0.0f);
  for (int d = 0; d < dir_count; ++d) {
    float4 dir = dirs[d];
    float tau = 0.5f * dir.z * s_here;
    if (has_upstream) {
      float pu = u + dir.x, pv = v + dir.y;
      float fu = floor(pu), fv = floor(pv);
      int iu = (int)fu, iv = (int)fv;
      float a = pu - fu, b = pv - fv;
      float s_up = 0.0f;
      for (int c = 0; c < 4; ++c) {
        int cu = iu + (c & 1), cv = iv + (c >> 1);
        if (cu < 0 || cv < 0 || cu >= nu || cv >= nv) continue;
        float w = ((c & 1) ? a : 1 - a) * ((c >> 1) ? b : 1 - b);
        s_up += w * sigma[slice_voxel(axis, cu, cv, upstream_k, nx, ny)];
      }
      tau += bilinear(tau_prev + d * slice, nu, nv, pu, pv) + 0.5f * dir.z * s_up;
    }
    tau_cur[d * slice + v * nu + u] = tau;
    t += exp(-tau) * moments[d].xyz;
  }
  moment[3 * vox] += t.x;
  moment[3 * vox + 1] += t.y;
  moment[3 * vox + 2] += t.z;
}

// out[(s * dir_count + d) * 3 + c]: optical depth of channel c from sample s along direction d.
__kernel void sample_depths(float3 origin, float voxel, int nx, int ny, int nz,
                            __global const float* sigma_t, __global const float* positions,
                            int sample_count, __global const float* dirs, int dir_count,
                            __global float* out) {
  int s = get_global_id(0), d = get_global_id(1);
  if (s >= sample_count || d >= dir_count) return;
  Grid g = make_grid(origin, voxel, nx, ny, nz, 1, 0, 0, 0);
  float3 o = (float3)(positions[3 * s], positions[3 * s + 1], positions[3 * s + 2]);
  float3 w = (float3)(dirs[3 * d], dirs[3 * d + 1], dirs[3 * d + 2]);
  float3 tau = (float3)(0.0f);
  float g0, g1;
  if (grid_interval(&g, o, w, &g0, &g1)) {
    Dda it;
    dda_init(&it, o, w, g.origin, g.voxel, (int3)(nx, ny, nz), g0, g1);
    float a, b;
    int3 c;
    while (dda_next(&it, &a, &b, &c)) {
      int v = 3 * voxel_index(&g, c.x, c.y, c.z);
      tau += (float3)(sigma_t[v], sigma_t[v + 1], sigma_t[v + 2]) * (b - a);
    }
  }
  size_t base = ((size_t)s * dir_count + d) * 3;
  out[base] = tau.x;
  out[base + 1] = tau.y;
  out[base + 2] = tau.z;
}
