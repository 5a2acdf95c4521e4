// The escape correction's exact part (pipelines/lbl/escape): per voxel, the chance that light
// emitted isotropically at its centre leaves the grid without another interaction (its own
// voxel's depth weighted: see below), the mean of
// exp(-tau) over `count` directions (tau through the delta-Eddington scaled sigma_t', RGB; exact
// voxel crossings, a ray stopped once all channels pass tau 6). Voxels that do not scatter get 1.
__kernel void escape_exact(float3 origin, float voxel, int nx, int ny, int nz,
                           __global const float* sigma_t, __global const float* sigma_s,
                           __global const float* dirs, int count, __global float* out) {
  int3 c = (int3)(get_global_id(0), get_global_id(1), get_global_id(2));
  if (c.x >= nx || c.y >= ny || c.z >= nz) return;
  Grid g = make_grid(origin, voxel, nx, ny, nz, 1, 0, 0, 0);
  int v = 3 * voxel_index(&g, c.x, c.y, c.z);
  if (!(sigma_s[v] > 0.0f || sigma_s[v + 1] > 0.0f || sigma_s[v + 2] > 0.0f)) {
    out[v] = out[v + 1] = out[v + 2] = 1.0f;
    return;
  }
  float3 o = origin + voxel * (convert_float3(c) + 0.5f);
  float3 sum = (float3)(0.0f);
  for (int k = 0; k < count; ++k) {
    float3 d = (float3)(dirs[3 * k], dirs[3 * k + 1], dirs[3 * k + 2]);
    float t0, t1;
    float3 tau = (float3)(0.0f);
    if (grid_interval(&g, o, d, &t0, &t1)) {
      Dda s;
      dda_init(&s, o, d, g.origin, g.voxel, (int3)(nx, ny, nz), t0, t1);
      float a, b;
      int3 q;
      while (dda_next(&s, &a, &b, &q) && fmin(tau.x, fmin(tau.y, tau.z)) < 6.0f) {
        int w = 3 * voxel_index(&g, q.x, q.y, q.z);
        float3 st = (float3)(sigma_t[w], sigma_t[w + 1], sigma_t[w + 2]);
        // The lattice sends a node's emission to its neighbours whole: its own voxel's depth
        // counts times exp(-sigma_t' dx), all of it when the voxel is thin, none when it is
        // dense (whose own depth would make P far below the lattice's, and m amplify).
        if (q.x == c.x && q.y == c.y && q.z == c.z) st *= exp(-st * voxel);
        tau += (b - a) * st;
      }
    }
    sum += exp(-tau);
  }
  sum /= (float)count;
  out[v] = sum.x;
  out[v + 1] = sum.y;
  out[v + 2] = sum.z;
}
