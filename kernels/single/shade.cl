// The `single` pipeline's per-sample factor with exact transmittance (setting exact_tr 1), after
// kernels/reference/common.cl: the optical depth from each sample to the eye and to every light is
// summed through the voxels (DDA) each frame instead of read from the sample's spherical harmonics.
// The factor is the same as shaders/single/shade.comp's:
//   weight * sigma_s * T(to eye) * sum over lights of E * T(to light) * HG
// Samples outside the surface (the shell) measure their depths from `at`, their anchor inside.
__kernel void shade_exact(float3 origin, float voxel, int nx, int ny, int nz, __global const float* sigma_t,
                          __global const float* at, __global const float* weight,
                          __global const float* sigma_s, int count, __global const float* lights,
                          int light_count, float g_phase, float3 eye, __global float4* out) {
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
      sum += e * exp(-optical_depth(&grid, sigma_t, ch, b, wl, 0.0f, dist)) * hg_phase(dot(wl, -v), g_phase);
    }
    res[ch] = weight[i] * sigma_s[3 * i + ch] * view * sum;
  }
  out[i] = (float4)(res[0], res[1], res[2], 0.0f);
}
