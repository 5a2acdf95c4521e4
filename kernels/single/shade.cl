// The `single` pipeline's per-sample factor with exact transmittance (setting exact_tr 1), after
// kernels/reference/common.cl: optical depths are summed through the voxels (DDA) instead of read
// from the samples' spherical harmonics. The factor is the same as shaders/single/shade.comp's:
//   weight * sigma_s * T(to eye) * sum over lights of E * T(to light) * HG
// T(to light) depends only on the light's position (or direction), so light_transmittance runs
// for a light when it appears or moves; shade_exact runs every frame and sums the eye's DDA only.
// Samples outside the surface (the shell) measure from `at`, their anchor inside.

// out[3 i + c]: transmittance of channel c from sample i to light `light`.
__kernel void light_transmittance(float3 origin, float voxel, int nx, int ny, int nz,
                                  __global const float* sigma_t, __global const float* at, int count,
                                  __global const float* lights, int light, __global float* out) {
  int i = get_global_id(0);
  if (i >= count) return;
  Grid grid = make_grid(origin, voxel, nx, ny, nz, 1, 0, 0, 0);
  float3 b = vload3(i, at);
  for (int ch = 0; ch < 3; ++ch) {
    float3 wl;
    float dist;
    light_irradiance(load_light(lights, light), b, ch, &wl, &dist);
    out[3 * i + ch] = exp(-optical_depth(&grid, sigma_t, ch, b, wl, 0.0f, dist));
  }
}

// light_tr: light_count blocks of 3 * count floats from light_transmittance.
__kernel void shade_exact(float3 origin, float voxel, int nx, int ny, int nz, __global const float* sigma_t,
                          __global const float* at, __global const float* weight,
                          __global const float* sigma_s, int count, __global const float* lights,
                          int light_count, __global const float* light_tr, float g_phase, float3 eye,
                          __global float4* out) {
  int i = get_global_id(0);
  if (i >= count) return;
  Grid grid = make_grid(origin, voxel, nx, ny, nz, 1, 0, 0, 0);
  float3 b = vload3(i, at);
  float3 to_eye = eye - b;
  float de = length(to_eye);
  float3 v = to_eye / de;
  float res[3];
  for (int ch = 0; ch < 3; ++ch) {
    float view = exp(-optical_depth(&grid, sigma_t, ch, b, v, 0.0f, de));
    float sum = 0.0f;
    for (int l = 0; l < light_count; ++l) {
      float3 wl;
      float dist;
      float e = light_irradiance(load_light(lights, l), b, ch, &wl, &dist);
      if (e <= 0.0f) continue;
      sum += e * light_tr[((size_t)l * count + i) * 3 + ch] * hg_phase(dot(wl, -v), g_phase);
    }
    res[ch] = weight[i] * sigma_s[3 * i + ch] * view * sum;
  }
  out[i] = (float4)(res[0], res[1], res[2], 0.0f);
}
