// The `psf` pipeline's light volume (Algorithm 1's ComputeLightAttenuationVolume), after
// kernels/common/: per voxel centre, the light's unscattered radiance there and what
// the path towards the light holds, all through the voxels exactly (DDA):
//   l0[i]   = (E * exp(-tau), 0)      E: the light's irradiance (1/r^2, spot cone); RGB
//   path[i] = (l2 (RGB), s2)          l2 = int b ds (scattering events), s2 = length inside the medium
//   tau[i]  = (tau2 (RGB), 0)         tau2 = int c ds
__kernel void light_volume(float3 origin, float voxel, int nx, int ny, int nz,
                           __global const float* sigma_s, __global const float* sigma_t,
                           __global const float* lights, int light, __global float4* l0,
                           __global float4* path, __global float4* tau) {
  int i = get_global_id(0), j = get_global_id(1), k = get_global_id(2);
  if (i >= nx || j >= ny || k >= nz) return;
  Grid g = make_grid(origin, voxel, nx, ny, nz, 1, 0, 0, 0);
  int v = voxel_index(&g, i, j, k);
  float3 x = origin + voxel * ((float3)(i, j, k) + 0.5f);
  Light L = load_light(lights, light);
  float3 wl;
  float dist;
  float3 e;
  e.x = light_irradiance(L, x, 0, &wl, &dist);
  e.y = light_irradiance(L, x, 1, &wl, &dist);
  e.z = light_irradiance(L, x, 2, &wl, &dist);
  float3 t = (float3)(0.0f), l = (float3)(0.0f);
  float s = 0.0f;
  float g0, g1;
  if (grid_interval(&g, x, wl, &g0, &g1)) {
    g1 = fmin(g1, dist);
    if (g1 > g0) {
      Dda d;
      dda_init(&d, x, wl, origin, voxel, (int3)(nx, ny, nz), g0, g1);
      float a, b;
      int3 c;
      while (dda_next(&d, &a, &b, &c)) {
        int u = 3 * voxel_index(&g, c.x, c.y, c.z);
        float3 st = vload3(0, sigma_t + u);
        if (st.x <= 0.0f && st.y <= 0.0f && st.z <= 0.0f) continue;
        t += st * (b - a);
        l += vload3(0, sigma_s + u) * (b - a);
        s += b - a;
      }
    }
  }
  l0[v] = (float4)(e * exp(-t), 0.0f);
  path[v] = (float4)(l, s);
  tau[v] = (float4)(t, 0.0f);
}
